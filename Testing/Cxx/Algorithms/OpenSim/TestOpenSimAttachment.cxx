// SPDX-License-Identifier: BSD-3-Clause
// Attaching surfaces and paths to a model: assignments parsed, a surface's body found by name, a
// path given to the muscle that holds most of it.
#include "OpenSim/OpenSimAttachment.h"
#include "OpenSimTestModels.h"
#include "TestMeshes.h"

#include <gtest/gtest.h>

using namespace md::osim;
using namespace md::osim::test;

TEST(OpenSimAttachment, AssignmentsAreReadWithEitherSeparator)
{
  const auto assignments = ParseAssignments("pelvis=hip_r.vtk, sacrum.vtk; femur_r = femur_r.stl\ntibia=a b");
  ASSERT_EQ(assignments.size(), 3u);
  EXPECT_EQ(assignments[0].first, "pelvis");
  EXPECT_EQ(assignments[0].second, (std::vector<std::string>{ "hip_r.vtk", "sacrum.vtk" }));
  EXPECT_EQ(assignments[1].first, "femur_r");
  EXPECT_EQ(assignments[1].second, (std::vector<std::string>{ "femur_r.stl" }));
  EXPECT_EQ(assignments[2].second, (std::vector<std::string>{ "a", "b" }));
  EXPECT_TRUE(ParseAssignments("").empty());
  EXPECT_NE(ExpectInputError([] { ParseAssignments("pelvis hip_r.vtk"); }).find("pelvis hip_r.vtk"), std::string::npos);
}

TEST(OpenSimAttachment, ASurfaceMovesWithTheBodyItIsGivenOrNamedFor)
{
  const std::vector<std::string> bodies = { "pelvis", "femur", "femur_r", "tibia_r" };
  EXPECT_EQ(WithoutExtension("femur_r.vtk"), "femur_r");
  EXPECT_EQ(WithoutExtension("femur_r"), "femur_r");
  EXPECT_EQ(BodyOfSurface("femur_r.vtk", bodies, {}), 2);      // named as the body
  EXPECT_EQ(BodyOfSurface("femur_r_head.vtp", bodies, {}), 2); // the longest body name it starts with
  EXPECT_EQ(BodyOfSurface("femurhead.vtp", bodies, {}), -1);   // not followed by a non-letter
  EXPECT_EQ(BodyOfSurface("sacrum.vtk", bodies, {}), -1);      // nothing says
  EXPECT_EQ(BodyOfSurface("sacrum.vtk", bodies, ParseAssignments("sacrum=pelvis")), 0); // given: surface=body
}

TEST(OpenSimAttachment, APathGoesToTheMuscleThatHoldsMostOfIt)
{
  const std::vector<md::TriangleMesh> muscles = { Box(Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(1, 1, 4)),
    Box(Eigen::Vector3d(3, 0, 0), Eigen::Vector3d(4, 1, 4)) };
  const std::vector<std::string> muscleNames = { "left", "right" };
  md::Points inLeft(2, 3), mostlyRight(2, 3), outside(2, 3);
  inLeft << 0.5, 0.5, -1, 0.5, 0.5, 5;     // 4 of its 6 inside the left box
  mostlyRight << 0.5, 0.5, 2, 3.9, 0.5, 2; // a piece in the left box, twice that in the right
  outside << 10, 0, 0, 10, 0, 4;
  const std::vector<md::Points> paths = { inLeft, mostlyRight, outside };
  const std::vector<std::string> pathNames = { "a", "b", "c" };
  PathGrouping grouping = GroupPaths(muscles, muscleNames, paths, pathNames, {});
  EXPECT_EQ(grouping.muscleOfPath, (std::vector<int>{ 0, 1, -1 }));
  // Shares from where the segments cross the surfaces: exact to rounding.
  EXPECT_NEAR(grouping.insideFraction[0], 4.0 / 6.0, 1e-9);
  EXPECT_NEAR(grouping.insideFraction[1], 0.9 / 3.4, 1e-9);
  EXPECT_EQ(grouping.insideFraction[2], 0.0);
  // 4 % of a two-point path inside: below the 5 % a path needs (sampled at 16 points, it was
  // taken for 6 %).
  md::Points grazing(2, 3);
  grazing << 0.5, 0.5, 3.8, 0.5, 0.5, 8.8;
  const PathGrouping short4 = GroupPaths(muscles, muscleNames, { grazing }, { "d" }, {});
  EXPECT_EQ(short4.muscleOfPath[0], -1);
  grazing(0, 2) = 3.7; // 6 %: taken
  const PathGrouping share6 = GroupPaths(muscles, muscleNames, { grazing }, { "d" }, {});
  EXPECT_EQ(share6.muscleOfPath[0], 0);
  EXPECT_NEAR(share6.insideFraction[0], 0.3 / 5.1, 1e-9);
  // Named in the assignments: where the user says, whatever the share.
  grouping = GroupPaths(muscles, muscleNames, paths, pathNames, ParseAssignments("left=b; right=c"));
  EXPECT_EQ(grouping.muscleOfPath, (std::vector<int>{ 0, 0, 1 }));
  EXPECT_EQ(grouping.assignedByUser, (std::vector<bool>{ false, true, true }));
  EXPECT_NE(ExpectInputError([&] {
    GroupPaths(muscles, muscleNames, paths, pathNames, ParseAssignments("middle=a"));
  }).find("middle"),
    std::string::npos);
}
