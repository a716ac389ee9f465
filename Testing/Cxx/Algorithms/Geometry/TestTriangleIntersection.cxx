// SPDX-License-Identifier: BSD-3-Clause
// Triangle tests: a line or a segment through a triangle, two triangles crossing, and the
// self-intersections of a mesh.
#include "Geometry/TriangleIntersection.h"
#include "TestMeshes.h"

#include <gtest/gtest.h>

namespace
{
const Eigen::Vector3d A(0, 0, 0), B(2, 0, 0), C(0, 2, 0);
}

TEST(TriangleIntersection, ALineMeetsATriangleAtItsBarycentricPoint)
{
  double t = 0, u = 0, v = 0;
  ASSERT_TRUE(md::IntersectLineTriangle(Eigen::Vector3d(0.5, 0.4, 3), Eigen::Vector3d(0, 0, -2), A, B, C, 0, t, u, v));
  EXPECT_DOUBLE_EQ(t, 1.5);
  EXPECT_DOUBLE_EQ(u, 0.25);
  EXPECT_DOUBLE_EQ(v, 0.2);
  // Beyond an edge: missed, unless within eps of it.
  EXPECT_FALSE(md::IntersectLineTriangle(Eigen::Vector3d(2.01, 0, 3), Eigen::Vector3d(0, 0, 1), A, B, C, 0, t, u, v));
  EXPECT_TRUE(md::IntersectLineTriangle(Eigen::Vector3d(2.01, 0, 3), Eigen::Vector3d(0, 0, 1), A, B, C, 0.01, t, u, v));
  // Parallel to the plane: no meeting point.
  EXPECT_FALSE(
    md::IntersectLineTriangle(Eigen::Vector3d(0.5, 0.5, 1), Eigen::Vector3d(1, 0, 0), A, B, C, 0.1, t, u, v));
}

TEST(TriangleIntersection, ASegmentCrossesOnlyBetweenItsEnds)
{
  EXPECT_TRUE(md::SegmentHitsTriangle(Eigen::Vector3d(0.5, 0.5, 1), Eigen::Vector3d(0.5, 0.5, -1), A, B, C, 1e-9));
  EXPECT_FALSE(md::SegmentHitsTriangle(Eigen::Vector3d(0.5, 0.5, 3), Eigen::Vector3d(0.5, 0.5, 1), A, B, C, 1e-9));
  // Through a corner: touching counts with eps > 0, not with eps < 0.
  EXPECT_TRUE(md::SegmentHitsTriangle(Eigen::Vector3d(0, 0, 1), Eigen::Vector3d(0, 0, -1), A, B, C, 1e-9));
  EXPECT_FALSE(md::SegmentHitsTriangle(Eigen::Vector3d(0, 0, 1), Eigen::Vector3d(0, 0, -1), A, B, C, -1e-9));
}

TEST(TriangleIntersection, TwoTrianglesCrossUnlessTheyOnlyShareACorner)
{
  const std::array<Eigen::Vector3d, 3> x = { A, B, C };
  const std::array<Eigen::Vector3d, 3> through = { Eigen::Vector3d(0.5, 0.5, -1), Eigen::Vector3d(0.5, 0.5, 1),
    Eigen::Vector3d(1.5, -1, 0.2) };
  EXPECT_TRUE(md::TrianglesIntersect(x, { 0, 1, 2 }, through, { 3, 4, 5 }));
  const std::array<Eigen::Vector3d, 3> above = { Eigen::Vector3d(0.5, 0.5, 1), Eigen::Vector3d(1, 0.5, 2),
    Eigen::Vector3d(0.5, 1, 2) };
  EXPECT_FALSE(md::TrianglesIntersect(x, { 0, 1, 2 }, above, { 3, 4, 5 }));
  // Sharing corner A and leaning away from it: what they share is no intersection.
  const std::array<Eigen::Vector3d, 3> fan = { A, Eigen::Vector3d(-1, -1, 1), Eigen::Vector3d(-1, 1, 1) };
  EXPECT_FALSE(md::TrianglesIntersect(x, { 0, 1, 2 }, fan, { 0, 6, 7 }));
}

TEST(TriangleIntersection, AClosedSurfaceHasNoSelfIntersectionUntilAPointIsPushedThrough)
{
  md::TriangleMesh sphere = Sphere(Eigen::Vector3d::Zero(), 1.0, 2);
  EXPECT_TRUE(md::FindSelfIntersections(sphere.points, sphere.triangles).empty());
  // One point pulled through the far side of the sphere: its triangles cross the far ones.
  sphere.points.row(0) *= -2.0;
  const std::vector<std::pair<int, int>> pairs = md::FindSelfIntersections(sphere.points, sphere.triangles);
  ASSERT_FALSE(pairs.empty());
  for (const auto& [s, t] : pairs)
  {
    EXPECT_LT(s, t);
  }
}

TEST(TriangleIntersection, GridCellsAreVisitedInOrderAndTheWalkStopsWhenAsked)
{
  int visited = 0;
  EXPECT_TRUE(md::ForEachGridCell({ 0, 0, 0 }, { 1, 2, 3 }, [&](std::uint64_t) { ++visited; }));
  EXPECT_EQ(visited, 2 * 3 * 4);
  visited = 0;
  EXPECT_FALSE(md::ForEachGridCell({ 0, 0, 0 }, { 1, 2, 3 }, [&](std::uint64_t key) {
    ++visited;
    return key != md::GridCellKey(0, 1, 0);
  }));
  EXPECT_EQ(visited, 5);
  EXPECT_NE(md::GridCellKey(1, 0, 0), md::GridCellKey(0, 1, 0));
  EXPECT_NE(md::GridCellKey(-1, 0, 0), md::GridCellKey(0, 0, 0));
}
