// SPDX-License-Identifier: BSD-3-Clause
#include "Geometry/TriangleTree.h"

#include "Geometry/MeshChecks.h"
#include "Geometry/TriangleIntersection.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

namespace md
{
namespace
{
constexpr int leafSize = 4;
constexpr int maximumDepth = 60; // splits stop there, so a traversal stack never holds more than this + 1

/// The nodes still to visit in a depth-first traversal, on the call stack:
/// queries run in hot parallel loops, where a heap allocation each would cost.
/// An entry is a node's index, or the index with what the query knows of it.
template<typename Entry = int>
class NodeStack
{
public:
  void Push(const Entry& node) { this->Nodes[this->Size++] = node; }
  Entry Pop() { return this->Nodes[--this->Size]; }
  bool Empty() const { return this->Size == 0; }

private:
  std::array<Entry, maximumDepth + 2> Nodes;
  int Size = 0;
};

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
  // Triangles are ordered by splitting (contiguous centroids: cache-friendly).
  std::vector<BuildItem> items(static_cast<size_t>(m));
  for (Eigen::Index t = 0; t < m; ++t)
  {
    items[t].centroid = (mesh.points.row(mesh.triangles(t, 0)) + mesh.points.row(mesh.triangles(t, 1)) +
                          mesh.points.row(mesh.triangles(t, 2)))
                          .transpose() /
      3.0;
    items[t].triangle = t;
  }
  this->Nodes.reserve(static_cast<size_t>(4 * m / leafSize + 1));
  this->Build(items, 0, static_cast<int>(m), 0);
  this->Order.resize(static_cast<size_t>(m));
  for (Eigen::Index t = 0; t < m; ++t)
  {
    this->Order[t] = items[t].triangle;
  }
  for (Node& node : this->Nodes)
  {
    if (node.left >= 0)
    {
      continue;
    }
    node.pointFirst = static_cast<int>(this->LeafPoints.size());
    for (int i = node.first; i < node.first + node.count; ++i)
    {
      for (int k = 0; k < 3; ++k)
      {
        this->LeafPoints.push_back(mesh.triangles(this->Order[i], k));
      }
    }
    std::sort(this->LeafPoints.begin() + node.pointFirst, this->LeafPoints.end());
    this->LeafPoints.erase(
      std::unique(this->LeafPoints.begin() + node.pointFirst, this->LeafPoints.end()), this->LeafPoints.end());
    node.pointCount = static_cast<int>(this->LeafPoints.size()) - node.pointFirst;
  }
  this->UpdateBoxes();
}

int TriangleTree::Build(std::vector<BuildItem>& items, int first, int count, int depth)
{
  const int index = static_cast<int>(this->Nodes.size());
  this->Nodes.emplace_back();
  this->Nodes[index].first = first;
  this->Nodes[index].count = count;
  if (count <= leafSize || depth >= maximumDepth)
  {
    return index;
  }
  Eigen::Vector3d centreLow = Eigen::Vector3d::Constant(std::numeric_limits<double>::max());
  Eigen::Vector3d centreHigh = -centreLow;
  for (int i = first; i < first + count; ++i)
  {
    centreLow = centreLow.cwiseMin(items[i].centroid);
    centreHigh = centreHigh.cwiseMax(items[i].centroid);
  }
  Eigen::Index axis;
  (centreHigh - centreLow).maxCoeff(&axis);
  // Split at the middle of the centroids' extent (one linear pass); at the
  // median when that leaves a side empty or nearly so.
  const double middle = 0.5 * (centreLow[axis] + centreHigh[axis]);
  auto begin = items.begin() + first, end = items.begin() + first + count;
  int half = static_cast<int>(
    std::partition(begin, end, [&](const BuildItem& item) { return item.centroid[axis] < middle; }) - begin);
  if (half < count / 8 || half > count - count / 8)
  {
    half = count / 2;
    std::nth_element(begin, begin + half, end,
      [&](const BuildItem& a, const BuildItem& b) { return a.centroid[axis] < b.centroid[axis]; });
  }
  const int left = this->Build(items, first, half, depth + 1);
  const int right = this->Build(items, first + half, count - half, depth + 1);
  this->Nodes[index].left = left;
  this->Nodes[index].right = right;
  return index;
}

void TriangleTree::LeafBox(Node& node) const
{
  node.low = Eigen::Vector3d::Constant(std::numeric_limits<double>::max());
  node.high = -node.low;
  for (int i = node.pointFirst; i < node.pointFirst + node.pointCount; ++i)
  {
    const Eigen::Vector3d p = this->Surface.points.row(this->LeafPoints[i]).transpose();
    node.low = node.low.cwiseMin(p);
    node.high = node.high.cwiseMax(p);
  }
}

void TriangleTree::Refit(const Points& points)
{
  if (points.rows() != this->Surface.points.rows())
  {
    throw InputError("TriangleTree::Refit needs the same number of points as the tree was built with");
  }
  this->Surface.points = points;
  this->GridDistance.clear(); // the distances were the old surface's
  this->UpdateBoxes();
  this->Size = (points.colwise().maxCoeff() - points.colwise().minCoeff()).norm();
}

void TriangleTree::BuildDistanceGrid(int nodes)
{
  this->GridDistance.clear();
  if (!(this->Size > 0) || !std::isfinite(this->Size))
  {
    return; // a surface of one point (or none finite): no grid, the queries search
  }
  // A flat box gets a hundredth of the surface's size across, so that the cells stay few.
  const Eigen::Vector3d box = (this->Nodes[0].high - this->Nodes[0].low).cwiseMax(0.01 * this->Size);
  this->GridCell = std::cbrt(box.prod() / std::max(nodes, 8));
  this->GridOrigin = this->Nodes[0].low - Eigen::Vector3d::Constant(this->GridCell);
  const Eigen::Vector3d extent = box + Eigen::Vector3d::Constant(2 * this->GridCell);
  for (int axis = 0; axis < 3; ++axis)
  {
    this->GridCount[size_t(axis)] = static_cast<int>(std::ceil(extent[axis] / this->GridCell)) + 1;
  }
  const Eigen::Index total = Eigen::Index(this->GridCount[0]) * this->GridCount[1] * this->GridCount[2];
  std::vector<float> distance(size_t(total), 0.0F);
#pragma omp parallel for schedule(dynamic, 256)
  for (Eigen::Index node = 0; node < total; ++node)
  {
    const Eigen::Index i = node % this->GridCount[0];
    const Eigen::Index j = (node / this->GridCount[0]) % this->GridCount[1];
    const Eigen::Index k = node / (Eigen::Index(this->GridCount[0]) * this->GridCount[1]);
    const Eigen::Vector3d x = this->GridOrigin + this->GridCell * Eigen::Vector3d(double(i), double(j), double(k));
    const double d = this->ClosestPoint(x).distance;
    distance[size_t(node)] = static_cast<float>(this->Inside(x) ? -d : d);
  }
  this->GridDistance = std::move(distance);
}

std::optional<std::pair<double, double>> TriangleTree::SignedDistanceBounds(const Eigen::Vector3d& p) const
{
  if (this->GridDistance.empty())
  {
    return std::nullopt;
  }
  std::array<Eigen::Index, 3> at{};
  for (int axis = 0; axis < 3; ++axis)
  {
    const double u = std::round((p[axis] - this->GridOrigin[axis]) / this->GridCell);
    if (!(u >= 0 && u < this->GridCount[size_t(axis)]))
    {
      return std::make_pair(this->GridCell, std::numeric_limits<double>::infinity());
    }
    at[size_t(axis)] = static_cast<Eigen::Index>(u);
  }
  const Eigen::Vector3d node =
    this->GridOrigin + this->GridCell * Eigen::Vector3d(double(at[0]), double(at[1]), double(at[2]));
  const double slack = (p - node).norm() * (1 + 1e-6) + 1e-9 * this->GridCell; // the float's rounding too
  const double d = this->GridDistance[size_t((at[2] * this->GridCount[1] + at[1]) * this->GridCount[0] + at[0])];
  return std::make_pair(d - slack - 1e-6 * std::abs(d), d + slack + 1e-6 * std::abs(d));
}

void TriangleTree::UpdateBoxes()
{
  // Children come after their parent (pre-order build): walk backwards.
  for (auto node = this->Nodes.rbegin(); node != this->Nodes.rend(); ++node)
  {
    if (node->left < 0)
    {
      this->LeafBox(*node);
    }
    else
    {
      node->low = this->Nodes[node->left].low.cwiseMin(this->Nodes[node->right].low);
      node->high = this->Nodes[node->left].high.cwiseMax(this->Nodes[node->right].high);
    }
  }
}

template<typename Visit>
void TriangleTree::ForTrianglesNearSegment(
  const Eigen::Vector3d& from, const Eigen::Vector3d& direction, const double& limit, Visit&& visit) const
{
  // `limit` is read at every box: a caller may shorten the segment as it goes.
  const Eigen::Vector3d inverse = direction.cwiseInverse();
  NodeStack<> stack;
  stack.Push(0);
  while (!stack.Empty())
  {
    const Node& node = this->Nodes[stack.Pop()];
    if (!SegmentMeetsBox(from, inverse, limit, node.low, node.high))
    {
      continue;
    }
    if (node.left >= 0)
    {
      stack.Push(node.left);
      stack.Push(node.right);
      continue;
    }
    for (int i = node.first; i < node.first + node.count; ++i)
    {
      visit(this->Order[i]);
    }
  }
}

template<typename Accept>
std::optional<TriangleTree::Hit> TriangleTree::FirstHitWhere(
  const Eigen::Vector3d& from, const Eigen::Vector3d& direction, Accept&& accepted) const
{
  std::optional<Hit> best;
  double limit = 1.0;
  this->ForTrianglesNearSegment(from, direction, limit, [&](Eigen::Index t) {
    double t01, u, v;
    if (IntersectLineTriangle(
          from, direction, this->Corner(t, 0), this->Corner(t, 1), this->Corner(t, 2), 0.0, t01, u, v) &&
      t01 >= 0 && t01 <= limit && accepted(t))
    {
      limit = t01;
      best = Hit{ t01, t, from + t01 * direction };
    }
  });
  return best;
}

std::optional<TriangleTree::Hit> TriangleTree::FirstHit(const Eigen::Vector3d& from, const Eigen::Vector3d& to) const
{
  return this->FirstHitWhere(from, to - from, [](Eigen::Index) { return true; });
}

std::optional<TriangleTree::Hit> TriangleTree::FirstEntry(const Eigen::Vector3d& from, const Eigen::Vector3d& to) const
{
  const Eigen::Vector3d direction = to - from;
  return this->FirstHitWhere(from, direction, [&](Eigen::Index t) { return direction.dot(this->Normal(t)) < 0; });
}

int TriangleTree::Crossings(const Eigen::Vector3d& from, const Eigen::Vector3d& to) const
{
  return this->SegmentCrossings(from, to - from, 0.0).crossings;
}

TriangleTree::CrossingCount TriangleTree::CountCrossings(
  const Eigen::Vector3d& origin, const Eigen::Vector3d& direction) const
{
  // A segment just long enough to leave the surface's box (slab exits).
  double exit = std::numeric_limits<double>::max();
  for (int axis = 0; axis < 3; ++axis)
  {
    if (direction[axis] != 0)
    {
      const double bound = direction[axis] > 0 ? this->Nodes[0].high[axis] : this->Nodes[0].low[axis];
      exit = std::min(exit, (bound - origin[axis]) / direction[axis]);
    }
  }
  const Eigen::Vector3d d = (std::max(exit, 0.0) + 1e-3 * this->Size) * direction;
  return this->SegmentCrossings(origin, d, 1e-9);
}

TriangleTree::CrossingCount TriangleTree::SegmentCrossings(
  const Eigen::Vector3d& from, const Eigen::Vector3d& d, double edgeTolerance) const
{
  CrossingCount count;
  this->ForTrianglesNearSegment(from, d, 1.0, [&](Eigen::Index t) {
    double t01, u, v;
    const Eigen::Vector3d a = this->Corner(t, 0), b = this->Corner(t, 1), c = this->Corner(t, 2);
    if (!IntersectLineTriangle(from, d, a, b, c, edgeTolerance, t01, u, v) || t01 < 0 || t01 > 1)
    {
      return;
    }
    if (u < edgeTolerance || v < edgeTolerance || u + v > 1 - edgeTolerance)
    {
      count.grazed = true; // through an edge or a point: this ray cannot be trusted
    }
    ++count.crossings;
    count.leavingMinusEntering += (b - a).cross(c - a).dot(d) > 0 ? 1 : -1;
  });
  return count;
}

std::array<Eigen::Vector3d, 6> TriangleTree::RayDirections(const Eigen::Vector3d& p) const
{
  // Towards the nearest faces of the surface's box, where a ray leaves it soonest and so meets
  // the fewest boxes of the tree; each tilted off its axis by fixed, unremarkable amounts so that
  // no ray runs along the edges of a mesh aligned with the axes.
  const Eigen::Vector3d& low = this->Nodes[0].low;
  const Eigen::Vector3d& high = this->Nodes[0].high;
  std::array<std::pair<double, int>, 6> faces; // distance, 2 * axis + (1 towards high)
  for (int axis = 0; axis < 3; ++axis)
  {
    faces[2 * axis] = { p[axis] - low[axis], 2 * axis };
    faces[2 * axis + 1] = { high[axis] - p[axis], 2 * axis + 1 };
  }
  std::sort(faces.begin(), faces.end());
  static const Eigen::Vector3d tilts[] = { Eigen::Vector3d(0.1234, 0.0871, 0.1057),
    Eigen::Vector3d(-0.0963, 0.1311, -0.0729), Eigen::Vector3d(0.1102, -0.0658, -0.1247),
    Eigen::Vector3d(-0.1189, -0.1046, 0.0902), Eigen::Vector3d(0.0817, 0.1153, -0.1361),
    Eigen::Vector3d(-0.0744, -0.1278, -0.0986) };
  std::array<Eigen::Vector3d, 6> directions;
  for (size_t k = 0; k < 6; ++k)
  {
    const int axis = faces[k].second / 2;
    directions[k] = tilts[k];
    directions[k][axis] = faces[k].second % 2 ? 1.0 : -1.0;
    directions[k].normalize();
  }
  return directions;
}

bool TriangleTree::Inside(const Eigen::Vector3d& p) const
{
  if (!this->InBounds(p))
  {
    return false; // a closed surface lies within its box
  }
  int votesInside = 0, votes = 0;
  for (const Eigen::Vector3d& direction : this->RayDirections(p))
  {
    const CrossingCount count = this->CountCrossings(p, direction);
    if (count.grazed)
    {
      continue;
    }
    votesInside += count.crossings % 2;
    ++votes;
    if (votes == 3 || (votes == 2 && votesInside != 1))
    {
      break; // a majority of three: two that agree decide
    }
  }
  if (votes == 0)
  {
    return WindingNumber(this->Surface.points, this->Surface.triangles, p) > 0.5; // every ray grazed
  }
  return 2 * votesInside > votes;
}

int TriangleTree::Winding(const Eigen::Vector3d& p) const
{
  if (!this->InBounds(p))
  {
    return 0;
  }
  std::array<int, 6> said{};
  int rays = 0;
  for (const Eigen::Vector3d& direction : this->RayDirections(p))
  {
    const CrossingCount count = this->CountCrossings(p, direction);
    if (count.grazed)
    {
      continue;
    }
    said[size_t(rays++)] = count.leavingMinusEntering;
    for (int other = 0; other + 1 < rays; ++other)
    {
      if (said[size_t(other)] == count.leavingMinusEntering)
      {
        return count.leavingMinusEntering; // two rays that agree decide
      }
    }
  }
  // Every ray grazed, or no two agreed: the sum over every triangle.
  return static_cast<int>(std::lround(WindingNumber(this->Surface.points, this->Surface.triangles, p)));
}

TriangleTree::Closest TriangleTree::ClosestPoint(const Eigen::Vector3d& p, double within, Eigen::Index hint) const
{
  Closest best;
  double bestSquared = within < std::numeric_limits<double>::max() ? within * within : within;
  if (hint >= 0 && hint < this->Surface.triangles.rows())
  {
    const double d = PointTriangleDistance(p, this->Corner(hint, 0), this->Corner(hint, 1), this->Corner(hint, 2));
    if (d * d < bestSquared)
    {
      bestSquared = d * d;
      best.distance = d;
      best.triangle = hint;
    }
  }
  // Each node with its box's distance, found when its parent ordered its children (not again).
  NodeStack<std::pair<int, double>> stack;
  stack.Push({ 0, BoxDistanceSquared(p, this->Nodes[0].low, this->Nodes[0].high) });
  while (!stack.Empty())
  {
    const auto [index, boxSquared] = stack.Pop();
    if (boxSquared >= bestSquared)
    {
      continue;
    }
    const Node& node = this->Nodes[index];
    if (node.left >= 0)
    {
      // Nearer child last, so it is visited first.
      const Node& left = this->Nodes[node.left];
      const Node& right = this->Nodes[node.right];
      const double toLeft = BoxDistanceSquared(p, left.low, left.high);
      const double toRight = BoxDistanceSquared(p, right.low, right.high);
      if (toLeft < toRight)
      {
        stack.Push({ node.right, toRight });
        stack.Push({ node.left, toLeft });
      }
      else
      {
        stack.Push({ node.left, toLeft });
        stack.Push({ node.right, toRight });
      }
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
