// SPDX-License-Identifier: BSD-3-Clause
// The phantom: closed, oriented surfaces apart from each other, moving as a hip does.
#include "Geometry/MeshChecks.h"
#include "Phantom/Phantom.h"

#include <gtest/gtest.h>

#include <cmath>

using md::Points;
using md::Triangles;

TEST(Phantom, SurfacesAreClosedOrientedAndApart)
{
  const md::Phantom phantom = md::BuildPhantom(md::PhantomParameters{});
  ASSERT_EQ(phantom.bones.size(), 2u);
  ASSERT_EQ(phantom.muscles.size(), 3u);
  std::vector<const md::TriangleMesh*> surfaces;
  for (const auto& bone : phantom.bones)
  {
    surfaces.push_back(&bone.rest);
  }
  for (const auto& muscle : phantom.muscles)
  {
    surfaces.push_back(&muscle.rest);
  }
  for (const md::TriangleMesh* surface : surfaces)
  {
    const md::EdgeReport report = md::CheckEdges(surface->triangles);
    EXPECT_TRUE(report.IsClosedOrientedManifold());
    EXPECT_GT(md::SignedVolume(surface->points, surface->triangles), 1e4);
    EXPECT_TRUE(surface->points.allFinite());
  }
  for (size_t a = 0; a < surfaces.size(); ++a)
  {
    for (size_t b = 0; b < surfaces.size(); ++b)
    {
      if (a != b)
      {
        EXPECT_EQ(md::CountInside(surfaces[b]->points, surfaces[b]->triangles, surfaces[a]->points), 0)
          << "surfaces " << a << " and " << b << " overlap in the rest pose";
      }
    }
  }
}

TEST(Phantom, FlexionMovesTheFemurAboutTheHipCentreIntoTheRectusFemoris)
{
  md::PhantomParameters parameters;
  parameters.flexionDegrees = 60;
  const md::Phantom flexed = md::BuildPhantom(parameters);
  const md::PhantomBone& femur = flexed.bones[1];
  ASSERT_EQ(femur.name, "Femur");
  EXPECT_LT((flexed.femurMotion.Apply(flexed.hipCentre) - flexed.hipCentre).norm(), 1e-12);
  EXPECT_TRUE((flexed.bones[0].currentPoints.array() == flexed.bones[0].rest.points.array()).all());
  const md::PhantomMuscle& rectus = flexed.muscles[2];
  ASSERT_EQ(rectus.name, "RectusFemoris");
  const auto inside = md::CountInside(femur.currentPoints, femur.rest.triangles, rectus.rest.points);
  EXPECT_GT(inside, 50) << "the flexed femur should sweep into the rest-pose rectus femoris";

  parameters.flexionDegrees = 0;
  const md::Phantom straight = md::BuildPhantom(parameters);
  EXPECT_TRUE(straight.bones[1].currentPoints.isApprox(straight.bones[1].rest.points, 1e-12));
  EXPECT_EQ(
    md::CountInside(straight.bones[1].currentPoints, straight.bones[1].rest.triangles, straight.muscles[2].rest.points),
    0);
}

TEST(Phantom, ConditionalViaPointChangesTheCurrentActionLine)
{
  md::PhantomParameters parameters;
  parameters.flexionDegrees = 20;
  const md::Phantom low = md::BuildPhantom(parameters);
  EXPECT_EQ(low.muscles[0].actionLinesCurrent[0].rows(), 3);
  parameters.flexionDegrees = 60;
  const md::Phantom high = md::BuildPhantom(parameters);
  EXPECT_EQ(high.muscles[0].actionLinesRest[0].rows(), 3);
  EXPECT_EQ(high.muscles[0].actionLinesCurrent[0].rows(), 2);
  // The gluteus has two bundles, moved with the femur where they attach to it.
  const md::PhantomMuscle& gluteus = high.muscles[1];
  ASSERT_EQ(gluteus.actionLinesRest.size(), 2u);
  for (size_t l = 0; l < 2; ++l)
  {
    EXPECT_EQ(gluteus.actionLinesCurrent[l].row(0), gluteus.actionLinesRest[l].row(0));
    EXPECT_TRUE(gluteus.actionLinesCurrent[l].row(3).transpose().isApprox(
      high.femurMotion.Apply(Eigen::Vector3d(gluteus.actionLinesRest[l].row(3).transpose())), 1e-12));
  }
  // Via points lie inside their muscle.
  for (const md::PhantomMuscle& muscle : high.muscles)
  {
    for (const Points& line : muscle.actionLinesRest)
    {
      const Points interior = line.middleRows(1, line.rows() - 2);
      EXPECT_EQ(md::CountInside(muscle.rest.points, muscle.rest.triangles, interior), interior.rows()) << muscle.name;
    }
  }
}

TEST(Phantom, ScaleAndResolution)
{
  md::PhantomParameters parameters;
  const md::Phantom unit = md::BuildPhantom(parameters);
  parameters.scale = 0.001; // metres
  const md::Phantom metres = md::BuildPhantom(parameters);
  const auto& a = unit.muscles[1].rest;
  const auto& b = metres.muscles[1].rest;
  ASSERT_EQ(a.points.rows(), b.points.rows());
  EXPECT_TRUE((a.points * 0.001).isApprox(b.points, 1e-9));
  parameters.scale = 1;
  parameters.resolution = 12;
  const md::Phantom coarse = md::BuildPhantom(parameters);
  EXPECT_LT(coarse.muscles[1].rest.points.rows(), a.points.rows());
  EXPECT_TRUE(md::CheckEdges(coarse.muscles[1].rest.triangles).IsClosedOrientedManifold());
  parameters.resolution = 3;
  EXPECT_THROW(md::BuildPhantom(parameters), md::InputError);
  parameters.resolution = 24;
  parameters.scale = -1;
  EXPECT_THROW(md::BuildPhantom(parameters), md::InputError);
}
