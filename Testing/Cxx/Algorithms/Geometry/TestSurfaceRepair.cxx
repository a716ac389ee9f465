// SPDX-License-Identifier: BSD-3-Clause
// Repair of scanned surfaces (SurfaceRepair.h): what is safe is repaired and said, what is not is refused.
#include "Geometry/MeshChecks.h"
#include "Geometry/SurfaceRepair.h"
#include "Geometry/TriangleIntersection.h"
#include "Hull/ProgressiveHull.h"
#include "Phantom/Phantom.h"
#include "TestMeshes.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

using md::Points;
using md::TriangleMesh;
using md::Triangles;

TEST(SurfaceRepair, RemovesUnusedPointsAndOrientsOutwards)
{
  TriangleMesh box = Box({ 0, 0, 0 }, { 1, 2, 3 });
  box.points.conservativeResize(9, 3);
  box.points.row(8) << 5, 5, 5; // used by nothing
  for (Eigen::Index t = 0; t < box.triangles.rows(); ++t)
  {
    std::swap(box.triangles(t, 1), box.triangles(t, 2)); // inside out
  }
  std::swap(box.triangles(3, 1), box.triangles(3, 2)); // and one against its neighbours
  md::RepairReport report;
  const TriangleMesh clean = md::RepairClosedSurface(box, report);
  EXPECT_EQ(report.unusedPointsRemoved, 1);
  EXPECT_GT(report.trianglesReoriented, 0);
  EXPECT_EQ(clean.points.rows(), 8);
  EXPECT_TRUE(md::CheckEdges(clean.triangles).IsClosedOrientedManifold());
  EXPECT_NEAR(md::SignedVolume(clean.points, clean.triangles), 6.0, 1e-12);
  EXPECT_NE(report.Describe().find("removed unused points: 1"), std::string::npos);
}

TEST(SurfaceRepair, CutsTwoSheetsPinchedAlongAnEdgeApart)
{
  // Two boxes touching along the edge x = 1, y = 1 (z from 0 to 1): that edge
  // carries four triangles once the boxes share its points.
  TriangleMesh a = Box({ 0, 0, 0 }, { 1, 1, 1 });
  TriangleMesh b = Box({ 1, 1, 0 }, { 2, 2, 1 });
  TriangleMesh both;
  both.points.resize(16, 3);
  both.points << a.points, b.points;
  both.triangles.resize(24, 3);
  both.triangles << a.triangles, (b.triangles.array() + 8).matrix();
  // b's corner (1,1,z) points are 8 and 12: map them onto a's 3 and 7.
  for (Eigen::Index t = 12; t < 24; ++t)
  {
    for (int k = 0; k < 3; ++k)
    {
      if (both.triangles(t, k) == 8)
      {
        both.triangles(t, k) = 3;
      }
      if (both.triangles(t, k) == 12)
      {
        both.triangles(t, k) = 7;
      }
    }
  }
  ASSERT_GT(md::CheckEdges(both.triangles).nonManifoldEdges, 0);
  md::RepairReport report;
  const TriangleMesh clean = md::RepairClosedSurface(both, report);
  EXPECT_GE(report.nonManifoldEdgesSplit, 1);
  EXPECT_EQ(report.pointsDuplicatedAtPinches, 2);
  EXPECT_TRUE(md::CheckEdges(clean.triangles).IsClosedOrientedManifold());
  EXPECT_NEAR(md::SignedVolume(clean.points, clean.triangles), 2.0, 1e-5);
  EXPECT_EQ(report.pointsToEnclose.rows(), 2); // where the two pinched points were
}

