// SPDX-License-Identifier: BSD-3-Clause
// Checks and measures on closed triangle surfaces.
#pragma once

#include "Common/MeshTypes.h"

#include <vector>

namespace md
{
struct EdgeReport
{
  std::int64_t boundaryEdges = 0;       ///< edges used by one triangle (holes)
  std::int64_t nonManifoldEdges = 0;    ///< edges used by more than two triangles
  std::int64_t inconsistentEdges = 0;   ///< edges walked the same way by both triangles
  std::int64_t degenerateTriangles = 0; ///< triangles repeating a point index

  bool Closed() const { return this->boundaryEdges == 0; }
  bool Manifold() const { return this->nonManifoldEdges == 0; }
  bool ConsistentlyOriented() const { return this->inconsistentEdges == 0; }
  bool IsClosedOrientedManifold() const
  {
    return this->Closed() && this->Manifold() && this->ConsistentlyOriented() && this->degenerateTriangles == 0;
  }
};

/// Counts the edge defects of a triangle mesh (topology only).
EdgeReport CheckEdges(const Triangles& triangles);

/// Signed volume enclosed by a closed triangle surface: positive when the
/// triangles are oriented with normals pointing outwards.
double SignedVolume(const Points& points, const Triangles& triangles);

/// Generalised winding number of a closed surface about `query`
/// (Jacobson et al. 2013): about 1 inside, 0 outside. O(triangles) per query;
/// meant for checks and tests, not for hot loops.
double WindingNumber(const Points& points, const Triangles& triangles, const Eigen::Vector3d& query);

/// Number of `queries` inside the closed surface (winding number > 0.5).
std::int64_t CountInside(const Points& points, const Triangles& triangles, const Points& queries);

/// The point of triangle abc closest to `p`.
Eigen::Vector3d ClosestPointOnTriangle(
  const Eigen::Vector3d& p, const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c);

/// Barycentric coordinates of q (on the triangle's plane) in triangle t of `mesh`; a third each
/// for a degenerate triangle.
Eigen::Vector3d BarycentricCoordinates(const TriangleMesh& mesh, Eigen::Index t, const Eigen::Vector3d& q);

/// Distance from `p` to the triangle abc.
double PointTriangleDistance(
  const Eigen::Vector3d& p, const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c);

/// Number of `points` outside the closed surface: winding number below 1/2
/// and farther than `tolerance` from every triangle. Every point is tested.
std::int64_t CountOutside(const TriangleMesh& surface, const Points& points, double tolerance);

/// The diagonal of the points' bounding box (0 for no points): the size tolerances are relative to.
inline double BoxDiagonal(const Points& points)
{
  return points.rows() ? (points.colwise().maxCoeff() - points.colwise().minCoeff()).norm() : 0.0;
}

/// Per point, whether a triangle uses it (mesh files may carry other points).
std::vector<char> UsedMask(const TriangleMesh& mesh);

/// The points the triangles use, in order.
Points UsedPoints(const TriangleMesh& mesh);

/// Connected component of every point, numbered from 0 (`count` of them),
/// through the edges of the triangles. With `member`, only member points
/// count and an edge joins two members only; other points get -1.
std::vector<int> Components(
  const Triangles& triangles, Eigen::Index points, int& count, const std::vector<char>* member = nullptr);

/// The distinct neighbours of every point through the edges of the triangles,
/// each list in increasing order (a fixed order: sums over it are reproducible).
std::vector<std::vector<std::int64_t>> PointNeighbours(const Triangles& triangles, Eigen::Index points);

/// Edges (between two triangles) whose dihedral angle, the angle between the
/// normals of their triangles, exceeds `angleDegrees` in `current` but not in
/// `rest` (same triangles): the pits and folds a deformation made.
std::int64_t CountNewSharpEdges(
  const Points& rest, const Points& current, const Triangles& triangles, double angleDegrees = 60.0);

/// CountNewSharpEdges for many poses of one rest surface: the edges not sharp at rest are
/// found once (pairing the triangles by edge is most of the count's time).
class NewSharpEdges
{
public:
  NewSharpEdges() = default;
  NewSharpEdges(const Points& rest, const Triangles& triangles, double angleDegrees = 60.0);
  /// The edges not sharp at rest that are sharp in `current` (the rest surface's triangles).
  std::int64_t Count(const Points& current) const;

private:
  Triangles TrianglesAtRest;
  std::vector<std::pair<Eigen::Index, Eigen::Index>> NotSharpAtRest; ///< the two triangles of each edge
  double Limit = 0.5;                                                ///< cosine of the angle
};

/// Number of pairs of triangles that intersect other than at what they share.
std::int64_t CountSelfIntersections(const TriangleMesh& surface);
}
