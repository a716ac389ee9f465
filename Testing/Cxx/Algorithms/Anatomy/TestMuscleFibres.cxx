// SPDX-License-Identifier: BSD-3-Clause
// Fibres: straight and as long as a cylinder between its caps, inside the muscle, carried exactly
// by any affine map of the surface, their ends found from the areas or the lines, and bad ends said.
#include "Anatomy/MuscleFibres.h"
#include "Geometry/MeshChecks.h"
#include "Geometry/TriangleTree.h"
#include "TestMeshes.h"

#include <gtest/gtest.h>

#include <cmath>

namespace
{
constexpr double kPi = 3.14159265358979323846;

/// A closed cylinder along z from 0 to `length`, radius `radius`, outward.
md::TriangleMesh Cylinder(double radius, double length, int around = 24, int along = 30)
{
  md::TriangleMesh mesh;
  const int rings = along + 1;
  mesh.points.resize(rings * around + 2, 3);
  for (int r = 0; r < rings; ++r)
  {
    for (int a = 0; a < around; ++a)
    {
      const double angle = 2 * kPi * a / around;
      mesh.points.row(r * around + a) << radius * std::cos(angle), radius * std::sin(angle), length * r / along;
    }
  }
  const int bottom = rings * around, top = bottom + 1;
  mesh.points.row(bottom) << 0, 0, 0;
  mesh.points.row(top) << 0, 0, length;
  std::vector<std::array<std::int64_t, 3>> triangles;
  for (int r = 0; r < along; ++r)
  {
    for (int a = 0; a < around; ++a)
    {
      const std::int64_t p = r * around + a, q = r * around + (a + 1) % around;
      triangles.push_back({ p, q, q + around });
      triangles.push_back({ p, q + around, p + around });
    }
  }
  for (int a = 0; a < around; ++a)
  {
    triangles.push_back({ bottom, (a + 1) % around, a });
    triangles.push_back({ top, along * around + a, along * around + (a + 1) % around });
  }
  mesh.triangles.resize(static_cast<Eigen::Index>(triangles.size()), 3);
  for (size_t t = 0; t < triangles.size(); ++t)
  {
    mesh.triangles.row(static_cast<Eigen::Index>(t)) << triangles[t][0], triangles[t][1], triangles[t][2];
  }
  return mesh;
}

/// The cylinder's cap points (z = 0: origin, z = length: insertion) as its ends.
md::FibreEnds CapEnds(const md::TriangleMesh& cylinder, double length)
{
  md::FibreEnds ends;
  for (Eigen::Index p = 0; p < cylinder.points.rows(); ++p)
  {
    if (cylinder.points(p, 2) == 0)
    {
      ends.origin.push_back(p);
    }
    else if (cylinder.points(p, 2) == length)
    {
      ends.insertion.push_back(p);
    }
  }
  return ends;
}
}

TEST(MuscleFibres, InACylinderTheyRunStraightFromCapToCap)
{
  const double length = 100, radius = 10;
  const md::TriangleMesh cylinder = Cylinder(radius, length);
  ASSERT_GT(md::SignedVolume(cylinder.points, cylinder.triangles), 0);
  md::FibreParameters parameters;
  parameters.gridNodes = 8000;
  const md::MuscleFibres fibres(cylinder, CapEnds(cylinder, length), parameters);
  EXPECT_EQ(fibres.Count(), 100);
  EXPECT_TRUE(fibres.Warnings().empty());
  const md::Points& rest = fibres.Rest();
  ASSERT_EQ(rest.rows(), 100 * parameters.pointsPerFibre);
  // At rest they stay where they are (to the weights' single precision), none moved back in.
  std::pair<int, int> kept{ -1, -1 };
  EXPECT_LT((fibres.At(cylinder.points, {}, &kept) - rest).cwiseAbs().maxCoeff(), 1e-5);
  EXPECT_EQ(kept, std::make_pair(0, 0));
  const md::TriangleTree tree(cylinder);
  for (Eigen::Index p = 0; p < rest.rows(); ++p)
  {
    EXPECT_TRUE(tree.Inside(rest.row(p).transpose())) << "fibre point " << p;
  }
  double spreadX = 0, spreadY = 0;
  for (int f = 0; f < fibres.Count(); ++f)
  {
    const auto fibre = rest.middleRows(Eigen::Index(f) * parameters.pointsPerFibre, parameters.pointsPerFibre);
    // From next to one cap to next to the other (about half a grid step, 0.8, inside), along z.
    EXPECT_LT(fibre(0, 2), 2.0);
    EXPECT_GT(fibre(fibre.rows() - 1, 2), length - 2.0);
    spreadX = std::max(spreadX, fibre.col(0).maxCoeff() - fibre.col(0).minCoeff());
    spreadY = std::max(spreadY, fibre.col(1).maxCoeff() - fibre.col(1).minCoeff());
  }
  // The field is phi = z / length away from the caps: only the ends' closing segments bend.
  EXPECT_LT(std::max(spreadX, spreadY), 0.35 * radius);
  for (double l : fibres.Lengths(rest))
  {
    EXPECT_GT(l, length - 4.0);
    EXPECT_LT(l, length + 0.2 * radius);
  }
  // The seeds spread over the cross-section: fibres near the axis and near the wall.
  double nearest = radius, farthest = 0;
  for (int f = 0; f < fibres.Count(); ++f)
  {
    const double r =
      rest.row(Eigen::Index(f) * parameters.pointsPerFibre + parameters.pointsPerFibre / 2).head<2>().norm();
    nearest = std::min(nearest, r);
    farthest = std::max(farthest, r);
  }
  EXPECT_LT(nearest, 0.3 * radius);
  EXPECT_GT(farthest, 0.7 * radius);
}