TEST(SurfaceRepair, RemovesBackToBackFinsAndDuplicateTriangles)
{
  TriangleMesh box = Box({ 0, 0, 0 }, { 1, 1, 1 });
  const Eigen::Index n = box.triangles.rows();
  box.triangles.conservativeResize(n + 3, 3);
  box.triangles.row(n) = box.triangles.row(0); // a copy
  box.triangles.row(n + 1) << 0, 5, 6;         // a fin ...
  box.triangles.row(n + 2) << 0, 6, 5;         // ... both sides
  md::RepairReport report;
  const TriangleMesh clean = md::RepairClosedSurface(box, report);
  EXPECT_EQ(report.duplicateTrianglesRemoved, 1);
  EXPECT_EQ(report.finTrianglesRemoved, 2);
  EXPECT_EQ(clean.triangles.rows(), 12);
  EXPECT_TRUE(md::CheckEdges(clean.triangles).IsClosedOrientedManifold());
}

TEST(SurfaceRepair, UndoesAFoldAndRemembersWhereThePointsWere)
{
  TriangleMesh muscle = md::BuildPhantom(md::PhantomParameters{}).muscles[2].rest;
  // Push one point through the far side of the muscle: a fold.
  const Eigen::Index p = muscle.points.rows() / 2;
  const Eigen::RowVector3d centre = muscle.points.colwise().mean();
  const Eigen::RowVector3d original = muscle.points.row(p);
  muscle.points.row(p) = original + 2.2 * (centre - original);
  ASSERT_FALSE(md::FindSelfIntersections(muscle.points, muscle.triangles).empty());
  md::RepairReport report;
  const TriangleMesh clean = md::RepairClosedSurface(muscle, report);
  EXPECT_GT(report.selfIntersectionsUntangled, 0);
  EXPECT_EQ(report.selfIntersectionsLeft, 0);
  EXPECT_TRUE(md::FindSelfIntersections(clean.points, clean.triangles).empty());
  EXPECT_GT(report.pointsSmoothed, 0);
  EXPECT_GE(report.pointsToEnclose.rows(), 1);
}

namespace
{
/// A sphere cut open along a seam: the triangles of its x > 0 half use copies of their points,
/// moved by `split` (a fraction of the sphere's size) in a direction of their own, as a scan
/// exported in pieces, or in float, carries them.
TriangleMesh SphereWithASeam(double split)
{
  TriangleMesh sphere = Sphere(Eigen::Vector3d(100, 50, 20), 10, 3);
  const Eigen::Index n = sphere.points.rows();
  std::vector<Eigen::Index> copyOf(static_cast<size_t>(n), -1);
  for (Eigen::Index t = 0; t < sphere.triangles.rows(); ++t)
  {
    Eigen::RowVector3d centroid = Eigen::RowVector3d::Zero();
    for (int k = 0; k < 3; ++k)
    {
      centroid += sphere.points.row(sphere.triangles(t, k)) / 3.0;
    }
    if (centroid.x() <= 100)
    {
      continue;
    }
    for (int k = 0; k < 3; ++k)
    {
      Eigen::Index& copy = copyOf[sphere.triangles(t, k)];
      if (copy < 0)
      {
        copy = sphere.points.rows();
        sphere.points.conservativeResize(copy + 1, 3);
        const double angle = 0.7 * static_cast<double>(copy);
        sphere.points.row(copy) = sphere.points.row(sphere.triangles(t, k)) +
          split * 20 * Eigen::RowVector3d(std::cos(angle), std::sin(angle), 0.5).normalized();
      }
      sphere.triangles(t, k) = copy;
    }
  }
  return sphere;
}
}

// Rounding noise must not open a scan along its duplicate points: points closer than 1e-5 of
// the surface's size are one point (and the hull encloses both); farther apart they are not.
TEST(SurfaceRepair, MergesPointsRoundingNoiseSplitAndSaysSo)
{
  for (double split : { 0.0, 1e-7, 5e-6 })
  {
    SCOPED_TRACE(split);
    const TriangleMesh seam = SphereWithASeam(split);
    md::RepairReport report;
    const TriangleMesh clean = md::RepairClosedSurface(seam, report);
    EXPECT_TRUE(md::CheckEdges(clean.triangles).IsClosedOrientedManifold());
    EXPECT_GT(report.duplicatePointsMerged, 10);
    EXPECT_EQ(report.nearDuplicatePointsMerged, split > 0 ? report.duplicatePointsMerged : 0);
    EXPECT_NEAR(report.mergeTolerance, 1e-5 * 20 * std::sqrt(3.0), 1e-5); // of the box's diagonal
    EXPECT_EQ(report.Describe().find("closer than") != std::string::npos, split > 0) << report.Describe();
    const md::MuscleHull hull = md::BuildMuscleHull(seam, md::HullParameters{ 100 });
    EXPECT_EQ(md::CountOutside(hull.result.hull, md::UsedPoints(seam), 0.0), 0);
  }
  md::RepairReport report;
  EXPECT_THROW(md::RepairClosedSurface(SphereWithASeam(1e-4), report), md::InputError); // a real gap
}

