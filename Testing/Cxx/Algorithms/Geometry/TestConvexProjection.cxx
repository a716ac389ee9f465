// SPDX-License-Identifier: BSD-3-Clause
// The placement of a collapse's new point: projection onto a convex polyhedron (ConvexProjection.h).
#include "Geometry/ConvexProjection.h"

#include <gtest/gtest.h>

using md::Points;
using md::TriangleMesh;
using md::Triangles;

TEST(ConvexProjection, ProjectsOntoABoxAndItsFacesEdgesAndCorners)
{
  std::vector<md::HalfSpace> cube; // 0 <= x, y, z <= 1
  for (int axis = 0; axis < 3; ++axis)
  {
    cube.push_back({ Eigen::Vector3d::Unit(axis), 0.0 });
    cube.push_back({ -Eigen::Vector3d::Unit(axis), -1.0 });
  }
  const Eigen::Vector3d start(0.5, 0.5, 0.5);
  const std::vector<std::pair<Eigen::Vector3d, Eigen::Vector3d>> cases = {
    { { 0.3, 0.4, 0.5 }, { 0.3, 0.4, 0.5 } },  // inside: itself
    { { 2.0, 0.5, 0.5 }, { 1.0, 0.5, 0.5 } },  // a face
    { { 2.0, 0.5, -3.0 }, { 1.0, 0.5, 0.0 } }, // an edge
    { { -1.0, 5.0, 9.0 }, { 0.0, 1.0, 1.0 } }, // a corner
  };
  for (const auto& [target, expected] : cases)
  {
    const auto projected = md::ProjectOntoPolyhedron(target, cube, start);
    ASSERT_TRUE(projected.has_value());
    EXPECT_LT((*projected - expected).norm(), 1e-12) << target.transpose();
  }
}

TEST(ConvexProjection, FeasiblePointsAlongARay)
{
  const std::vector<md::HalfSpace> slab = { { Eigen::Vector3d::UnitZ(), 1.0 }, { -Eigen::Vector3d::UnitZ(), -2.0 } };
  const auto inside = md::FeasiblePointAlongRay(Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitZ(), slab);
  ASSERT_TRUE(inside.has_value());
  EXPECT_NEAR((*inside)(2), 1.0, 1e-15);
  const std::vector<md::HalfSpace> empty = { { Eigen::Vector3d::UnitZ(), 2.0 }, { -Eigen::Vector3d::UnitZ(), -1.0 } };
  EXPECT_FALSE(md::FeasiblePointAlongRay(Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitZ(), empty).has_value());
}
