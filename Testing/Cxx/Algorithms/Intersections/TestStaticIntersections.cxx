// SPDX-License-Identifier: BSD-3-Clause
// Static intersection resolution and the quality measures it is judged by.
#include "Deformation/MuscleDeformer.h"
#include "Deformation/VolumeConstrainedSolver.h"
#include "Geometry/MeshChecks.h"
#include "Intersections/StaticIntersections.h"
#include "TestMeshes.h"

#include <gtest/gtest.h>

namespace
{
md::FixedObstacle Fixed(const md::TriangleTree& tree)
{
  return { "box", &tree };
}

/// A sphere of radius 10 about the origin and a box over x > 7: the sphere's cap pokes 3 into the box.
struct CapInBox : public ::testing::Test
{
  md::TriangleMesh sphere = Sphere(Eigen::Vector3d::Zero(), 10, 3);
  md::TriangleTree box{ Box(Eigen::Vector3d(7, -20, -20), Eigen::Vector3d(30, 20, 20)) };
};
}

TEST_F(CapInBox, ThePenetratingCapGoesOutToTheSurfaceAsOneGroup)
{
  const auto before = md::MeasureNewPenetration({ sphere }, { Fixed(box) }, nullptr);
  ASSERT_GT(before[0].count, 10);
  EXPECT_NEAR(before[0].maxDepth, 3.0, 0.05);
  EXPECT_EQ(before[0].fixedCount, before[0].count);

  md::StaticResolveParameters parameters;
  parameters.falloff = 0; // the paper's rule: only the penetrating points move
  const md::StaticResolveResult r = md::ResolveStaticIntersections({ sphere }, { Fixed(box) }, nullptr, parameters);
  EXPECT_EQ(r.reports[0].penetratingPoints, before[0].count);
  EXPECT_EQ(r.reports[0].groups, 1);
  EXPECT_NEAR(r.reports[0].maxShift, 3.0, 0.05);
  md::TriangleMesh resolved = sphere;
  resolved.points = r.points[0];
  EXPECT_EQ(md::MeasureNewPenetration({ resolved }, { Fixed(box) }, nullptr)[0].count, 0);
  for (Eigen::Index i = 0; i < sphere.points.rows(); ++i)
  {
    if (sphere.points(i, 0) < 7)
    {
      EXPECT_EQ(r.shift[0].row(i).norm(), 0.0) << "point " << i << " was outside and moved";
    }
    else
    {
      EXPECT_NEAR(r.points[0](i, 0), 7.0, 1e-3); // flattened against the box's face, along -x
      EXPECT_NEAR(r.shift[0](i, 1), 0.0, 1e-9);
    }
  }
}

TEST_F(CapInBox, TheMoveSpreadsToASmoothRimWithFewerSharpEdges)
{
  md::StaticResolveParameters paper, smooth;
  paper.falloff = 0;
  smooth.falloff = 3;
  const auto sharp = md::ResolveStaticIntersections({ sphere }, { Fixed(box) }, nullptr, paper);
  const auto soft = md::ResolveStaticIntersections({ sphere }, { Fixed(box) }, nullptr, smooth);
  EXPECT_NEAR(soft.reports[0].maxShift, sharp.reports[0].maxShift, 1e-9);
  md::TriangleMesh resolved = sphere;
  resolved.points = soft.points[0];
  EXPECT_EQ(md::MeasureNewPenetration({ resolved }, { Fixed(box) }, nullptr)[0].count, 0);
  std::int64_t moved = 0;
  for (Eigen::Index i = 0; i < sphere.points.rows(); ++i)
  {
    moved += soft.shift[0].row(i).norm() > 0;
  }
  EXPECT_GT(moved, soft.reports[0].penetratingPoints); // the rim moved too
  EXPECT_LE(md::CountNewSharpEdges(sphere.points, soft.points[0], sphere.triangles),
    md::CountNewSharpEdges(sphere.points, sharp.points[0], sphere.triangles));
}