// The surface the full-mesh settle is posed on: the same welding on the input's own points, with
// fins kept (they are part of the muscle's shape there) and what welding leaves of no area dropped.
TEST(SurfaceRepair, WeldsDuplicatesOnTheSurfacesOwnPoints)
{
  const TriangleMesh sphere = Sphere(Eigen::Vector3d(100, 50, 20), 10, 3);
  for (double split : { 0.0, 1e-7 })
  {
    SCOPED_TRACE(split);
    const TriangleMesh seam = SphereWithASeam(split);
    std::vector<std::int64_t> representative;
    const md::Triangles welded = md::WeldedTriangles(seam, representative);
    ASSERT_EQ(representative.size(), static_cast<size_t>(seam.points.rows()));
    // The sphere's triangles again, each corner one point of the seamed surface at its place.
    ASSERT_EQ(welded.rows(), sphere.triangles.rows());
    std::vector<std::int64_t> used(welded.data(), welded.data() + welded.size());
    std::sort(used.begin(), used.end());
    EXPECT_EQ(std::unique(used.begin(), used.end()) - used.begin(), sphere.points.rows());
    for (Eigen::Index t = 0; t < welded.rows(); ++t)
    {
      for (int k = 0; k < 3; ++k)
      {
        EXPECT_LT((seam.points.row(welded(t, k)) - sphere.points.row(sphere.triangles(t, k))).norm(), 1e-5);
      }
    }
  }
  TriangleMesh box = Box({ 0, 0, 0 }, { 1, 1, 1 });
  const Eigen::Index n = box.triangles.rows();
  box.points.conservativeResize(box.points.rows() + 1, 3);
  box.points.row(8) = box.points.row(0); // a duplicate of point 0 ...
  box.triangles.conservativeResize(n + 3, 3);
  box.triangles.row(n) << 0, 8, 5;     // ... in a triangle of no area
  box.triangles.row(n + 1) << 0, 5, 6; // a fin ...
  box.triangles.row(n + 2) << 0, 6, 5; // ... both sides
  std::vector<std::int64_t> representative;
  const md::Triangles welded = md::WeldedTriangles(box, representative);
  EXPECT_EQ(representative[8], 0);
  EXPECT_EQ(welded.rows(), n + 2);
}

TEST(SurfaceRepair, RefusesWhatCannotBeRepaired)
{
  TriangleMesh box = Box({ 0, 0, 0 }, { 1, 1, 1 });
  TriangleMesh open = box;
  open.triangles.conservativeResize(11, 3);
  md::RepairReport report;
  try
  {
    md::RepairClosedSurface(open, report);
    FAIL() << "an open surface was accepted";
  }
  catch (const md::InputError& e)
  {
    EXPECT_NE(std::string(e.what()).find("open"), std::string::npos);
  }
  TriangleMesh flat = box;
  flat.points.col(2).setZero(); // every point in one plane: no volume
  EXPECT_THROW(md::RepairClosedSurface(flat, report), md::InputError);
  TriangleMesh empty;
  empty.points.resize(0, 3);
  empty.triangles.resize(0, 3);
  EXPECT_THROW(md::RepairClosedSurface(empty, report), md::InputError);
  TriangleMesh withNaN = box;
  withNaN.points(2, 1) = std::nan("");
  EXPECT_THROW(md::RepairClosedSurface(withNaN, report), md::InputError);
}
