// SPDX-License-Identifier: BSD-3-Clause
// A bounding-volume hierarchy over the triangles of a closed surface, for the
// queries intersection handling needs against obstacles (bones, other muscles):
// first hit along a segment, inside or outside, closest point.
#pragma once

#include "Common/MeshTypes.h"

#include <array>
#include <limits>
#include <optional>
#include <utility>
#include <vector>

namespace md
{
class TriangleTree
{
public:
  /// Builds the tree (median splits on the longest axis, a few triangles a
  /// leaf). The mesh is copied: the tree stays valid whatever happens to it.
  explicit TriangleTree(const TriangleMesh& mesh);

  struct Hit
  {
    double t = 0; ///< fraction of the segment, in [0, 1]
    Eigen::Index triangle = -1;
    Eigen::Vector3d point;
  };
  /// The first triangle the segment from `from` to `to` meets, if any.
  std::optional<Hit> FirstHit(const Eigen::Vector3d& from, const Eigen::Vector3d& to) const;

  /// The first triangle the segment from `from` to `to` enters through (against the triangle's
  /// normal: from outside an outward surface to its inside), if any. Triangles it leaves through
  /// are passed, so a segment that starts inside an outward surface, or behind a one-sided
  /// open sheet, meets only what it enters.
  std::optional<Hit> FirstEntry(const Eigen::Vector3d& from, const Eigen::Vector3d& to) const;

  /// How many triangles the segment from `from` to `to` crosses: odd when
  /// the segment leaves or enters the closed surface, even when both ends are
  /// on the same side.
  int Crossings(const Eigen::Vector3d& from, const Eigen::Vector3d& to) const;

  /// Whether p is inside the closed surface: the parity of crossings along
  /// rays towards the nearest sides of the surface's box, decided by the
  /// majority of three (two that agree) so that a ray grazing an edge or a
  /// point cannot decide alone.
  bool Inside(const Eigen::Vector3d& p) const;

  /// The winding number of the closed, oriented surface about p (1 inside, 0 outside, 2 where a
  /// surface that passes through itself covers p twice): the crossings of a ray from p, each +1
  /// where the ray leaves through a triangle and -1 where it enters, along the same rays as
  /// Inside, two that agree deciding. The same integer as WindingNumber (MeshChecks.h) rounded,
  /// at the cost of a ray query instead of a sum over every triangle.
  int Winding(const Eigen::Vector3d& p) const;

  struct Closest
  {
    double distance = 0;
    Eigen::Index triangle = -1;
    Eigen::Vector3d point;
  };
  /// The point of the surface closest to p; with `within`, only if closer
  /// than that (else triangle -1), which prunes the search to that radius. A `hint`, a triangle
  /// likely to be near p, prunes it from the start to that triangle's distance (the answer is
  /// the same: a triangle as close as the closest).
  Closest ClosestPoint(
    const Eigen::Vector3d& p, double within = std::numeric_limits<double>::max(), Eigen::Index hint = -1) const;

  const TriangleMesh& Mesh() const { return this->Surface; }

  /// Builds a coarse grid of the surface's signed distance (negative inside) at about `nodes`
  /// nodes over its box grown by a cell, for SignedDistanceBounds: a query far from the
  /// surface then learns its side without a search. A refit drops it; a surface with no extent
  /// gets none.
  void BuildDistanceGrid(int nodes = 32768);
  /// Bounds on p's signed distance to the surface (negative inside), from the nearest node of
  /// the distance grid give or take p's distance to that node (a distance changes no faster
  /// than the point): {a cell, infinity} beyond the grid; nullopt without a grid.
  std::optional<std::pair<double, double>> SignedDistanceBounds(const Eigen::Vector3d& p) const;

  /// Moves the surface's points (same triangles) and updates the boxes
  /// bottom-up: O(triangles), far cheaper than a rebuild, for obstacles that
  /// deform a little at a time (muscles). Queries stay exact; only their speed
  /// suffers if the points move far.
  void Refit(const Points& points);

  /// Whether p lies inside the box of the whole surface.
  bool InBounds(const Eigen::Vector3d& p) const
  {
    return (p.array() >= this->Nodes[0].low.array()).all() && (p.array() <= this->Nodes[0].high.array()).all();
  }

