// SPDX-License-Identifier: BSD-3-Clause
// Static intersection resolution (Hajkova & Kohout sec. 3.1; docs/DESIGN.md
// section 5), once after a deformation, on the full meshes: the
// vertices of deformable meshes (muscles) that lie inside an obstacle (a bone,
// or another of the deformable meshes) go out to the obstacle's surface.
#pragma once

#include "Common/MeshTypes.h"
#include "Geometry/TriangleTree.h"

#include <functional>
#include <string>
#include <vector>

namespace md
{
/// A fixed obstacle of the static resolution: only the deformable meshes move.
struct FixedObstacle
{
  std::string name;
  const TriangleTree* tree = nullptr;
};

struct Obstacle;

/// Views of the trees of `obstacles` (BuildObstacles), which must outlive them.
std::vector<FixedObstacle> FixedObstacles(const std::vector<Obstacle>& obstacles);

/// overlap[m][o][i] != 0: point i of deformable mesh m lies inside obstacle o,
/// where o counts the fixed obstacles first, then the deformable meshes (a
/// mesh's own entry is empty). Used for the overlap a rest pose already has.
using OverlapMasks = std::vector<std::vector<std::vector<char>>>;

/// Whether `masks` (may be null) marks point i of mesh m as inside obstacle o.
bool InOverlap(const OverlapMasks* masks, size_t m, size_t o, Eigen::Index i);

/// Which points of each mesh (those its triangles use) lie inside each
/// obstacle (see OverlapMasks), from trees of the meshes as they are.
OverlapMasks FindOverlaps(const std::vector<TriangleMesh>& meshes, const std::vector<FixedObstacle>& fixed);

/// "" unless most points of `mesh` (named `name`, mesh m of `masks`) lie inside one fixed
/// obstacle or on its surface (within 1e-6 of the mesh's size) in the rest pose: a muscle given
/// as a bone too, or scanned inside one, which the method cannot tell apart from it (whether a
/// point on the bone's surface is inside is decided by rounding). Otherwise a message naming both.
std::string MostlyInAnObstacle(const TriangleMesh& mesh, const std::string& name, size_t m,
  const std::vector<FixedObstacle>& fixed, const OverlapMasks& masks);

struct Penetration
{
  std::int64_t count = 0;      ///< points inside an obstacle
  double maxDepth = 0;         ///< the largest distance of one of them to that obstacle's surface
  std::int64_t fixedCount = 0; ///< of them, inside a fixed obstacle (a bone)
  double fixedMaxDepth = 0;
};

/// New penetration of each mesh: its points inside an obstacle that are not
/// marked in `existing` (the rest pose's overlap; none when null). A point
/// in a bone and a muscle counts with the bone.
std::vector<Penetration> MeasureNewPenetration(
  const std::vector<TriangleMesh>& meshes, const std::vector<FixedObstacle>& fixed, const OverlapMasks* existing);

struct StaticResolveParameters
{
  /// Share of the correction a deformable mesh takes when its obstacle is
  /// another deformable mesh (which takes its own share from its side): 0.6
  /// in the original, so that neither is pushed all the way.
  double deformableShare = 0.6;
  /// The print's rim, as a multiple of each group's largest move: the points
  /// within this distance of the group (along the mesh's edges) move too, and
  /// the moves of the group and its rim form a smooth field in which every
  /// penetrating point still goes at least its way out; so the print is a
  /// smooth dent, as deep as the deepest point needs, fading to nothing over
  /// the rim, instead of the obstacle's outline cut into the mesh. 0: the
  /// paper's rule, each penetrating point moves to its own target, no other.
  double falloff = 3.0;
};

struct StaticResolveReport
{
  std::int64_t penetratingPoints = 0; ///< new penetration found (points moved)
  int groups = 0;                     ///< edge-connected groups of them
  double maxDepth = 0;                ///< deepest point found, distance to the surface
  double maxShift = 0;                ///< largest move applied (of a penetrating point, or spread)
};

struct StaticResolveResult
{
  std::vector<Points> points; ///< each mesh resolved
  std::vector<Points> shift;  ///< each mesh's move, per point
  std::vector<StaticResolveReport> reports;
  /// Each mesh's new penetration at the points given, before the moves: what
  /// MeasureNewPenetration of the meshes given finds.
  std::vector<Penetration> found;
};

/// Moves the points of every mesh that lie inside an obstacle (and are not
/// marked in `existing`) out to its surface. Each point goes with the
/// obstacle it is deepest in, a fixed one (a bone) before a mesh; the points
/// with the same obstacle form edge-connected groups, and a group moves along
/// one direction, the mean of its points' ways to their nearest surface
/// points: each point's way out is to where that direction leaves the
/// obstacle (to its nearest surface point when that exit is more than twice
/// as far: a thin part of the obstacle). With `falloff` the moves are then
/// smoothed over the group and its rim (see StaticResolveParameters), each
/// penetrating point still going at least its way out. No move enters a
/// fixed obstacle. All meshes are resolved against the obstacles as they are
/// on entry (the result does not depend on the meshes' order). `outsideFixed`
/// (optional; per mesh, point * fixed.size() + obstacle): points known to be
/// outside a fixed obstacle, which are not tested against it (a settle's proof,
/// ProvenOutsideBones).
StaticResolveResult ResolveStaticIntersections(const std::vector<TriangleMesh>& meshes,
  const std::vector<FixedObstacle>& fixed, const OverlapMasks* existing, const StaticResolveParameters& parameters,
  const std::vector<std::vector<char>>* outsideFixed = nullptr);

/// The static resolution as a step of its own (the IntersectionResolve filter), and what it left.
struct StaticStep
{
  StaticResolveResult resolved;
  std::vector<Penetration> left;           ///< each mesh's new penetration after the moves
  std::vector<double> volumeChangePercent; ///< against the rest pose, or the meshes given without one
};

/// Resolves `meshes` against the obstacles (`obstacleNames`, `obstacles`, fixed) and one another.
/// With `meshesRest` (the same meshes in the rest pose, the same points) the overlap the rest pose
/// has is left alone: found against `restObstacles` (paired with the obstacles, the same points),
/// or against the obstacles themselves when that is empty. `progress` from 0 to 1.
StaticStep ResolveStatically(const std::vector<TriangleMesh>& meshes, const std::vector<TriangleMesh>* meshesRest,
  const std::vector<std::string>& obstacleNames, const std::vector<TriangleMesh>& obstacles,
  const std::vector<std::string>& restObstacleNames, const std::vector<TriangleMesh>& restObstacles,
  const StaticResolveParameters& parameters, const std::function<void(double)>& progress = {});

/// Gives the meshes back their target volumes after a static resolution
/// (which dents them where it pushes): the surface moves out along its unit
/// normals by one common distance (a few Newton steps on it), which tapers to
/// nothing over three rings towards the `held` points (held[m][i] != 0; they
/// stay). Spread over the whole surface the move is small and smooth; a move
/// that would enter an obstacle or another mesh stops at its surface, and
/// that point moves no further. Returns the volume change left, in percent of
/// each target.
std::vector<double> RestoreVolumes(std::vector<TriangleMesh>& meshes, const std::vector<double>& targetVolumes,
  const std::vector<FixedObstacle>& fixed, const std::vector<std::vector<char>>& held);
}