TEST_F(CapInBox, TheResolutionReportsThePenetrationItFoundAsTheMeasureDoes)
{
  // A sphere beside the cap one, partly inside it and the box, so that the muscle obstacles
  // count too: what the resolution found at its input is what the measure finds there.
  md::TriangleMesh other = Sphere(Eigen::Vector3d(-15, 0, 0), 8, 3);
  const std::vector<md::TriangleMesh> meshes{ sphere, other };
  const auto measured = md::MeasureNewPenetration(meshes, { Fixed(box) }, nullptr);
  const auto r = md::ResolveStaticIntersections(meshes, { Fixed(box) }, nullptr, md::StaticResolveParameters{});
  ASSERT_EQ(r.found.size(), 2u);
  for (size_t m = 0; m < 2; ++m)
  {
    EXPECT_GT(measured[m].count, 0) << "mesh " << m;
    EXPECT_EQ(r.found[m].count, measured[m].count) << "mesh " << m;
    EXPECT_EQ(r.found[m].maxDepth, measured[m].maxDepth) << "mesh " << m;
    EXPECT_EQ(r.found[m].fixedCount, measured[m].fixedCount) << "mesh " << m;
    EXPECT_EQ(r.found[m].fixedMaxDepth, measured[m].fixedMaxDepth) << "mesh " << m;
  }
  EXPECT_GT(measured[0].fixedCount, 0);
  EXPECT_LT(measured[0].fixedCount, measured[0].count); // in the box and in the other sphere
}

TEST_F(CapInBox, AMeshThatPenetratesNothingIsGivenBackAsItCame)
{
  // The sphere moved clear of the box: every point, shift and report as it was, bit for bit.
  md::TriangleMesh clear = sphere;
  clear.points.col(0).array() -= 5;
  const auto r = md::ResolveStaticIntersections({ clear }, { Fixed(box) }, nullptr, md::StaticResolveParameters{});
  EXPECT_TRUE(r.points[0] == clear.points);
  EXPECT_EQ(r.shift[0].rows(), clear.points.rows());
  EXPECT_EQ(r.shift[0].cwiseAbs().maxCoeff(), 0.0);
  EXPECT_EQ(r.reports[0].penetratingPoints, 0);
  EXPECT_EQ(r.reports[0].groups, 0);
  EXPECT_EQ(r.reports[0].maxShift, 0.0);
  EXPECT_EQ(r.found[0].count, 0);
}

TEST_F(CapInBox, RestoreVolumesLeavesAMeshThatHoldsItsVolumeUntouched)
{
  // The settle holds the volume to 1e-9: nothing is given back, not a bit moves, and the share
  // left is reported all the same.
  std::vector<md::TriangleMesh> meshes{ sphere };
  const double volume = md::EnclosedVolume(sphere.points, sphere.triangles);
  const std::vector<double> left =
    md::RestoreVolumes(meshes, { volume * (1 + 1e-9) }, { Fixed(box) }, { std::vector<char>(sphere.points.rows(), 0) });
  EXPECT_TRUE(meshes[0].points == sphere.points);
  EXPECT_NEAR(left[0], -1e-7, 1e-12);
  // Short by more than that, it is given back.
  const std::vector<double> given =
    md::RestoreVolumes(meshes, { volume * 1.001 }, { Fixed(box) }, { std::vector<char>(sphere.points.rows(), 0) });
  EXPECT_FALSE(meshes[0].points == sphere.points);
  EXPECT_LT(std::abs(given[0]), 1e-5);
}

TEST_F(CapInBox, OverlapOfTheRestPoseIsLeftAlone)
{
  const md::OverlapMasks rest = md::FindOverlaps({ sphere }, { Fixed(box) });
  const md::StaticResolveResult r =
    md::ResolveStaticIntersections({ sphere }, { Fixed(box) }, &rest, md::StaticResolveParameters{});
  EXPECT_EQ(r.reports[0].penetratingPoints, 0);
  EXPECT_EQ(r.reports[0].maxShift, 0.0);
  EXPECT_EQ(md::MeasureNewPenetration({ sphere }, { Fixed(box) }, &rest)[0].count, 0);
}

