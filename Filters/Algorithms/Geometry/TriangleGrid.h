// SPDX-License-Identifier: BSD-3-Clause
// The uniform grid of triangle bounds that the self-intersection tests share (of a mesh, of a
// repair's moves, of the hull being built): which triangles may meet a box, without testing all.
// TriangleTree is the bounding-volume hierarchy for the distance and inside queries.
#pragma once

#include "Common/MeshTypes.h"
#include "Geometry/TriangleIntersection.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <type_traits>
#include <unordered_map>
#include <vector>

namespace md
{
/// Triangles (by an id of the caller's) listed in every cube of side CellSize() their box meets.
class TriangleGrid
{
public:
  explicit TriangleGrid(double cellSize = 1.0)
    : CellSize_(cellSize)
  {
  }

  /// The cell size that suits `triangles`: twice their mean first-edge length (a triangle then
  /// meets a few cells).
  static double CellSizeFor(const Points& points, const Triangles& triangles)
  {
    double edgeSum = 0;
    for (Eigen::Index t = 0; t < triangles.rows(); ++t)
    {
      edgeSum += (points.row(triangles(t, 0)) - points.row(triangles(t, 1))).norm();
    }
    return std::max(2.0 * edgeSum / static_cast<double>(std::max<Eigen::Index>(triangles.rows(), 1)), 1e-300);
  }

  double CellSize() const { return this->CellSize_; }
  /// Empties the grid, with cells of side `cellSize` from now on.
  void Reset(double cellSize)
  {
    this->CellSize_ = cellSize;
    this->Cells.clear();
  }

  /// The cell holding point `p`.
  std::array<long, 3> Cell(const Eigen::Vector3d& p) const
  {
    return { static_cast<long>(std::floor(p[0] / this->CellSize_)),
      static_cast<long>(std::floor(p[1] / this->CellSize_)), static_cast<long>(std::floor(p[2] / this->CellSize_)) };
  }

  /// Lists `id` in every cell the box [low, high] meets.
  void Insert(int id, const Eigen::Vector3d& low, const Eigen::Vector3d& high)
  {
    ForEachGridCell(this->Cell(low), this->Cell(high), [&](std::uint64_t key) { this->Cells[key].push_back(id); });
  }

  /// Takes `id`, inserted with the box [low, high], out of its cells (the last of a cell's list
  /// takes its place).
  void Remove(int id, const Eigen::Vector3d& low, const Eigen::Vector3d& high)
  {
    ForEachGridCell(this->Cell(low), this->Cell(high), [&](std::uint64_t key) {
      auto cell = this->Cells.find(key);
      if (cell != this->Cells.end())
      {
        std::vector<int>& ids = cell->second;
        auto found = std::find(ids.begin(), ids.end(), id);
        if (found != ids.end())
        {
          *found = ids.back();
          ids.pop_back();
        }
      }
    });
  }

  /// Calls `visit(ids)` with the list of every non-empty cell the box [low, high] meets (an id
  /// may come in several). A visitor that returns bool stops the walk by returning false; the
  /// walk then returns false.
  template<typename Visit>
  bool ForEachCellIn(const Eigen::Vector3d& low, const Eigen::Vector3d& high, Visit&& visit) const
  {
    return ForEachGridCell(this->Cell(low), this->Cell(high), [&](std::uint64_t key) {
      const auto cell = this->Cells.find(key);
      if constexpr (std::is_same_v<decltype(visit(std::vector<int>{})), bool>)
      {
        return cell == this->Cells.end() || visit(cell->second);
      }
      else if (cell != this->Cells.end())
      {
        visit(cell->second);
      }
    });
  }

  /// The lists of the cells that hold two ids or more: the candidates of an all-pairs test.
  std::vector<const std::vector<int>*> CrowdedCells() const
  {
    std::vector<const std::vector<int>*> crowded;
    crowded.reserve(this->Cells.size());
    for (const auto& entry : this->Cells)
    {
      if (entry.second.size() > 1)
      {
        crowded.push_back(&entry.second);
      }
    }
    return crowded;
  }

private:
  double CellSize_;
  std::unordered_map<std::uint64_t, std::vector<int>> Cells;
};
}
