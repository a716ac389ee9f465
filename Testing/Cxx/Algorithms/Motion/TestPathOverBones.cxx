// SPDX-License-Identifier: BSD-3-Clause
#include "Motion/PathOverBones.h"

#include "TestMeshes.h"

#include <gtest/gtest.h>

#include <cmath>

using md::Points;
using md::TriangleTree;

namespace
{
Points Path(std::initializer_list<Eigen::Vector3d> points)
{
  Points out(static_cast<Eigen::Index>(points.size()), 3);
  Eigen::Index i = 0;
  for (const Eigen::Vector3d& p : points)
  {
    out.row(i++) = p.transpose();
  }
  return out;
}

/// A closed cylinder of radius `radius` along the x axis from x = `from` to `to`, its section a
/// regular polygon of `sides` sides (outward-facing triangles).
md::TriangleMesh Cylinder(double radius, double from, double to, int sides)
{
  md::TriangleMesh mesh;
  mesh.points.resize(2 * sides + 2, 3);
  for (int k = 0; k < sides; ++k)
  {
    const double angle = 2 * M_PI * k / sides;
    mesh.points.row(k) << from, radius * std::cos(angle), radius * std::sin(angle);
    mesh.points.row(sides + k) << to, radius * std::cos(angle), radius * std::sin(angle);
  }
  mesh.points.row(2 * sides) << from, 0, 0;
  mesh.points.row(2 * sides + 1) << to, 0, 0;
  mesh.triangles.resize(4 * sides, 3);
  for (int k = 0; k < sides; ++k)
  {
    const int next = (k + 1) % sides;
    mesh.triangles.row(4 * k) << k, next, sides + next;
    mesh.triangles.row(4 * k + 1) << k, sides + next, sides + k;
    mesh.triangles.row(4 * k + 2) << 2 * sides, next, k;
    mesh.triangles.row(4 * k + 3) << 2 * sides + 1, sides + k, sides + next;
  }
  return mesh;
}

/// Whether any of `samples` points along each chord of `path` lies inside `bone`.
bool EntersBone(const Points& path, const TriangleTree& bone, int samples = 20)
{
  for (Eigen::Index i = 0; i + 1 < path.rows(); ++i)
  {
    for (int k = 0; k <= samples; ++k)
    {
      const double t = static_cast<double>(k) / samples;
      if (bone.Inside(((1 - t) * path.row(i) + t * path.row(i + 1)).transpose()))
      {
        return true;
      }
    }
  }
  return false;
}

/// The closed form of a taut string over a sphere of radius r about the origin, from a to b (both
/// outside it) in a plane through its centre: two tangents and the great circle's arc between.
double OverSphere(const Eigen::Vector3d& a, const Eigen::Vector3d& b, double r)
{
  const double angle = std::acos(a.normalized().dot(b.normalized()));
  return std::sqrt(a.squaredNorm() - r * r) + std::sqrt(b.squaredNorm() - r * r) +
    r * (angle - std::acos(r / a.norm()) - std::acos(r / b.norm()));
}
}

TEST(PathOverBones, PathClearOfEveryBoneIsTheStraightOneSubdivided)
{
  const TriangleTree sphere(Sphere(Eigen::Vector3d(0, 0, 5), 1, 3));
  const Points fixed = Path({ { -3, 0, 0 }, { 0, 1, 0 }, { 3, 0, 0 } });
  md::PathOverBonesParameters parameters;
  parameters.pointsPerSegment = 7;
  const md::PathOverBonesResult result = md::PathOverBones(fixed, { &sphere }, parameters);
  ASSERT_EQ(result.points.rows(), 2 * 8 + 1);
  EXPECT_LT((result.points - md::SubdividedPath(fixed, 7)).cwiseAbs().maxCoeff(), 1e-12);
  EXPECT_NEAR(result.length, result.straightLength, 1e-12);
  EXPECT_TRUE(result.converged);
  EXPECT_EQ(result.pointsOnBone[0], 0);
}