  /// Unit normal of a triangle (by its point order).
  Eigen::Vector3d Normal(Eigen::Index triangle) const
  {
    return (this->Corner(triangle, 1) - this->Corner(triangle, 0))
      .cross(this->Corner(triangle, 2) - this->Corner(triangle, 0))
      .normalized();
  }

private:
  struct Node
  {
    Eigen::Vector3d low, high;
    int first = 0, count = 0; // leaf: triangles Order[first .. first + count)
    int left = -1, right = -1;
    int pointFirst = 0, pointCount = 0; // leaf: its triangles' points LeafPoints[pointFirst ..)
  };
  struct BuildItem
  {
    Eigen::Vector3d centroid;
    Eigen::Index triangle;
  };
  int Build(std::vector<BuildItem>& items, int first, int count, int depth);
  void LeafBox(Node& node) const;
  void UpdateBoxes();
  Eigen::Vector3d Corner(Eigen::Index triangle, int k) const
  {
    return this->Surface.points.row(this->Surface.triangles(triangle, k)).transpose();
  }
  /// Triangles a segment crosses: how many, their sum with +1 for each the segment leaves through
  /// (along the triangle's normal) and -1 for each it enters through, and whether any crossing
  /// was close to an edge or a point (`grazed`: the counts cannot be trusted).
  struct CrossingCount
  {
    int crossings = 0;
    int leavingMinusEntering = 0;
    bool grazed = false;
  };
  /// The crossings of a ray from `origin` along `direction` out of the surface's box.
  CrossingCount CountCrossings(const Eigen::Vector3d& origin, const Eigen::Vector3d& direction) const;
  /// The crossings of the segment from + t d, t in [0, 1], counting those it meets within
  /// `edgeTolerance` (barycentric) of their edges.
  CrossingCount SegmentCrossings(const Eigen::Vector3d& from, const Eigen::Vector3d& d, double edgeTolerance) const;
  /// Six ray directions from p: towards the faces of the surface's box, nearest first, each
  /// tilted off its axis.
  std::array<Eigen::Vector3d, 6> RayDirections(const Eigen::Vector3d& p) const;
  /// The first triangle the segment from + t direction, t in [0, 1], meets among those
  /// `accepted(triangle)` is true of.
  template<typename Accept>
  std::optional<Hit> FirstHitWhere(
    const Eigen::Vector3d& from, const Eigen::Vector3d& direction, Accept&& accepted) const;
  /// Calls visit(triangle) for every triangle whose leaf box the segment
  /// from + t direction, t in [0, limit], meets.
  template<typename Visit>
  void ForTrianglesNearSegment(
    const Eigen::Vector3d& from, const Eigen::Vector3d& direction, const double& limit, Visit&& visit) const;

  TriangleMesh Surface;
  std::vector<Node> Nodes;
  std::vector<float> GridDistance; ///< signed distance at each grid node, x fastest; empty: no grid
  Eigen::Vector3d GridOrigin = Eigen::Vector3d::Zero();
  double GridCell = 0; ///< also the margin the grid reaches beyond the surface's box
  std::array<int, 3> GridCount{};
  std::vector<Eigen::Index> Order;
  /// Each leaf's points, once each: a refit reads each point about twice rather than six times.
  std::vector<Eigen::Index> LeafPoints;
  double Size = 0;
};

/// Just outside a surface: `offset` beyond its point `closest` nearest to p,
/// p being inside (closest.distance > 0), on the way out.
inline Eigen::Vector3d JustOutside(const TriangleTree::Closest& closest, const Eigen::Vector3d& p, double offset)
{
  return closest.point + (offset / closest.distance) * (closest.point - p);
}

/// The direction out of a surface at `q`, its point (on `triangle` of `tree`) nearest to `p`: from
/// q towards p when p is outside, from p towards q when p is inside, and the triangle's normal
/// when p lies on it.
inline Eigen::Vector3d OutwardNormal(
  const Eigen::Vector3d& p, const Eigen::Vector3d& q, bool inside, const TriangleTree& tree, Eigen::Index triangle)
{
  const double distance = (p - q).norm();
  return distance > 0 ? Eigen::Vector3d((inside ? -1.0 : 1.0) * (p - q) / distance) : tree.Normal(triangle);
}
}
