// SPDX-License-Identifier: BSD-3-Clause
// The grid of triangle bounds: a box finds every triangle whose box it meets (and only nearby
// ones), a triangle taken out is found no more, crowded cells are the all-pairs candidates.
#include "Geometry/TriangleGrid.h"
#include "TestMeshes.h"

#include <gtest/gtest.h>

#include <set>

namespace
{
std::set<int> Near(const md::TriangleGrid& grid, const Eigen::Vector3d& low, const Eigen::Vector3d& high)
{
  std::set<int> found;
  grid.ForEachCellIn(low, high, [&](const std::vector<int>& cell) { found.insert(cell.begin(), cell.end()); });
  return found;
}
}

TEST(TriangleGrid, ABoxFindsTheTrianglesWhoseBoxesItMeets)
{
  const md::TriangleMesh sphere = Sphere(Eigen::Vector3d::Zero(), 10.0, 2);
  const double cell = md::TriangleGrid::CellSizeFor(sphere.points, sphere.triangles);
  EXPECT_GT(cell, 0.0);
  EXPECT_LT(cell, 20.0); // a few cells across the sphere
  md::TriangleGrid grid(cell);
  std::vector<Eigen::Vector3d> low, high;
  for (Eigen::Index t = 0; t < sphere.triangles.rows(); ++t)
  {
    Eigen::Vector3d a = sphere.points.row(sphere.triangles(t, 0)).transpose(), l = a, h = a;
    for (int k = 1; k < 3; ++k)
    {
      l = l.cwiseMin(sphere.points.row(sphere.triangles(t, k)).transpose());
      h = h.cwiseMax(sphere.points.row(sphere.triangles(t, k)).transpose());
    }
    low.push_back(l);
    high.push_back(h);
    grid.Insert(static_cast<int>(t), l, h);
  }
  // A small box at the top of the sphere: every triangle whose box it meets is found.
  const Eigen::Vector3d queryLow(-1, -1, 9.5), queryHigh(1, 1, 10.5);
  const std::set<int> found = Near(grid, queryLow, queryHigh);
  int meeting = 0;
  for (size_t t = 0; t < low.size(); ++t)
  {
    const bool meets = !((low[t].array() > queryHigh.array()).any() || (high[t].array() < queryLow.array()).any());
    if (meets)
    {
      ++meeting;
      EXPECT_EQ(found.count(static_cast<int>(t)), 1u) << t;
    }
  }
  EXPECT_GT(meeting, 0);
  EXPECT_LT(found.size(), low.size() / 2); // the bottom of the sphere is not a candidate
  // Taken out: found no more.
  const int gone = *found.begin();
  grid.Remove(gone, low[gone], high[gone]);
  EXPECT_EQ(Near(grid, queryLow, queryHigh).count(gone), 0u);
  // A walk stops when the visitor says so.
  int visits = 0;
  EXPECT_FALSE(grid.ForEachCellIn(queryLow, queryHigh, [&](const std::vector<int>&) { return ++visits < 1; }));
  EXPECT_EQ(visits, 1);
  // Every pair of triangles whose boxes share a cell stands in a crowded cell.
  EXPECT_FALSE(grid.CrowdedCells().empty());
  for (const std::vector<int>* cell : grid.CrowdedCells())
  {
    EXPECT_GE(cell->size(), 2u);
  }
  grid.Reset(2 * cell);
  EXPECT_TRUE(Near(grid, queryLow, queryHigh).empty());
  EXPECT_EQ(grid.CellSize(), 2 * cell);
}