TEST(PathOverBones, StringOverASphereIsTheGreatCircleWithItsTangents)
{
  // The straight segment passes 0.2 above the centre of a sphere of radius 1: the string goes
  // over its top, in the plane y = 0, at the clearance from its facets.
  const double radius = 1;
  const TriangleTree sphere(Sphere(Eigen::Vector3d::Zero(), radius, 4));
  const Eigen::Vector3d a(-3, 0, 0.2), b(3, 0, 0.2);
  md::PathOverBonesParameters parameters;
  parameters.pointsPerSegment = 63;
  const md::PathOverBonesResult result = md::PathOverBones(Path({ a, b }), { &sphere }, parameters);
  ASSERT_TRUE(result.converged);
  EXPECT_FALSE(EntersBone(result.points, sphere));
  // The facets lie within 0.0005 of the sphere; the clearance is an eighth of the spacing.
  const double clearance = parameters.clearanceShare * (b - a).norm() / 64;
  const double lower = OverSphere(a, b, radius * 0.999), upper = OverSphere(a, b, radius + clearance);
  EXPECT_GT(result.length, lower);
  EXPECT_LT(result.length, upper);
  EXPECT_GT(result.length, result.straightLength + 0.1);
  for (Eigen::Index i = 0; i < result.points.rows(); ++i)
  {
    EXPECT_NEAR(result.points(i, 1), 0.0, 1e-6) << i; // stays in the plane of the great circle
    EXPECT_GE(result.points(i, 2), 0.2 - 1e-9) << i;  // over the top, the side nearer the segment
  }
  EXPECT_GT(result.pointsOnBone[0], 3); // the arc is 31 degrees of the sphere
}

TEST(PathOverBones, StringOverACylinderIsAHelixWithItsTangents)
{
  // Unrolled, the string's section-plane path (tangent, arc, tangent) and its run along the axis
  // form a straight line: length = sqrt(section length^2 + axial run^2).
  const double radius = 1;
  const TriangleTree cylinder(Cylinder(radius, -10, 10, 256));
  const Eigen::Vector3d a(-1.5, -3, 0.3), b(1.5, 3, 0.3);
  md::PathOverBonesParameters parameters;
  parameters.pointsPerSegment = 63;
  const md::PathOverBonesResult result = md::PathOverBones(Path({ a, b }), { &cylinder }, parameters);
  ASSERT_TRUE(result.converged);
  EXPECT_FALSE(EntersBone(result.points, cylinder));
  auto helix = [&](double r) {
    const Eigen::Vector2d p(a.y(), a.z()), q(b.y(), b.z());
    const double angle = std::acos(p.normalized().dot(q.normalized()));
    const double section = std::sqrt(p.squaredNorm() - r * r) + std::sqrt(q.squaredNorm() - r * r) +
      r * (angle - std::acos(r / p.norm()) - std::acos(r / q.norm()));
    return std::hypot(section, b.x() - a.x());
  };
  const double clearance = parameters.clearanceShare * (b - a).norm() / 64;
  EXPECT_GT(result.length, helix(radius * std::cos(M_PI / 256)));
  EXPECT_LT(result.length, helix(radius + clearance));
  // Along the axis the string advances in step with its length (a helix, not a bend).
  for (Eigen::Index i = 1; i < result.points.rows(); ++i)
  {
    const double chord = (result.points.row(i) - result.points.row(i - 1)).norm();
    const double run = result.points(i, 0) - result.points(i - 1, 0);
    EXPECT_NEAR(run / chord, (b.x() - a.x()) / result.length, 0.02) << i;
  }
}

TEST(PathOverBones, EndInsideABoneLeavesItStraightAndWrapsWhereItReentersIt)
{
  // The path starts inside the box (an attachment) and runs to a point beyond the box's far side
  // and over a sphere: from the box it leaves straight; the sphere it goes round.
  const TriangleTree box(Box(Eigen::Vector3d(-1, -1, -1), Eigen::Vector3d(1, 1, 1)));
  const TriangleTree sphere(Sphere(Eigen::Vector3d(4, 0, 0), 1, 3));
  const Eigen::Vector3d a(0, 0, 0.1), b(8, 0, 0.1);
  const md::PathOverBonesResult result = md::PathOverBones(Path({ a, b }), { &box, &sphere });
  ASSERT_TRUE(result.converged);
  EXPECT_FALSE(EntersBone(result.points.bottomRows(result.points.rows() - 3), sphere));
  EXPECT_LE(result.pointsOnBone[0], 1); // at most the point on the face the path leaves the box by
  EXPECT_GT(result.pointsOnBone[1], 0);
  EXPECT_GT(result.length, result.straightLength);
  // Outside the box, no point of the path is inside it.
  for (Eigen::Index i = 0; i < result.points.rows(); ++i)
  {
    if (result.points(i, 0) > 1.01)
    {
      EXPECT_FALSE(box.Inside(result.points.row(i).transpose())) << i;
    }
  }
}

