#include "TriangleTree.h"

#include "MeshChecks.h"
#include "TriangleIntersection.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace md
{
namespace
{
constexpr int leafSize = 4;

/// Slab test: does the segment origin + t * direction, t in [0, limit], meet the box?
bool SegmentMeetsBox(const Eigen::Vector3d& origin, const Eigen::Vector3d& inverse, double limit,
  const Eigen::Vector3d& low, const Eigen::Vector3d& high)
{
  double enter = 0, leave = limit;
  for (int axis = 0; axis < 3; ++axis)
  {
    double t0 = (low[axis] - origin[axis]) * inverse[axis];
    double t1 = (high[axis] - origin[axis]) * inverse[axis];
    if (std::isnan(t0) || std::isnan(t1))
    {
      continue; // parallel to the slab and on its boundary: does not decide
    }
    if (t0 > t1)
    {
      std::swap(t0, t1);
    }
    enter = std::max(enter, t0);
    leave = std::min(leave, t1);
    if (enter > leave)
    {
      return false;
    }
  }
  return true;
}

double BoxDistanceSquared(const Eigen::Vector3d& p, const Eigen::Vector3d& low, const Eigen::Vector3d& high)
{
  const Eigen::Vector3d outside = (low - p).cwiseMax(p - high).cwiseMax(0.0);
  return outside.squaredNorm();
}
}

TriangleTree::TriangleTree(const TriangleMesh& mesh)
  : Surface(mesh)
{
  const Eigen::Index m = mesh.triangles.rows();
  if (m == 0)
  {
    throw InputError("an obstacle has no triangles");
  }
  this->Size = (mesh.points.colwise().maxCoeff() - mesh.points.colwise().minCoeff()).norm();
  this->Order.resize(static_cast<size_t>(m));
  this->Centroid.resize(static_cast<size_t>(m));
  for (Eigen::Index t = 0; t < m; ++t)
  {
    this->Order[t] = t;
    this->Centroid[t] = (mesh.points.row(mesh.triangles(t, 0)) + mesh.points.row(mesh.triangles(t, 1)) +
                          mesh.points.row(mesh.triangles(t, 2)))
                          .transpose() /
      3.0;
  }
  this->Nodes.reserve(static_cast<size_t>(2 * m / leafSize + 1));
  this->Build(0, static_cast<int>(m), 0);
}

int TriangleTree::Build(int first, int count, int depth)
{
  const int index = static_cast<int>(this->Nodes.size());
  this->Nodes.emplace_back();
  Eigen::Vector3d low = Eigen::Vector3d::Constant(std::numeric_limits<double>::max());
  Eigen::Vector3d high = -low;
  Eigen::Vector3d centreLow = low, centreHigh = high;
  for (int i = first; i < first + count; ++i)
  {
    const Eigen::Index t = this->Order[i];
    for (int k = 0; k < 3; ++k)
    {
      low = low.cwiseMin(this->Corner(t, k));
      high = high.cwiseMax(this->Corner(t, k));
    }
    centreLow = centreLow.cwiseMin(this->Centroid[t]);
    centreHigh = centreHigh.cwiseMax(this->Centroid[t]);
  }
  this->Nodes[index].low = low;
  this->Nodes[index].high = high;
  if (count <= leafSize || depth > 60)
  {
    this->Nodes[index].first = first;
    this->Nodes[index].count = count;
    return index;
  }
  Eigen::Index axis;
  (centreHigh - centreLow).maxCoeff(&axis);
  const int half = count / 2;
  std::nth_element(this->Order.begin() + first, this->Order.begin() + first + half,
    this->Order.begin() + first + count,
    [&](Eigen::Index a, Eigen::Index b) { return this->Centroid[a][axis] < this->Centroid[b][axis]; });
  const int left = this->Build(first, half, depth + 1);
  const int right = this->Build(first + half, count - half, depth + 1);
  this->Nodes[index].left = left;
  this->Nodes[index].right = right;
  return index;
}

template <typename Visit>
void TriangleTree::ForTrianglesNearSegment(
  const Eigen::Vector3d& from, const Eigen::Vector3d& direction, const double& limit, Visit&& visit) const
{
  // `limit` is read at every box: a caller may shorten the segment as it goes.
  const Eigen::Vector3d inverse = direction.cwiseInverse();
  std::vector<int> stack{ 0 };
  while (!stack.empty())
  {
    const Node& node = this->Nodes[stack.back()];
    stack.pop_back();
    if (!SegmentMeetsBox(from, inverse, limit, node.low, node.high))
    {
      continue;
    }
    if (node.left >= 0)
    {
      stack.push_back(node.left);
      stack.push_back(node.right);
      continue;
    }
    for (int i = node.first; i < node.first + node.count; ++i)
    {
      visit(this->Order[i]);
    }
  }
}

std::optional<TriangleTree::Hit> TriangleTree::FirstHit(const Eigen::Vector3d& from, const Eigen::Vector3d& to) const
{
  const Eigen::Vector3d direction = to - from;
  std::optional<Hit> best;
  double limit = 1.0;
  this->ForTrianglesNearSegment(from, direction, limit, [&](Eigen::Index t) {
    double t01, u, v;
    if (IntersectLineTriangle(from, direction, this->Corner(t, 0), this->Corner(t, 1), this->Corner(t, 2), 0.0, t01, u, v) &&
      t01 >= 0 && t01 <= limit)
    {
      limit = t01;
      best = Hit{ t01, t, from + t01 * direction };
    }
  });
  return best;
}

int TriangleTree::CountCrossings(const Eigen::Vector3d& origin, const Eigen::Vector3d& direction, bool& grazed) const
{
  // A segment long enough to leave the surface's box.
  const Eigen::Vector3d d = 4.0 * (this->Size + (origin - this->Nodes[0].low).norm()) * direction;
  const double edgeTolerance = 1e-9;
  int crossings = 0;
  grazed = false;
  this->ForTrianglesNearSegment(origin, d, 1.0, [&](Eigen::Index t) {
    double t01, u, v;
    if (!IntersectLineTriangle(
          origin, d, this->Corner(t, 0), this->Corner(t, 1), this->Corner(t, 2), edgeTolerance, t01, u, v) ||
      t01 < 0 || t01 > 1)
    {
      return;
    }
    if (u < edgeTolerance || v < edgeTolerance || u + v > 1 - edgeTolerance)
    {
      grazed = true; // through an edge or a point: this ray cannot be trusted
    }
    ++crossings;
  });
  return crossings;
}

bool TriangleTree::Inside(const Eigen::Vector3d& p) const
{
  // Fixed, unremarkable directions: deterministic, and unlikely to run along edges.
  static const Eigen::Vector3d directions[] = { Eigen::Vector3d(0.5773, 0.5774, 0.5773).normalized(),
    Eigen::Vector3d(-0.3210, 0.8765, -0.3590).normalized(), Eigen::Vector3d(0.7071, -0.2345, -0.6669).normalized(),
    Eigen::Vector3d(-0.6543, -0.5432, 0.5265).normalized(), Eigen::Vector3d(0.1234, -0.9012, 0.4155).normalized() };
  int votesInside = 0, votes = 0;
  for (const Eigen::Vector3d& direction : directions)
  {
    bool grazed = false;
    const int crossings = this->CountCrossings(p, direction, grazed);
    if (grazed)
    {
      continue;
    }
    votesInside += crossings % 2;
    if (++votes == 3)
    {
      break;
    }
  }
  if (votes == 0)
  {
    return WindingNumber(this->Surface.points, this->Surface.triangles, p) > 0.5; // every ray grazed
  }
  return 2 * votesInside > votes;
}

TriangleTree::Closest TriangleTree::ClosestPoint(const Eigen::Vector3d& p) const
{
  Closest best;
  double bestSquared = std::numeric_limits<double>::max();
  std::vector<int> stack{ 0 };
  while (!stack.empty())
  {
    const Node& node = this->Nodes[stack.back()];
    stack.pop_back();
    if (BoxDistanceSquared(p, node.low, node.high) >= bestSquared)
    {
      continue;
    }
    if (node.left >= 0)
    {
      // Nearer child last, so it is visited first.
      const Node& left = this->Nodes[node.left];
      const Node& right = this->Nodes[node.right];
      const bool leftNearer =
        BoxDistanceSquared(p, left.low, left.high) < BoxDistanceSquared(p, right.low, right.high);
      stack.push_back(leftNearer ? node.right : node.left);
      stack.push_back(leftNearer ? node.left : node.right);
      continue;
    }
    for (int i = node.first; i < node.first + node.count; ++i)
    {
      const Eigen::Index t = this->Order[i];
      const double d = PointTriangleDistance(p, this->Corner(t, 0), this->Corner(t, 1), this->Corner(t, 2));
      if (d * d < bestSquared)
      {
        bestSquared = d * d;
        best.distance = d;
        best.triangle = t;
      }
    }
  }
  // The closest point itself, on the closest triangle.
  if (best.triangle >= 0)
  {
    best.point = ClosestPointOnTriangle(
      p, this->Corner(best.triangle, 0), this->Corner(best.triangle, 1), this->Corner(best.triangle, 2));
  }
  return best;
}
}
