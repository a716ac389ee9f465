// SPDX-License-Identifier: BSD-3-Clause
// A muscle's fibres (docs/DESIGN.md, "Fibres"): streamlines of a harmonic field through the rest
// muscle from its origin to its insertion (Choi & Blemker 2013), carried through any deformation
// of the surface by mean value coordinates.
#pragma once

#include "Common/Attachment.h"
#include "Common/MeshTypes.h"
#include "Geometry/RigidMotion.h"
#include "Geometry/TriangleTree.h"

#include <Eigen/SparseCore>

#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace md
{
/// How far below the surface (and out of an obstacle) a fibre point carried out of it is put
/// back: its depth at rest, at most this share of the muscle's grid spacing. A point is searched
/// for leaving within its rest clearance and two grid spacings.
constexpr double kFibreClearance = 0.25;

struct FibreParameters
{
  int count = 100;         ///< fibres per muscle
  int pointsPerFibre = 13; ///< points of each fibre's polyline, its ends included
  /// About this many grid nodes inside the muscle carry the field (four times as many, once,
  /// where that traces under half the fibres).
  int gridNodes = 20000;
  /// Share of the mean value weights (by absolute size) each fibre point keeps; the rest, the
  /// far surface's, is dropped and the kept weights are corrected to reproduce every affine map
  /// exactly. Keeps a frame's fibres a sparse product.
  double keptWeightShare = 0.99;
};

/// An obstacle the carried fibres keep out of: a tree of its surface in one pose, and the rigid
/// motion from that pose to where it is now (identity: the tree is where it is). A bone that
/// moves rigidly keeps its rest tree: no refit a frame. A tree with a distance grid
/// (TriangleTree::BuildDistanceGrid) is searched only where a point may be inside it, as deep as
/// it may be.
struct FibreObstacle
{
  const TriangleTree* tree = nullptr;
  RigidTransform toNow;
};

/// A bone that moved rigidly to within this share of its size is an obstacle of the fibres as its
/// rest tree moved rigidly: far below their clearance, and above the rounding of points stored in
/// single precision (6e-8), which would otherwise cost a refit and a slower search every frame.
constexpr double kRigidObstacleShare = 1e-6;

/// The rigid motion taking `rest` to `now` (the same points), when `now` is one to within
/// `tolerance` at every point; nullopt otherwise (or when the counts differ).
std::optional<RigidTransform> RigidMotionOf(const Points& rest, const Points& now, double tolerance);

/// The surface points each end of the fibres starts from: the origin's (nearer the action
/// lines' first points) and the insertion's.
struct FibreEnds
{
  std::vector<Eigen::Index> origin, insertion;
  std::string originSource, insertionSource; ///< how each was found (messages)
};

/// The ends of a muscle's fibres: its attachment areas, each given to the end of the action lines
/// its points are nearer (the lines' first points: the origin; their last: the insertion). An
/// end with no area is the muscle's cap there: the surface points within 5 % of the muscle's
/// extent along its lines' mean direction from that extreme. Throws InputError when the lines
/// have no length.
FibreEnds FindFibreEnds(
  const TriangleMesh& rest, const std::vector<Attachment>& attachments, const std::vector<Points>& restLines);

/// A muscle's fibres, made in the rest pose.
class MuscleFibres
{
public:
  /// Fibres from `ends.origin` to `ends.insertion` through the closed surface `rest`: the field
  /// phi solves Laplace's equation on a grid of the muscle's inside (phi = 0 next to the origin,
  /// 1 next to the insertion, no flux through the rest of the surface); each fibre is the
  /// streamline of grad phi from a seed next to the origin (seeds spread over it by farthest
  /// point sampling) to the insertion, closed at both ends by the nearest point of the end's
  /// area just inside the surface, and resampled to pointsPerFibre points at equal arc lengths.
  /// Where fewer than half the fibres can be traced, the muscle is traced once more on a grid
  /// of 4 * gridNodes (said in Warnings). Throws InputError when no fibre can be made on either
  /// (an end with no inside next to it, the ends not connected inside the muscle).
  /// The fibres keep out of `obstacles` (closed surfaces: the bones, in the muscle's frame),
  /// where the rest muscle overlaps them too.
  MuscleFibres(const TriangleMesh& rest, const FibreEnds& ends, const FibreParameters& parameters = {},
    const std::vector<const TriangleMesh*>& obstacles = {});

  int Count() const { return this->Fibres; }
  int PointsPerFibre() const { return this->PerFibre; }
  /// Every fibre's points in the rest pose: fibre f is rows [f * PointsPerFibre(), ...).
  const Points& Rest() const { return this->RestPoints; }
  /// The fibres where `surface` (the muscle's points, as many as at rest) has gone: each point
  /// by its mean value coordinates in the rest surface, then, where that has left it outside
  /// the surface or inside one of `obstacles` (the bones where they are now), moved back to
  /// its rest depth below the surface (at most kFibreClearance) or as far out of the obstacle.
  /// `kept` (optional) receives how many points were moved and how many could not be kept in.
  Points At(
    const Points& surface, const std::vector<FibreObstacle>& obstacles = {}, std::pair<int, int>* kept = nullptr) const;
  /// Each fibre's length (its polyline's) of fibre points `points`.
  std::vector<double> Lengths(const Points& points) const;
  /// What was said while making them (fewer fibres than asked for).
  const std::vector<std::string>& Warnings() const { return this->Said; }
  /// The rest surface's triangles (the fibres' muscle, for checks).
  const md::Triangles& SurfaceTriangles() const { return this->RestTriangles; }
  /// Nonzero weights per fibre point, on average (the cost of At).
  double MeanWeightsPerPoint() const;

private:
  int Fibres = 0;
  int PerFibre = 0;
  Points RestPoints;
  md::Triangles RestTriangles;
  std::shared_ptr<const TriangleTree> RestTree;
  std::vector<std::vector<Eigen::Index>> Around; ///< per surface point, its triangles
  Eigen::VectorXd Depth; ///< per fibre point: how deep it is put back (its rest clearance, at most kFibreClearance)
  /// Per fibre point, the muscle's triangle nearest it at rest: where the search for the wall
  /// nearest the carried point starts (it prunes the search; the answer is the same).
  std::vector<Eigen::Index> NearestWall;
  double Reach = 0; ///< how far from a carried point the surfaces are searched
  /// Fibre points x surface points; single precision (a frame reads every weight: half the
  /// memory traffic; 1e-7 of a weight is far below the settle's tolerance).
  Eigen::SparseMatrix<float, Eigen::RowMajor, int> Weights;
  /// A fibre's end: its row of Weights holds its area's point, (1 - share) of it; `share` of the
  /// carried next point of the fibre is added.
  struct EndBlend
  {
    Eigen::Index point, next;
    double share;
  };
  std::vector<EndBlend> EndBlends;
  std::vector<std::string> Said;
};

/// Median, smallest and largest of `values` (NaN for none).
struct Spread
{
  double median, low, high;
};
Spread SpreadOf(std::vector<double> values);
}
