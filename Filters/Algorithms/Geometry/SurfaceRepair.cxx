// SPDX-License-Identifier: BSD-3-Clause
#include "Geometry/SurfaceRepair.h"

#include "Geometry/MeshChecks.h"
#include "Geometry/TriangleGrid.h"
#include "Geometry/TriangleIntersection.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <map>
#include <numeric>
#include <queue>
#include <sstream>
#include <unordered_map>

namespace md
{
namespace
{
using Triangle = std::array<std::int64_t, 3>;

std::uint64_t EdgeKey(std::int64_t a, std::int64_t b)
{
  const auto lo = static_cast<std::uint64_t>(std::min(a, b));
  const auto hi = static_cast<std::uint64_t>(std::max(a, b));
  return (lo << 32) | hi;
}

/// Points of a surface closer than this fraction of its size are one point (rounding noise, e.g. a
/// scan's duplicate points exported in float or moved by 1e-7; scans' point spacing is ~1e-2 of
/// their size).
constexpr double kMergeTolerance = 1e-5;

struct TriangleHash
{
  size_t operator()(const Triangle& t) const
  {
    return static_cast<size_t>(t[0]) * 73856093u ^ static_cast<size_t>(t[1]) * 19349663u ^
      static_cast<size_t>(t[2]) * 83492791u;
  }
};

using EdgeMap = std::unordered_map<std::uint64_t, std::vector<int>>;

/// Triangles incident to each undirected edge.
EdgeMap EdgeFaces(const std::vector<Triangle>& triangles)
{
  EdgeMap edges;
  edges.reserve(triangles.size() * 2);
  for (int t = 0; t < static_cast<int>(triangles.size()); ++t)
  {
    for (int k = 0; k < 3; ++k)
    {
      edges[EdgeKey(triangles[t][k], triangles[t][(k + 1) % 3])].push_back(t);
    }
  }
  return edges;
}

/// Does triangle t walk its edge from a to b?
bool WalksFrom(const Triangle& t, std::int64_t a, std::int64_t b)
{
  for (int k = 0; k < 3; ++k)
  {
    if (t[k] == a && t[(k + 1) % 3] == b)
    {
      return true;
    }
  }
  return false;
}

std::int64_t ThirdPoint(const Triangle& t, std::int64_t a, std::int64_t b)
{
  for (std::int64_t p : t)
  {
    if (p != a && p != b)
    {
      return p;
    }
  }
  return -1;
}
}

namespace
{
using Pairing = std::map<std::pair<int, std::uint64_t>, int>; // (triangle, edge) -> triangle

/// For every point, the smallest index among the points used by `triangles` that are joined to it by
/// steps shorter than `tolerance` (itself when there is none): the representative of its cluster,
/// whatever the order of the points. A grid of cells `tolerance` wide finds the pairs.
std::vector<std::int64_t> ClusterNearPoints(const Points& points, const Triangles& triangles, double tolerance)
{
  const auto pointCount = static_cast<std::int64_t>(points.rows());
  std::vector<std::int64_t> root(static_cast<size_t>(pointCount));
  std::iota(root.begin(), root.end(), std::int64_t{ 0 });
  std::vector<char> used(static_cast<size_t>(pointCount), 0);
  for (Eigen::Index i = 0; i < triangles.size(); ++i)
  {
    used[triangles.data()[i]] = 1;
  }
  auto find = [&](std::int64_t i) {
    while (root[i] != i)
    {
      root[i] = root[root[i]];
      i = root[i];
    }
    return i;
  };
  // Cells counted from the lowest corner: their indices stay small whatever the coordinates.
  const Eigen::RowVector3d corner =
    points.rows() > 0 ? Eigen::RowVector3d(points.colwise().minCoeff()) : Eigen::RowVector3d::Zero();
  auto cellOf = [&](std::int64_t i, long offset) {
    std::array<long, 3> c;
    for (int k = 0; k < 3; ++k)
    {
      c[k] = static_cast<long>(std::floor((points(i, k) - corner[k]) / tolerance)) + offset;
    }
    return c;
  };
  std::unordered_map<std::uint64_t, std::vector<std::int64_t>> grid;
  for (std::int64_t i = 0; i < pointCount; ++i)
  {
    if (used[i])
    {
      const std::array<long, 3> c = cellOf(i, 0);
      grid[GridCellKey(c[0], c[1], c[2])].push_back(i);
    }
  }
  for (std::int64_t i = 0; i < pointCount; ++i)
  {
    if (!used[i])
    {
      continue;
    }
    ForEachGridCell(cellOf(i, -1), cellOf(i, 1), [&](std::uint64_t cell) {
      const auto found = grid.find(cell);
      if (found == grid.end())
      {
        return;
      }
      for (std::int64_t j : found->second)
      {
        if (j > i && (points.row(i) - points.row(j)).squaredNorm() < tolerance * tolerance)
        {
          const std::int64_t a = find(i), b = find(j);
          root[std::max(a, b)] = std::min(a, b);
        }
      }
    });
  }
  for (std::int64_t i = 0; i < pointCount; ++i)
  {
    root[i] = find(i);
  }
  return root;
}

/// Merges points closer than `tolerance` (`representative`: each input point's surviving twin, the
/// lowest index of its cluster; the merged points at other coordinates are added to
/// report.pointsToEnclose) and drops degenerate and duplicate triangles, and back-to-back ones
/// unless `keepFins`.
std::vector<Triangle> MergeAndDeduplicate(const TriangleMesh& surface, double tolerance,
  std::vector<std::int64_t>& representative, RepairReport& report, bool keepFins = false)
{
  const auto pointCount = static_cast<std::int64_t>(surface.points.rows());
  representative = ClusterNearPoints(surface.points, surface.triangles, tolerance);
  std::vector<Eigen::RowVector3d> movedByMerge;
  for (std::int64_t i = 0; i < pointCount; ++i)
  {
    if (representative[i] != i && surface.points.row(i) != surface.points.row(representative[i]))
    {
      ++report.nearDuplicatePointsMerged;
      movedByMerge.push_back(surface.points.row(i));
    }
  }
  report.AddPointsToEnclose(movedByMerge);
  std::vector<bool> used(static_cast<size_t>(pointCount), false);
  std::vector<bool> mergedAway(static_cast<size_t>(pointCount), false);
  std::vector<Triangle> triangles;
  // Degenerate triangles go; of two triangles on the same points, a copy goes,
  // and a back-to-back pair (a fin of no thickness, e.g. what is left of a
  // collapsed bubble) goes entirely.
  std::vector<Triangle> kept;
  {
    std::unordered_map<Triangle, int, TriangleHash> seen; // sorted points -> index in kept
    seen.reserve(static_cast<size_t>(surface.triangles.rows()));
    std::vector<bool> fin;
    for (Eigen::Index t = 0; t < surface.triangles.rows(); ++t)
    {
      Triangle tri;
      for (int k = 0; k < 3; ++k)
      {
        const std::int64_t original = surface.triangles(t, k);
        tri[k] = representative[original];
        mergedAway[original] = mergedAway[original] || tri[k] != original;
      }
      if (tri[0] == tri[1] || tri[1] == tri[2] || tri[0] == tri[2])
      {
        ++report.degenerateTrianglesRemoved;
        continue;
      }
      Triangle sorted = tri;
      std::sort(sorted.begin(), sorted.end());
      auto found = seen.find(sorted);
      if (found == seen.end())
      {
        seen.emplace(sorted, static_cast<int>(kept.size()));
        kept.push_back(tri);
        fin.push_back(false);
        continue;
      }
      const Triangle& first = kept[found->second];
      const bool sameWay = WalksFrom(first, tri[0], tri[1]);
      if (sameWay)
      {
        ++report.duplicateTrianglesRemoved;
      }
      else if (keepFins)
      {
        kept.push_back(tri);
        fin.push_back(false);
      }
      else if (!fin[found->second])
      {
        fin[found->second] = true;
        report.finTrianglesRemoved += 2;
      }
    }
    for (size_t t = 0; t < kept.size(); ++t)
    {
      if (!fin[t])
      {
        triangles.push_back(kept[t]);
      }
    }
    for (const Triangle& tri : triangles)
    {
      for (std::int64_t p : tri)
      {
        used[p] = true;
      }
    }
  }
  for (std::int64_t i = 0; i < pointCount; ++i)
  {
    report.duplicatePointsMerged += mergedAway[i] ? 1 : 0;
    report.unusedPointsRemoved += (!used[i] && !mergedAway[i]) ? 1 : 0;
  }
  return triangles;
}

/// Holes cannot be closed safely.
void RequireClosed(const EdgeMap& edges)
{
  std::int64_t boundary = 0;
  for (const auto& entry : edges)
  {
    boundary += entry.second.size() == 1 ? 1 : 0;
  }
  if (boundary > 0)
  {
    throw InputError("the surface is open: " + std::to_string(boundary) +
      " edges belong to a single triangle (holes); a muscle must be a closed surface");
  }
}

/// Orients the triangles consistently by walking across manifold edges;
/// returns the part each triangle was reached in (`parts` of them).
std::vector<int> OrientConsistently(
  std::vector<Triangle>& triangles, const EdgeMap& edges, int& parts, RepairReport& report)
{
  std::vector<int> component(triangles.size(), -1);
  int components = 0;
  for (size_t seed = 0; seed < triangles.size(); ++seed)
  {
    if (component[seed] >= 0)
    {
      continue;
    }
    std::queue<int> queue;
    queue.push(static_cast<int>(seed));
    component[seed] = components;
    while (!queue.empty())
    {
      const int t = queue.front();
      queue.pop();
      for (int k = 0; k < 3; ++k)
      {
        const std::int64_t a = triangles[t][k], b = triangles[t][(k + 1) % 3];
        const std::vector<int>& around = edges.at(EdgeKey(a, b));
        if (around.size() != 2)
        {
          continue;
        }
        const int other = around[0] == t ? around[1] : around[0];
        if (component[other] >= 0)
        {
          continue;
        }
        if (WalksFrom(triangles[other], a, b)) // must walk b -> a to agree with t
        {
          std::swap(triangles[other][1], triangles[other][2]);
          ++report.trianglesReoriented;
        }
        component[other] = components;
        queue.push(other);
      }
    }
    ++components;
  }
  parts = components;
  return component;
}

/// Non-manifold edges: pairs the triangles around each so that every pair
/// bounds one lobe. Rotating about the edge a -> b, a triangle walking b -> a
/// has its lobe on the side of increasing angle, one walking a -> b on the side
/// of decreasing angle; a lobe runs from the first to the next.
Pairing PairTrianglesAtPinches(
  const Points& points, const std::vector<Triangle>& triangles, const EdgeMap& edges, RepairReport& report)
{
  Pairing pairing;
  for (const auto& entry : edges)
  {
    if (entry.second.size() <= 2)
    {
      continue;
    }
    ++report.nonManifoldEdgesSplit;
    const std::uint64_t key = entry.first;
    const auto a = static_cast<std::int64_t>(key >> 32);
    const auto b = static_cast<std::int64_t>(key & 0xffffffffu);
    const Eigen::Vector3d pa = points.row(a).transpose(), axis = (points.row(b).transpose() - pa).normalized();
    Eigen::Vector3d u = axis.unitOrthogonal();
    const Eigen::Vector3d w = axis.cross(u);
    struct Around
    {
      double angle;
      int face;
      bool walksBA;
    };
    std::vector<Around> around;
    for (int f : entry.second)
    {
      const Eigen::Vector3d d = points.row(ThirdPoint(triangles[f], a, b)).transpose() - pa;
      around.push_back({ std::atan2(d.dot(w), d.dot(u)), f, WalksFrom(triangles[f], b, a) });
    }
    std::sort(around.begin(), around.end(), [](const Around& x, const Around& y) { return x.angle < y.angle; });
    const size_t count = around.size();
    for (size_t i = 0; i < count; ++i)
    {
      if (!around[i].walksBA)
      {
        continue;
      }
      for (size_t step = 1; step < count; ++step)
      {
        const Around& next = around[(i + step) % count];
        if (!next.walksBA && !pairing.count({ next.face, key }))
        {
          pairing[{ around[i].face, key }] = next.face;
          pairing[{ next.face, key }] = around[i].face;
          break;
        }
      }
    }
  }

  return pairing;
}

/// Points whose triangles form several fans (pinches) get one copy per extra
/// fan; the point and its copies move `separation` into their own lobes, and
/// where the point was is kept in report.pointsToEnclose.
void SplitPinchedPoints(Points& points, std::vector<Triangle>& triangles, const EdgeMap& edges, const Pairing& pairing,
  const Points& original, double separation, RepairReport& report)
{
  // Neighbour of triangle t across its edge k, or -1 where the edge is cut.
  auto neighbour = [&](int t, int k) {
    const std::int64_t a = triangles[t][k], b = triangles[t][(k + 1) % 3];
    const std::uint64_t key = EdgeKey(a, b);
    const std::vector<int>& around = edges.at(key);
    if (around.size() == 2)
    {
      return around[0] == t ? around[1] : around[0];
    }
    auto found = pairing.find({ t, key });
    return found == pairing.end() ? -1 : found->second;
  };

  std::vector<std::vector<int>> facesOfPoint(static_cast<size_t>(points.rows()));
  for (int t = 0; t < static_cast<int>(triangles.size()); ++t)
  {
    for (std::int64_t p : triangles[t])
    {
      facesOfPoint[p].push_back(t);
    }
  }
  // First every point's fans, on the triangles as they are (the neighbour
  // look-up goes by the original point indices); then the copies.
  struct Split
  {
    std::int64_t point;
    std::vector<std::pair<int, int>> fanOfTriangle; // (triangle, fan)
    std::vector<Eigen::Vector3d> fanNormal;
  };
  std::vector<Split> splits;
  for (std::int64_t p = 0; p < static_cast<std::int64_t>(facesOfPoint.size()); ++p)
  {
    std::map<int, int> fanOf; // triangle -> fan
    int fans = 0;
    for (int start : facesOfPoint[p])
    {
      if (fanOf.count(start))
      {
        continue;
      }
      std::queue<int> queue;
      queue.push(start);
      fanOf[start] = fans;
      while (!queue.empty())
      {
        const int t = queue.front();
        queue.pop();
        for (int k = 0; k < 3; ++k)
        {
          if (triangles[t][k] != p && triangles[t][(k + 1) % 3] != p)
          {
            continue; // only edges through p join the triangles of a fan
          }
          const int other = neighbour(t, k);
          if (other >= 0 && !fanOf.count(other))
          {
            fanOf[other] = fans;
            queue.push(other);
          }
        }
      }
      ++fans;
    }
    if (fans < 2)
    {
      continue;
    }
    Split split{ p, {}, std::vector<Eigen::Vector3d>(static_cast<size_t>(fans), Eigen::Vector3d::Zero()) };
    for (const auto& [t, fan] : fanOf)
    {
      const Triangle& tri = triangles[t];
      split.fanNormal[fan] += (points.row(tri[1]) - points.row(tri[0]))
                                .transpose()
                                .cross((points.row(tri[2]) - points.row(tri[0])).transpose());
      split.fanOfTriangle.emplace_back(t, fan);
    }
    splits.push_back(std::move(split));
  }
  for (const Split& split : splits)
  {
    const std::int64_t p = split.point;
    const Eigen::RowVector3d from = original.row(p);
    report.AddPointsToEnclose({ from });
    points.row(p) = from - separation * split.fanNormal[0].normalized().transpose();
    for (int fan = 1; fan < static_cast<int>(split.fanNormal.size()); ++fan)
    {
      const std::int64_t copy = points.rows();
      points.conservativeResize(copy + 1, 3);
      points.row(copy) = from - separation * split.fanNormal[fan].normalized().transpose();
      ++report.pointsDuplicatedAtPinches;
      for (const auto& [t, f] : split.fanOfTriangle)
      {
        if (f == fan)
        {
          std::replace(triangles[t].begin(), triangles[t].end(), p, copy);
        }
      }
    }
  }
}

/// The mesh on the points its triangles use; input points that it no longer
/// carries are added to report.pointsToEnclose.
TriangleMesh Compact(const Points& points, const std::vector<Triangle>& triangles, const TriangleMesh& surface,
  const std::vector<std::int64_t>& representative, RepairReport& report)
{
  const auto pointCount = static_cast<std::int64_t>(surface.points.rows());
  std::vector<std::int64_t> newIndex(static_cast<size_t>(points.rows()), -1);
  std::int64_t next = 0;
  for (const Triangle& t : triangles)
  {
    for (std::int64_t p : t)
    {
      if (newIndex[p] < 0)
      {
        newIndex[p] = next++;
      }
    }
  }
  // Points the input's triangles used but the repaired surface dropped.
  {
    std::vector<char> usedInInput(static_cast<size_t>(pointCount), 0);
    for (Eigen::Index t = 0; t < surface.triangles.rows(); ++t)
    {
      for (int k = 0; k < 3; ++k)
      {
        usedInInput[surface.triangles(t, k)] = 1;
      }
    }
    std::vector<Eigen::RowVector3d> dropped;
    for (std::int64_t i = 0; i < pointCount; ++i)
    {
      if (usedInInput[i] && newIndex[representative[i]] < 0)
      {
        dropped.push_back(surface.points.row(i));
      }
    }
    report.AddPointsToEnclose(dropped);
  }
  TriangleMesh out;
  out.points.resize(next, 3);
  for (std::int64_t p = 0; p < points.rows(); ++p)
  {
    if (newIndex[p] >= 0)
    {
      out.points.row(newIndex[p]) = points.row(p);
    }
  }
  out.triangles.resize(static_cast<Eigen::Index>(triangles.size()), 3);
  for (size_t t = 0; t < triangles.size(); ++t)
  {
    for (int k = 0; k < 3; ++k)
    {
      out.triangles(static_cast<Eigen::Index>(t), k) = newIndex[triangles[t][k]];
    }
  }

  return out;
}

/// Each part outwards (positive volume).
void OrientPartsOutwards(TriangleMesh& out, const std::vector<int>& component, int components, RepairReport& report)
{
  std::vector<double> partVolume(static_cast<size_t>(components), 0.0);
  for (Eigen::Index t = 0; t < out.triangles.rows(); ++t)
  {
    const Eigen::Vector3d a = out.points.row(out.triangles(t, 0)), b = out.points.row(out.triangles(t, 1)),
                          c = out.points.row(out.triangles(t, 2));
    partVolume[component[t]] += a.cross(b).dot(c) / 6.0;
  }
  for (Eigen::Index t = 0; t < out.triangles.rows(); ++t)
  {
    if (partVolume[component[t]] < 0)
    {
      std::swap(out.triangles(t, 1), out.triangles(t, 2));
      ++report.trianglesReoriented;
    }
  }
}
}

void RepairReport::AddPointsToEnclose(const std::vector<Eigen::RowVector3d>& rows)
{
  const Eigen::Index old = this->pointsToEnclose.rows();
  this->pointsToEnclose.conservativeResize(old + static_cast<Eigen::Index>(rows.size()), 3);
  for (size_t i = 0; i < rows.size(); ++i)
  {
    this->pointsToEnclose.row(old + static_cast<Eigen::Index>(i)) = rows[i];
  }
}

std::string RepairReport::Describe() const
{
  std::ostringstream out;
  const char* separator = "";
  auto say = [&](std::int64_t count, const char* what) {
    if (count > 0)
    {
      out << separator << what << " " << count;
      separator = ", ";
    }
  };
  say(unusedPointsRemoved, "removed unused points:");
  say(duplicatePointsMerged, "merged duplicate points:");
  if (nearDuplicatePointsMerged > 0)
  {
    out << separator << "of them " << nearDuplicatePointsMerged << " closer than " << mergeTolerance
        << " (1e-5 of the surface's size) but not at the same coordinates";
    separator = ", ";
  }
  say(degenerateTrianglesRemoved, "removed degenerate triangles:");
  say(duplicateTrianglesRemoved, "removed duplicate triangles:");
  say(finTrianglesRemoved, "removed back-to-back triangles (fins of no thickness):");
  say(trianglesReoriented, "reoriented triangles:");
  say(nonManifoldEdgesSplit, "split non-manifold edges:");
  say(pointsDuplicatedAtPinches, "points duplicated at those pinches:");
  say(selfIntersectionsUntangled, "self-intersecting triangle pairs undone:");
  if (pointsSmoothed > 0)
  {
    out << separator << "by smoothing " << pointsSmoothed << " points (moved at most " << largestSmoothingShift << ")";
    separator = ", ";
  }
  say(selfIntersectionsLeft, "self-intersecting triangle pairs left:");
  say(enclosedPiecesRemoved, "removed pieces lying inside another:");
  return out.str();
}

TriangleMesh RepairClosedSurface(const TriangleMesh& surface, RepairReport& report)
{
  report = RepairReport{};
  report.pointsToEnclose.resize(0, 3);
  if (!AllFinite(surface.points))
  {
    throw InputError("the surface has non-finite (NaN or infinite) coordinates");
  }
  const auto pointCount = static_cast<std::int64_t>(surface.points.rows());
  for (Eigen::Index t = 0; t < surface.triangles.rows(); ++t)
  {
    for (int k = 0; k < 3; ++k)
    {
      if (surface.triangles(t, k) < 0 || surface.triangles(t, k) >= pointCount)
      {
        throw InputError("a triangle refers to a point that does not exist");
      }
    }
  }
  const double size = BoxDiagonal(UsedPoints(surface));
  report.mergeTolerance = kMergeTolerance * size;
  std::vector<std::int64_t> representative;
  std::vector<Triangle> triangles = MergeAndDeduplicate(surface, report.mergeTolerance, representative, report);
  if (triangles.size() < 4)
  {
    throw InputError("the surface has fewer than 4 usable triangles once degenerate, duplicate and "
                     "back-to-back ones are removed: it is flat or degenerate");
  }
  const EdgeMap edges = EdgeFaces(triangles);
  RequireClosed(edges);
  int parts = 0;
  const std::vector<int> part = OrientConsistently(triangles, edges, parts, report);
  Points points = surface.points;
  const Pairing pairing = PairTrianglesAtPinches(points, triangles, edges, report);
  SplitPinchedPoints(points, triangles, edges, pairing, surface.points, 1e-6 * size, report);
  TriangleMesh out = Compact(points, triangles, surface, representative, report);
  OrientPartsOutwards(out, part, parts, report);
  UntangleSelfIntersections(out, report);
  RemoveEnclosedPieces(out, report);
  const double volume = SignedVolume(out.points, out.triangles);
  if (!(volume > kDegenerateShare * size * size * size))
  {
    throw InputError("the surface encloses no volume (it is flat or degenerate)");
  }
  return out;
}

Triangles WeldedTriangles(const TriangleMesh& surface, std::vector<std::int64_t>& representative)
{
  RepairReport unused;
  const double tolerance = kMergeTolerance * BoxDiagonal(UsedPoints(surface));
  const std::vector<Triangle> kept = MergeAndDeduplicate(surface, tolerance, representative, unused, true);
  Triangles triangles(static_cast<Eigen::Index>(kept.size()), 3);
  for (size_t t = 0; t < kept.size(); ++t)
  {
    for (int k = 0; k < 3; ++k)
    {
      triangles(static_cast<Eigen::Index>(t), k) = kept[t][k];
    }
  }
  return triangles;
}
}