TEST_F(CapInBox, RestoreVolumesGivesTheDentedVolumeBackSmoothlyAndKeepsHeldPointsAndTheBoxOut)
{
  const md::StaticResolveResult r =
    md::ResolveStaticIntersections({ sphere }, { Fixed(box) }, nullptr, md::StaticResolveParameters{});
  std::vector<md::TriangleMesh> meshes{ { r.points[0], sphere.triangles } };
  const double target = md::EnclosedVolume(sphere.points, sphere.triangles);
  const double dented = md::EnclosedVolume(meshes[0].points, sphere.triangles);
  ASSERT_LT(dented, 0.995 * target); // the print took a visible share
  // Hold the points on the far side (x < -8), as the rest pose's overlap is held.
  std::vector<std::vector<char>> held(1, std::vector<char>(static_cast<size_t>(sphere.points.rows()), 0));
  for (Eigen::Index i = 0; i < sphere.points.rows(); ++i)
  {
    held[0][i] = sphere.points(i, 0) < -8;
  }
  const std::vector<double> left = md::RestoreVolumes(meshes, { target }, { Fixed(box) }, held);
  ASSERT_EQ(left.size(), 1u);
  EXPECT_LT(std::abs(left[0]), 1e-3);
  EXPECT_NEAR(100 * (md::EnclosedVolume(meshes[0].points, sphere.triangles) - target) / target, left[0], 1e-9);
  EXPECT_EQ(md::MeasureNewPenetration(meshes, { Fixed(box) }, nullptr)[0].count, 0);
  double largest = 0;
  for (Eigen::Index i = 0; i < sphere.points.rows(); ++i)
  {
    const double move = (meshes[0].points.row(i) - r.points[0].row(i)).norm();
    if (held[0][i])
    {
      EXPECT_EQ(move, 0.0) << "held point " << i << " moved";
    }
    largest = std::max(largest, move);
  }
  // Spread over the surface: a small move everywhere, no bulge (a uniform
  // offset of the radius-10 sphere would need 0.1 mm or so).
  EXPECT_GT(largest, 0.0);
  EXPECT_LT(largest, 0.5);
  EXPECT_EQ(md::CountNewSharpEdges(r.points[0], meshes[0].points, sphere.triangles), 0);
}

TEST(StaticIntersections, TwoDeformableMeshesEachTakeTheirShare)
{
  // Two spheres overlapping by 2 along x: each point of one inside the other
  // moves 0.6 of its way out, from both sides.
  const md::TriangleMesh a = Sphere(Eigen::Vector3d::Zero(), 10, 3);
  const md::TriangleMesh b = Sphere(Eigen::Vector3d(18, 0, 0), 10, 3);
  md::StaticResolveParameters parameters;
  parameters.falloff = 0;
  const auto before = md::MeasureNewPenetration({ a, b }, {}, nullptr);
  ASSERT_GT(before[0].count, 0);
  ASSERT_GT(before[1].count, 0);
  EXPECT_EQ(before[0].fixedCount, 0);
  const md::StaticResolveResult r = md::ResolveStaticIntersections({ a, b }, {}, nullptr, parameters);
  for (int m = 0; m < 2; ++m)
  {
    EXPECT_GT(r.reports[m].maxShift, 0.5 * before[m].maxDepth);
    EXPECT_LT(r.reports[m].maxShift, 0.7 * before[m].maxDepth);
  }
}

TEST(StaticIntersections, AMoveOutOfAMuscleStopsAtABone)
{
  // The muscle's cap is inside another muscle, with a bone right behind it
  // in the way out: the bone wins, no point ends in it.
  const md::TriangleMesh muscle = Sphere(Eigen::Vector3d::Zero(), 10, 3);
  const md::TriangleMesh other = Sphere(Eigen::Vector3d(17, 0, 0), 10, 3);
  const md::TriangleTree bone(Box(Eigen::Vector3d(-30, -30, -30), Eigen::Vector3d(-10.5, 30, 30)));
  md::StaticResolveParameters parameters;
  parameters.deformableShare = 1.0;
  const auto r = md::ResolveStaticIntersections({ muscle, other }, { Fixed(bone) }, nullptr, parameters);
  md::TriangleMesh resolved = muscle;
  resolved.points = r.points[0];
  EXPECT_EQ(md::MeasureNewPenetration({ resolved }, { Fixed(bone) }, nullptr)[0].fixedCount, 0);
}

TEST(SharpEdges, NoneUnderARigidMotionSomeWhereAPointIsPushedIn)
{
  const md::TriangleMesh sphere = Sphere(Eigen::Vector3d::Zero(), 10, 2);
  const Eigen::Matrix3d rotation = Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
  const md::Points moved = (sphere.points * rotation.transpose()).rowwise() + Eigen::RowVector3d(5, 6, 7);
  EXPECT_EQ(md::CountNewSharpEdges(sphere.points, moved, sphere.triangles), 0);
  md::Points pit = sphere.points;
  pit.row(0) *= 0.5; // a pit half the radius deep
  EXPECT_GE(md::CountNewSharpEdges(sphere.points, pit, sphere.triangles), 5);
}