// A muscle too slender for the grid asked for (spacing 3.2 about an axis 3 from the wall: few
// nodes inside) is traced on a grid of four times the nodes, as if that had been asked for, and
// says so.
TEST(MuscleFibres, ATooSlenderMuscleIsTracedOnAFinerGrid)
{
  const double length = 200, radius = 3;
  const md::TriangleMesh cylinder = Cylinder(radius, length, 16, 60);
  md::FibreParameters parameters;
  parameters.gridNodes = 200;
  parameters.count = 8;
  const md::MuscleFibres fibres(cylinder, CapEnds(cylinder, length), parameters);
  ASSERT_FALSE(fibres.Warnings().empty());
  EXPECT_NE(fibres.Warnings().front().find("grid of 800 nodes, not 200"), std::string::npos)
    << fibres.Warnings().front();
  md::FibreParameters finer = parameters;
  finer.gridNodes = 800;
  const md::MuscleFibres asked(cylinder, CapEnds(cylinder, length), finer);
  EXPECT_EQ(fibres.Count(), 8);
  EXPECT_EQ(fibres.Count(), asked.Count());
  EXPECT_EQ(fibres.Rest(), asked.Rest());
  const md::TriangleTree tree(cylinder);
  for (Eigen::Index p = 0; p < fibres.Rest().rows(); ++p)
  {
    EXPECT_TRUE(tree.Inside(fibres.Rest().row(p).transpose())) << "fibre point " << p;
  }
  for (double l : fibres.Lengths(fibres.Rest()))
  {
    EXPECT_GT(l, length - 6.0);
  }
}

// A bone poked deep into the muscle (6 deep at the axis, beyond any fixed search radius the
// fibres use): with its distance grid, every fibre point inside it is put out of it, and stays
// inside the muscle.
TEST(MuscleFibres, APointDeepInsideABoneIsPutOutOfIt)
{
  const double length = 100, radius = 10;
  const md::TriangleMesh cylinder = Cylinder(radius, length);
  const md::MuscleFibres fibres(cylinder, CapEnds(cylinder, length));
  const md::TriangleMesh box = Box(Eigen::Vector3d(-6, -6, 40), Eigen::Vector3d(6, 6, 60));
  md::TriangleTree bone(box);
  const auto insideBone = [&](const md::Points& points) {
    int count = 0;
    for (Eigen::Index p = 0; p < points.rows(); ++p)
    {
      count += md::WindingNumber(box.points, box.triangles, points.row(p).transpose()) > 0.5;
    }
    return count;
  };
  int deepest = 0;
  for (Eigen::Index p = 0; p < fibres.Rest().rows(); ++p)
  {
    const Eigen::Vector3d x = fibres.Rest().row(p).transpose();
    deepest += std::abs(x[0]) < 0.5 && std::abs(x[1]) < 0.5 && std::abs(x[2] - 50) < 5;
  }
  ASSERT_GT(deepest, 0); // some fibre points lie at least 5 inside the bone
  ASSERT_GT(insideBone(fibres.Rest()), deepest);
  bone.BuildDistanceGrid();
  std::pair<int, int> kept;
  const md::Points carried = fibres.At(cylinder.points, { md::FibreObstacle{ &bone, md::RigidTransform() } }, &kept);
  EXPECT_EQ(insideBone(carried), 0);
  EXPECT_EQ(md::CountOutside(cylinder, carried, 0.0), 0);
  EXPECT_EQ(kept.second, 0);
}

