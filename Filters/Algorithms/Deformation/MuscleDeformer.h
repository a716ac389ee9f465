// SPDX-License-Identifier: BSD-3-Clause
// One rest-pose -> current-pose pass of the muscle deformation (Kellnhofer &
// Kohout, after Huang et al. 2006; docs/DESIGN.md section 4):
// least squares on the hull points, shape rows (cotangent Laplacian with
// rotated Laplacian coordinates) and action-line rows, the volume held by
// corrected Gauss-Newton steps, the full mesh following by mean value
// coordinates, and vertices kept out of obstacles at every fine iteration.
#pragma once

#include "Common/MeshTypes.h"
#include "Geometry/MeanValueCoordinates.h"
#include "Geometry/TriangleTree.h"

#include <functional>
#include <memory>
#include <string>
#include <vector>

namespace md
{
/// A matched action line (ActionLineMatching): the same number of points in
/// both poses, point k of `rest` moving to point k of `current`. The deformation takes the line
/// piece by piece from one of its own points (`knots`) to the next (LineSpan), so that points put
/// between them (a path kept over a bone) only say where the piece runs: each piece pulls and
/// turns the muscle as one segment of the line does.
struct MatchedLine
{
  Points rest;
  Points current;
  Knots knots;
};

struct DeformationParameters
{
  int maximumIterations = 200;       ///< both phases together
  int maximumCoarseIterations = 100; ///< of them, at most this many on the hull alone
  /// Converged when no hull coordinate moves more than this in an iteration
  /// (data units; 0.01 mm in the original).
  double convergenceTolerance = 0.01;
  /// Gauss-Newton step length alpha in (0, 1]. The original damped with 0.1
  /// falling to 0.025, which needs about 10x more iterations for the same
  /// result: the energy is quadratic apart from the volume, and the corrected
  /// step (VolumeConstrainedSolver) converges at full length.
  double stepLength = 1.0;
  bool preserveVolume = true;
  bool dynamicIntersections = true;
  int samplesPerSegment = 10; ///< action-line rows per segment of each matched line
  /// Weight of one row per hull point that pulls it to where the motion of
  /// its nearest action-line segment takes it (the Laplacian rows weigh 1 a
  /// point). Without it a hull point that the Laplacian and the action-line
  /// rows hardly fix (a near-null mode of their normal matrix, on the LHDL
  /// hip one of eigenvalue 3e-8 of the largest, half of it on one point)
  /// takes the least-squares step of that mode: moves of metres that tore
  /// muscles apart. 0: the paper's system.
  double followWeight = 0.01;
  /// Bones push the muscle (beyond the paper, whose bones only stop points
  /// that move into them): after the coarse phase, each point of the full
  /// mesh that the bones' motion put inside a bone gets a row (of this weight
  /// against the action-line rows' 1) pulling it to the bone's nearest
  /// surface point, and the hull is solved again with those rows, for up to
  /// `contactRounds` rounds as new points come in. The muscle then slides over
  /// the bone as a whole, its volume held, instead of keeping a deep print
  /// for the static resolution to cut out; and the unfolding of turned-over
  /// triangles keeps to the bones (a point it would carry into a bone slides
  /// on its surface, one already inside is not carried deeper). Overlap a
  /// muscle may keep is MuscleToDeform::boneOverlap. 0: none of this, the
  /// paper's method.
  double contactWeight = 0;
  int contactRounds = 3;
  /// Measure DeformationResult::restSamplesInside and currentSamplesInside
  /// (a hierarchy of each muscle, twice): callers that do not report them
  /// skip the cost.
  bool measureSamplesInside = true;
};

/// One muscle to deform.
struct MuscleToDeform
{
  std::string name;                     ///< for messages
  const TriangleMesh* muscle = nullptr; ///< full mesh in the rest pose (any point order; unused points follow too)
  const TriangleMesh* hull = nullptr;   ///< rest-pose hull enclosing the muscle (BuildProgressiveHull)
  std::vector<MatchedLine> lines;
  /// Mean value coordinates of the muscle's points in the hull (one row per
  /// point), when already known: they depend on the rest pose only, so
  /// callers that deform the same muscle again keep them. Computed when null.
  const WeightMatrix* weights = nullptr;
  /// Per-point offset from weights * hull (one row per point), when the
  /// muscle is not exactly the mapping of its hull: a step of the
  /// interpolation method starts from a resolved mesh whose bone prints the
  /// hull does not carry. The full mesh is then weights * hull + detail.
  const Points* detail = nullptr;
  /// The shape that turned-over triangles are judged against and that
  /// unfolding gives back locally (same points and triangles), when not the
  /// muscle's own: a step of the interpolation method gives the rest pose, so
  /// that a fold an earlier step left is undone rather than kept.
  const Points* reference = nullptr;
  /// Volume to hold, when not the muscle's own (a step of the interpolation
  /// method holds the rest pose's volume, so that no error builds up); 0: its own.
  double targetVolume = 0;
  /// With DeformationParameters::contactWeight: [bone][point] != 0 where the
  /// point may stay inside that bone (the overlap a rest pose already has),
  /// one list per bone of the pass. Null: none may.
  const std::vector<std::vector<char>>* boneOverlap = nullptr;
};

struct DeformationResult
{
  Points points;     ///< deformed full mesh
  Points hullPoints; ///< deformed hull
  int iterations = 0;
  int coarseIterations = 0;
  bool converged = false;
  double volumeChangePercent = 0;    ///< of the full mesh
  std::int64_t flippedTriangles = 0; ///< against the reference shape
  /// Points left where they were because they were inside a bone when the
  /// fine phase started (frozen), and points stopped at an obstacle's surface
  /// in the last step.
  std::int64_t verticesFrozen = 0;
  std::int64_t verticesStopped = 0;
  /// Points held to a bone's surface by contact rows (DeformationParameters::contactWeight).
  std::int64_t verticesInContact = 0;
  /// Action-line samples inside the muscle: rest samples in the rest-pose
  /// muscle, current samples in the deformed muscle (fractions in [0, 1];
  /// 0 unless DeformationParameters::measureSamplesInside).
  double restSamplesInside = 0;
  double currentSamplesInside = 0;
  double seconds = 0; ///< this muscle's share of the pass (set-up and iterations)
  std::vector<std::string> warnings;
};

/// An obstacle in the current pose (a bone, or any mesh the muscles may not
/// enter). The muscles of a pass are obstacles for each other without being
/// listed. The tree may be refitted to another pose between passes.
struct Obstacle
{
  std::string name;
  std::shared_ptr<TriangleTree> tree;
};

/// Bounding-volume hierarchies of the obstacles, built in parallel.
std::vector<Obstacle> BuildObstacles(const std::vector<std::string>& names, const std::vector<TriangleMesh>& meshes);

/// Deforms every muscle from the rest pose to the current pose in one pass,
/// all together.
///
/// Coarse phase: the hull alone, its own volume held, no obstacles; with
/// `contactWeight` then again with rows pulling the points the bones moved
/// into out to the bones' surfaces (see DeformationParameters). Fine
/// phase, from the coarse result W X: the volume of the full mesh held and,
/// with `dynamicIntersections`, every move that would enter an obstacle or
/// another muscle stops at its surface, and a point inside a bone when the
/// fine phase starts stays where it is (the paper's rule). Before the fine
/// phase, a point the coarse phase put inside another muscle, where it was not
/// in the rest pose, goes out to that muscle's nearest surface point. At
/// convergence, triangles the mapping turned over are unfolded and the volume
/// settles again.
///
/// Throws InputError naming the muscle for input that cannot give a sound
/// result: an action line that does not pass through the hull, a muscle
/// entirely inside an obstacle before it moves, no or unmatched action lines,
/// non-finite coordinates, a least-squares system nothing fixes; ComputationError
/// when a muscle's deformation diverges. The caller
/// checks that a hull it was given encloses its muscle. `progress`
/// (optional) receives fractions in [0, 1].
std::vector<DeformationResult> DeformMuscles(const std::vector<MuscleToDeform>& muscles,
  const std::vector<Obstacle>& bones, const DeformationParameters& parameters,
  const std::function<void(double)>& progress = {});

/// DeformMuscles of every muscle that can be deformed: a muscle whose failure is its own (see
/// DeformMuscles) is left out, `failures[m]` (one per muscle; those not empty on entry are left out
/// from the start) says why, its result has no points, and the others are deformed as if it had
/// not been given. Throws what DeformMuscles throws for every muscle's failure (an obstacle's) and
/// when no muscle can be deformed.
std::vector<DeformationResult> DeformMusclesThatCan(const std::vector<MuscleToDeform>& muscles,
  const std::vector<Obstacle>& bones, const DeformationParameters& parameters, std::vector<std::string>& failures,
  const std::function<void(double)>& progress = {});

/// Whether `knots` name the own points of a line of `points` points: none (every point is its
/// own), or rising from its first point to its last (kKnotsRule).
bool KnotsFit(const Knots& knots, Eigen::Index points);
inline constexpr const char* kKnotsRule =
  "they must be none (every point its own) or rise from its first point to its last";

/// Lines of more than `maximumPoints` points (a path sampled densely, a scanned centreline) are
/// cut down to `maximumPoints`, keeping the points that deviate most from the kept line in either
/// pose (greedy Douglas-Peucker on both poses at once), so that the action-line rows, which grow
/// with the points, stay bounded. A line's own points (`knots`) are always kept. Lines within the
/// limit are left exactly as they are. Returns one note per line cut down (its index, points
/// before and after, largest deviation left).
std::vector<std::string> LimitActionLinePoints(std::vector<MatchedLine>& lines, Eigen::Index maximumPoints = 256);

/// Samples along matched lines: `samplesPerSegment` per piece (LineSpan: a segment, or the
/// points between two of the line's own points, evenly over its rest length) plus the last point
/// of each line, at the same places on both poses.
void SampleMatchedLines(
  const std::vector<MatchedLine>& lines, int samplesPerSegment, Points& restSamples, Points& currentSamples);

/// Triangles the deformation turned over: the deformed normal points against
/// the rest normal carried by the rotation of the triangle's neighbourhood
/// (the best rotation of the edges at its three points, rest to deformed).
/// A rigid motion flips none, whatever the rotation.
std::int64_t CountFlippedTriangles(const Points& rest, const Points& deformed, const Triangles& triangles);
/// The same triangles, listed; only among `candidates` when given.
std::vector<Eigen::Index> FlippedTriangles(const Points& rest, const Points& deformed, const Triangles& triangles,
  const std::vector<Eigen::Index>* candidates = nullptr);

/// Number of `points` inside the closed surface of `tree` (bounding-box check first).
std::int64_t CountInsideTree(const TriangleTree& tree, const Points& points);

/// The warning for a part of muscle `muscle` that lies apart from the rest and that no action
/// line passes through: `points` of the `of` points of `what` (its coarse hull, its surface).
std::string PartApartWarning(const std::string& muscle, std::int64_t points, std::int64_t of, const std::string& what);
}
