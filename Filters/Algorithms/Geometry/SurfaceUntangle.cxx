// SPDX-License-Identifier: BSD-3-Clause
// RepairClosedSurface's last steps (docs/DESIGN.md section 3): crossing triangles undone by
// smoothing, pieces inside other pieces removed.
#include "Geometry/SurfaceRepair.h"

#include "Geometry/MeshChecks.h"
#include "Geometry/TriangleGrid.h"
#include "Geometry/TriangleIntersection.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <numeric>
#include <queue>
#include <unordered_map>

namespace md
{
namespace
{
/// Moves smoothed points back towards where they were (all the way, half,
/// a quarter), wherever that makes no triangle cross another.
void RestoreTowardsOriginal(TriangleMesh& mesh, const Points& original, const std::vector<std::int64_t>& moved)
{
  std::vector<std::vector<Eigen::Index>> facesOf(static_cast<size_t>(mesh.points.rows()));
  for (Eigen::Index t = 0; t < mesh.triangles.rows(); ++t)
  {
    for (int k = 0; k < 3; ++k)
    {
      facesOf[mesh.triangles(t, k)].push_back(t);
    }
  }
  // A grid of triangle bounds, those of the moved points' triangles widened
  // by the largest move, so that a query finds every triangle a move can meet.
  double reach = 0;
  std::vector<char> movable(static_cast<size_t>(mesh.points.rows()), 0);
  for (std::int64_t p : moved)
  {
    reach = std::max(reach, (mesh.points.row(p) - original.row(p)).norm());
    movable[p] = 1;
  }
  auto bounds = [&](Eigen::Index t, Eigen::Vector3d& low, Eigen::Vector3d& high) {
    low = high = mesh.points.row(mesh.triangles(t, 0)).transpose();
    bool widen = false;
    for (int k = 0; k < 3; ++k)
    {
      low = low.cwiseMin(mesh.points.row(mesh.triangles(t, k)).transpose());
      high = high.cwiseMax(mesh.points.row(mesh.triangles(t, k)).transpose());
      widen = widen || movable[mesh.triangles(t, k)];
    }
    if (widen)
    {
      low.array() -= reach;
      high.array() += reach;
    }
  };
  TriangleGrid grid(TriangleGrid::CellSizeFor(mesh.points, mesh.triangles));
  for (Eigen::Index t = 0; t < mesh.triangles.rows(); ++t)
  {
    Eigen::Vector3d low, high;
    bounds(t, low, high);
    grid.Insert(static_cast<int>(t), low, high);
  }
  auto corners = [&](Eigen::Index t) {
    return std::array<Eigen::Vector3d, 3>{ mesh.points.row(mesh.triangles(t, 0)).transpose(),
      mesh.points.row(mesh.triangles(t, 1)).transpose(), mesh.points.row(mesh.triangles(t, 2)).transpose() };
  };
  auto ids = [&](Eigen::Index t) {
    return std::array<int, 3>{ static_cast<int>(mesh.triangles(t, 0)), static_cast<int>(mesh.triangles(t, 1)),
      static_cast<int>(mesh.triangles(t, 2)) };
  };
  auto exactBounds = [&](Eigen::Index t, Eigen::Vector3d& low, Eigen::Vector3d& high) {
    low = high = mesh.points.row(mesh.triangles(t, 0)).transpose();
    for (int k = 1; k < 3; ++k)
    {
      low = low.cwiseMin(mesh.points.row(mesh.triangles(t, k)).transpose());
      high = high.cwiseMax(mesh.points.row(mesh.triangles(t, k)).transpose());
    }
  };
  auto crossesNothing = [&](std::int64_t p) {
    for (Eigen::Index t : facesOf[p])
    {
      Eigen::Vector3d low, high;
      exactBounds(t, low, high);
      const bool clear = grid.ForEachCellIn(low, high, [&](const std::vector<int>& cell) {
        for (Eigen::Index u : cell)
        {
          if (u == t)
          {
            continue;
          }
          Eigen::Vector3d otherLow, otherHigh;
          exactBounds(u, otherLow, otherHigh);
          if ((otherLow.array() > high.array()).any() || (otherHigh.array() < low.array()).any())
          {
            continue;
          }
          if (TrianglesIntersect(corners(t), ids(t), corners(u), ids(u)))
          {
            return false;
          }
        }
        return true;
      });
      if (!clear)
      {
        return false;
      }
    }
    return true;
  };
  for (int sweep = 0; sweep < 3; ++sweep)
  {
    for (std::int64_t p : moved)
    {
      const Eigen::RowVector3d smoothed = mesh.points.row(p);
      for (double fraction : { 1.0, 0.5, 0.25 })
      {
        mesh.points.row(p) = smoothed + fraction * (original.row(p) - smoothed);
        if (crossesNothing(p))
        {
          break;
        }
        mesh.points.row(p) = smoothed;
      }
    }
  }
}
}

void UntangleSelfIntersections(TriangleMesh& mesh, RepairReport& report)
{
  auto pairs = FindSelfIntersections(mesh.points, mesh.triangles);
  if (pairs.empty())
  {
    return;
  }
  const auto initialPairs = static_cast<std::int64_t>(pairs.size());
  // Scans have a few crossing folds (at most 24 pairs in the LHDL muscles, 0.3 % of their
  // triangles); a surface crossing itself everywhere (vertex noise of a millimetre or more) would
  // be smoothed out of shape, and slowly: refused instead.
  if (initialPairs > std::max<std::int64_t>(50, mesh.triangles.rows() / 20))
  {
    throw InputError("the surface intersects itself in " + std::to_string(initialPairs) + " pairs of its " +
      std::to_string(mesh.triangles.rows()) +
      " triangles: too many to repair without changing its shape (is it very noisy?); smooth or remesh it");
  }
  const auto neighbours = PointNeighbours(mesh.triangles, mesh.points.rows());
  const Points original = mesh.points;
  std::vector<char> inRegion(static_cast<size_t>(mesh.points.rows()), 0);
  std::vector<std::int64_t> region;
  auto add = [&](std::int64_t p) {
    if (!inRegion[p])
    {
      inRegion[p] = 1;
      region.push_back(p);
    }
  };
  constexpr int rounds = 12;
  for (int round = 0; round < rounds && !pairs.empty(); ++round)
  {
    for (const auto& [s, t] : pairs)
    {
      for (int k = 0; k < 3; ++k)
      {
        add(mesh.triangles(s, k));
        add(mesh.triangles(t, k));
      }
    }
    if (round > 0)
    {
      // add() grows `region`: walk a copy.
      const std::vector<std::int64_t> current = region; // NOLINT(performance-unnecessary-copy-initialization)
      for (std::int64_t p : current)
      {
        for (std::int64_t q : neighbours[p])
        {
          add(q);
        }
      }
    }
    for (int iteration = 0; iteration < 10; ++iteration)
    {
      Points next = mesh.points;
      for (std::int64_t p : region)
      {
        Eigen::RowVector3d mean = Eigen::RowVector3d::Zero();
        for (std::int64_t q : neighbours[p])
        {
          mean += mesh.points.row(q);
        }
        next.row(p) = 0.5 * mesh.points.row(p) + 0.5 * mean / static_cast<double>(neighbours[p].size());
      }
      mesh.points = next;
    }
    pairs = FindSelfIntersections(mesh.points, mesh.triangles);
  }
  report.selfIntersectionsLeft = static_cast<std::int64_t>(pairs.size());
  report.selfIntersectionsUntangled = initialPairs - std::min(initialPairs, report.selfIntersectionsLeft);
  if (pairs.empty())
  {
    RestoreTowardsOriginal(mesh, original, region);
  }
  std::vector<Eigen::RowVector3d> movedFrom;
  for (std::int64_t p : region)
  {
    const double shift = (mesh.points.row(p) - original.row(p)).norm();
    if (shift > 0)
    {
      ++report.pointsSmoothed;
      movedFrom.push_back(original.row(p));
    }
    report.largestSmoothingShift = std::max(report.largestSmoothingShift, shift);
  }
  report.AddPointsToEnclose(movedFrom);
}

void RemoveEnclosedPieces(TriangleMesh& mesh, RepairReport& report)
{
  const auto neighbours = PointNeighbours(mesh.triangles, mesh.points.rows());
  std::vector<int> piece(static_cast<size_t>(mesh.points.rows()), -1);
  int pieces = 0;
  for (std::int64_t seed = 0; seed < mesh.points.rows(); ++seed)
  {
    if (piece[seed] >= 0)
    {
      continue;
    }
    std::queue<std::int64_t> queue;
    queue.push(seed);
    piece[seed] = pieces;
    while (!queue.empty())
    {
      const std::int64_t p = queue.front();
      queue.pop();
      for (std::int64_t q : neighbours[p])
      {
        if (piece[q] < 0)
        {
          piece[q] = pieces;
          queue.push(q);
        }
      }
    }
    ++pieces;
  }
  if (pieces < 2)
  {
    return;
  }
  std::vector<Triangles> trianglesOf(static_cast<size_t>(pieces));
  std::vector<std::vector<Eigen::Index>> rows(static_cast<size_t>(pieces));
  for (Eigen::Index t = 0; t < mesh.triangles.rows(); ++t)
  {
    rows[piece[mesh.triangles(t, 0)]].push_back(t);
  }
  for (int k = 0; k < pieces; ++k)
  {
    trianglesOf[k].resize(static_cast<Eigen::Index>(rows[k].size()), 3);
    for (size_t i = 0; i < rows[k].size(); ++i)
    {
      trianglesOf[k].row(static_cast<Eigen::Index>(i)) = mesh.triangles.row(rows[k][i]);
    }
  }
  std::vector<char> removed(static_cast<size_t>(pieces), 0);
  for (int k = 0; k < pieces; ++k)
  {
    for (int host = 0; host < pieces && !removed[k]; ++host)
    {
      if (host == k || removed[host])
      {
        continue;
      }
      bool inside = true;
      for (std::int64_t p = 0; p < mesh.points.rows() && inside; ++p)
      {
        if (piece[p] == k)
        {
          inside = WindingNumber(mesh.points, trianglesOf[host], mesh.points.row(p).transpose()) > 0.5;
        }
      }
      removed[k] = inside ? 1 : 0;
    }
  }
  std::vector<Eigen::Index> keep;
  for (Eigen::Index t = 0; t < mesh.triangles.rows(); ++t)
  {
    if (!removed[piece[mesh.triangles(t, 0)]])
    {
      keep.push_back(t);
    }
  }
  for (int k = 0; k < pieces; ++k)
  {
    report.enclosedPiecesRemoved += removed[k];
  }
  if (keep.size() == static_cast<size_t>(mesh.triangles.rows()))
  {
    return;
  }
  // Compact the points of the kept triangles.
  std::vector<std::int64_t> newIndex(static_cast<size_t>(mesh.points.rows()), -1);
  std::int64_t next = 0;
  Triangles kept(static_cast<Eigen::Index>(keep.size()), 3);
  for (size_t i = 0; i < keep.size(); ++i)
  {
    for (int c = 0; c < 3; ++c)
    {
      std::int64_t& index = newIndex[mesh.triangles(keep[i], c)];
      if (index < 0)
      {
        index = next++;
      }
      kept(static_cast<Eigen::Index>(i), c) = index;
    }
  }
  Points points(next, 3);
  for (std::int64_t p = 0; p < mesh.points.rows(); ++p)
  {
    if (newIndex[p] >= 0)
    {
      points.row(newIndex[p]) = mesh.points.row(p);
    }
  }
  mesh.points = points;
  mesh.triangles = kept;
}
}