TEST(MuscleFibres, AnAffineMapOfTheSurfaceCarriesThemExactly)
{
  const double length = 80;
  const md::TriangleMesh cylinder = Cylinder(8, length);
  md::FibreParameters parameters;
  parameters.count = 8;
  parameters.gridNodes = 4000;
  const md::MuscleFibres fibres(cylinder, CapEnds(cylinder, length), parameters);
  EXPECT_LT(fibres.MeanWeightsPerPoint(), 0.9 * static_cast<double>(cylinder.points.rows()));
  // Stretched by 1.2 along the axis and thinned to keep the volume, turned and moved.
  Eigen::Matrix3d map = Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix() *
    Eigen::Vector3d(1 / std::sqrt(1.2), 1 / std::sqrt(1.2), 1.2).asDiagonal();
  const Eigen::RowVector3d shift(5, -3, 40);
  const md::Points moved = (cylinder.points * map.transpose()).rowwise() + shift;
  const md::Points carried = fibres.At(moved);
  const md::Points expected = (fibres.Rest() * map.transpose()).rowwise() + shift;
  // To the weights' single precision (1e-7 of the muscle's size).
  EXPECT_LT((carried - expected).cwiseAbs().maxCoeff(), 1e-7 * md::BoxDiagonal(cylinder.points) * 10);
  const std::vector<double> before = fibres.Lengths(fibres.Rest()), after = fibres.Lengths(carried);
  for (size_t f = 0; f < before.size(); ++f)
  {
    EXPECT_NEAR(after[f], 1.2 * before[f], 0.05 * before[f]); // the closing segments are not axial
  }
  const md::Spread spread = md::SpreadOf(after);
  EXPECT_LE(spread.low, spread.median);
  EXPECT_LE(spread.median, spread.high);
}

TEST(MuscleFibres, TheirEndsAreTheAreasAtTheLinesEndsOrTheMusclesCaps)
{
  const double length = 60;
  const md::TriangleMesh cylinder = Cylinder(6, length, 12, 10);
  const md::FibreEnds caps = CapEnds(cylinder, length);
  md::Attachment top;
  top.bone = "femur";
  top.points = caps.insertion;
  // The line runs from the bottom to the top: the top area is the insertion.
  const std::vector<md::Points> lines{ (md::Points(2, 3) << 0, 0, -5, 0, 0, length + 5).finished() };
  const md::FibreEnds ends = md::FindFibreEnds(cylinder, { top }, lines);
  EXPECT_EQ(ends.insertion, caps.insertion);
  EXPECT_EQ(ends.insertionSource, "its area on femur");
  // No area at the bottom: the points within 5 % of the extent of the bottom (the cap's ring).
  EXPECT_EQ(ends.originSource, "its end along its action lines");
  ASSERT_FALSE(ends.origin.empty());
  for (Eigen::Index p : ends.origin)
  {
    EXPECT_LE(cylinder.points(p, 2), 0.05 * length);
  }
  // The line the other way round: the same area is the origin.
  const std::vector<md::Points> reversed{ lines[0].colwise().reverse() };
  EXPECT_EQ(md::FindFibreEnds(cylinder, { top }, reversed).origin, caps.insertion);
  EXPECT_THROW(md::FindFibreEnds(cylinder, {}, { md::Points::Zero(2, 3) }), md::InputError);
}

TEST(MuscleFibres, EndsThatCannotBeJoinedAreSaid)
{
  const md::TriangleMesh cylinder = Cylinder(6, 60, 12, 10);
  md::FibreEnds ends = CapEnds(cylinder, 60);
  md::FibreEnds noInsertion = ends;
  noInsertion.insertion.clear();
  EXPECT_THROW(md::MuscleFibres(cylinder, noInsertion), md::InputError);
  // Two separate spheres: the origin in one, the insertion in the other.
  md::TriangleMesh two = Sphere(Eigen::Vector3d(0, 0, 0), 5, 3);
  const md::TriangleMesh other = Sphere(Eigen::Vector3d(20, 0, 0), 5, 3);
  const Eigen::Index offset = two.points.rows();
  two.points.conservativeResize(offset + other.points.rows(), 3);
  two.points.bottomRows(other.points.rows()) = other.points;
  const Eigen::Index triangles = two.triangles.rows();
  two.triangles.conservativeResize(triangles + other.triangles.rows(), 3);
  two.triangles.bottomRows(other.triangles.rows()) = other.triangles.array() + offset;
  md::FibreEnds apart;
  apart.origin = { 0 };
  apart.insertion = { offset };
  try
  {
    md::MuscleFibres fibres(two, apart);
    FAIL() << "no error";
  }
  catch (const md::InputError& e)
  {
    EXPECT_NE(std::string(e.what()).find("not connected"), std::string::npos) << e.what();
  }
}