TEST(PathOverBones, StartedFromTheLastFrameStaysOnItsSideAndMovesContinuously)
{
  // A sphere rises through a fixed path, from 0.3 below it to 0.3 above: the string, first over
  // the sphere's top (the nearer side), is carried over it frame after frame although below
  // becomes the shorter way round; started afresh at the last frame it goes below.
  const Eigen::Vector3d a(-3, 0, 0), b(3, 0, 0);
  md::PathOverBonesParameters parameters;
  Points last;
  double largestStep = 0;
  md::PathOverBonesResult result;
  for (int k = 0; k <= 30; ++k)
  {
    const double centre = -0.3 + 0.02 * k;
    const TriangleTree sphere(Sphere(Eigen::Vector3d(0, 0, centre), 1, 3));
    result = md::PathOverBones(Path({ a, b }), { &sphere }, parameters, last.rows() ? &last : nullptr);
    ASSERT_TRUE(result.converged) << k;
    EXPECT_FALSE(EntersBone(result.points, sphere)) << k;
    if (last.rows())
    {
      largestStep = std::max(largestStep, (result.points - last).rowwise().norm().maxCoeff());
    }
    last = result.points;
  }
  EXPECT_GT(result.points.col(2).minCoeff(), -1e-9); // still over the top
  EXPECT_LT(largestStep, 0.1);                       // the sphere moves 0.02 a frame
  const TriangleTree sphere(Sphere(Eigen::Vector3d(0, 0, 0.3), 1, 3));
  const md::PathOverBonesResult fresh = md::PathOverBones(Path({ a, b }), { &sphere }, parameters);
  EXPECT_LT(fresh.points.col(2).maxCoeff(), 1e-9); // the shorter way, below
  EXPECT_LT(fresh.length, result.length);
}

TEST(PathOverBones, InputNoiseOfOneInTenMillionMovesThePathByAsLittle)
{
  const TriangleTree sphere(Sphere(Eigen::Vector3d::Zero(), 1, 4));
  // (Not a path symmetric about the sphere's axis: the two mirror images of a string held by
  // points on a facetted sphere are equally short, and noise picks one.)
  const Points exact = Path({ { -3, 0.1, 0.2 }, { 2.5, -0.3, 0.35 } });
  const md::PathOverBonesResult reference = md::PathOverBones(exact, { &sphere });
  double spread = 0;
  for (int seed = 1; seed <= 5; ++seed)
  {
    Points noisy = exact;
    for (Eigen::Index i = 0; i < noisy.size(); ++i)
    {
      noisy.data()[i] *= 1 + 1e-7 * std::sin(37.0 * seed + 11.0 * static_cast<double>(i));
    }
    spread = std::max(spread, (md::PathOverBones(noisy, { &sphere }).points - reference.points).cwiseAbs().maxCoeff());
  }
  EXPECT_LT(spread, 1e-5);
}

TEST(PathOverBones, BadPathsAreRefusedWithTheProblem)
{
  const TriangleTree sphere(Sphere(Eigen::Vector3d::Zero(), 1, 2));
  EXPECT_THROW(md::PathOverBones(Path({ { 0, 0, 0 } }), { &sphere }), md::InputError);
  EXPECT_THROW(md::PathOverBones(Path({ { 0, 0, 0 }, { NAN, 0, 0 } }), { &sphere }), md::InputError);
  md::PathOverBonesParameters none;
  none.pointsPerSegment = 0;
  try
  {
    md::PathOverBones(Path({ { 0, 0, 0 }, { 1, 0, 0 } }), { &sphere }, none);
    FAIL() << "no error";
  }
  catch (const md::InputError& e)
  {
    EXPECT_NE(std::string(e.what()).find("at least one point per segment"), std::string::npos) << e.what();
  }
}
