// SPDX-License-Identifier: BSD-3-Clause
#include "Geometry/MeshChecks.h"
#include "Geometry/TriangleTree.h"
#include "Phantom/Phantom.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <random>

namespace
{
const md::Phantom& TestPhantom()
{
  static const md::Phantom phantom = md::BuildPhantom(md::PhantomParameters{});
  return phantom;
}

md::TriangleMesh Femur()
{
  const md::PhantomBone& femur = TestPhantom().bones[1];
  return md::TriangleMesh{ femur.currentPoints, femur.rest.triangles };
}

Eigen::Vector3d RandomPoint(std::mt19937& generator, const md::TriangleMesh& mesh, double margin)
{
  const Eigen::Vector3d low = mesh.points.colwise().minCoeff().transpose().array() - margin;
  const Eigen::Vector3d high = mesh.points.colwise().maxCoeff().transpose().array() + margin;
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  return low + (high - low).cwiseProduct(Eigen::Vector3d(unit(generator), unit(generator), unit(generator)));
}
}

TEST(TriangleTree, InsideAgreesWithTheWindingNumber)
{
  const md::TriangleMesh femur = Femur();
  const md::TriangleTree tree(femur);
  std::mt19937 generator(11);
  int inside = 0;
  for (int i = 0; i < 2000; ++i)
  {
    // Near the bone: half the points come from its surface, pushed a little in or out.
    Eigen::Vector3d p = RandomPoint(generator, femur, 10.0);
    if (i % 2 == 0)
    {
      const Eigen::Index v = static_cast<Eigen::Index>(generator() % femur.points.rows());
      p = femur.points.row(v).transpose() + (RandomPoint(generator, femur, 0) - p).normalized() * 0.5;
    }
    const bool expected = md::WindingNumber(femur.points, femur.triangles, p) > 0.5;
    if (tree.ClosestPoint(p).distance < 1e-6)
    {
      continue; // on the surface: either answer is right
    }
    EXPECT_EQ(tree.Inside(p), expected) << p.transpose();
    inside += expected ? 1 : 0;
  }
  EXPECT_GT(inside, 200);
  // The rest-pose muscles are outside the femur; at 60 degrees some rectus femoris points are in.
  const md::TriangleMesh& rectus = TestPhantom().muscles[2].rest;
  int rectusInside = 0;
  for (Eigen::Index i = 0; i < rectus.points.rows(); ++i)
  {
    rectusInside += tree.Inside(rectus.points.row(i).transpose()) ? 1 : 0;
  }
  EXPECT_EQ(rectusInside, md::CountInside(femur.points, femur.triangles, rectus.points));
  EXPECT_GT(rectusInside, 50);
}

TEST(TriangleTree, WindingCountsHowOftenTheSurfaceCoversAPoint)
{
  // Two femurs, the second moved by a fifth of its width: one surface that covers the overlap
  // twice (as a muscle does where it folds through itself).
  const md::TriangleMesh femur = Femur();
  const double width = (femur.points.colwise().maxCoeff() - femur.points.colwise().minCoeff()).minCoeff();
  md::TriangleMesh both;
  both.points.resize(2 * femur.points.rows(), 3);
  both.points << femur.points, femur.points.rowwise() + Eigen::RowVector3d(width / 5, 0.05 * width, 0.02 * width);
  both.triangles.resize(2 * femur.triangles.rows(), 3);
  both.triangles << femur.triangles, femur.triangles.array() + static_cast<int>(femur.points.rows());
  const md::TriangleTree tree(both);
  std::mt19937 generator(23);
  std::array<int, 3> seen{};
  for (int i = 0; i < 1500; ++i)
  {
    // Within half the bone's width of its surface, in any direction.
    const Eigen::Index v = static_cast<Eigen::Index>(generator() % both.points.rows());
    const Eigen::Vector3d offset = RandomPoint(generator, both, 0.0) - RandomPoint(generator, both, 0.0);
    const Eigen::Vector3d p = both.points.row(v).transpose() +
      0.5 * width * offset.normalized() * std::uniform_real_distribution<double>(0.0, 1.0)(generator);
    if (tree.ClosestPoint(p).distance < 1e-6)
    {
      continue;
    }
    const long expected = std::lround(md::WindingNumber(both.points, both.triangles, p));
    ASSERT_EQ(tree.Winding(p), expected) << p.transpose();
    ++seen[size_t(std::clamp<long>(expected, 0, 2))];
  }
  // Every case met often: outside, covered once, covered twice.
  EXPECT_GT(seen[0], 500);
  EXPECT_GT(seen[1], 200);
  EXPECT_GT(seen[2], 50);
}

TEST(TriangleTree, AHintChangesNotTheClosestPoint)
{
  const md::TriangleMesh femur = Femur();
  const md::TriangleTree tree(femur);
  std::mt19937 generator(31);
  for (int i = 0; i < 500; ++i)
  {
    const Eigen::Vector3d p = RandomPoint(generator, femur, 10.0);
    const Eigen::Index hint = static_cast<Eigen::Index>(generator() % femur.triangles.rows());
    const double within = i % 2 ? 5.0 : std::numeric_limits<double>::max();
    const md::TriangleTree::Closest plain = tree.ClosestPoint(p, within);
    const md::TriangleTree::Closest hinted = tree.ClosestPoint(p, within, hint);
    ASSERT_EQ(plain.triangle >= 0, hinted.triangle >= 0) << p.transpose();
    if (plain.triangle >= 0)
    {
      EXPECT_EQ(hinted.distance, plain.distance);
      EXPECT_LT((hinted.point - plain.point).norm(), 1e-12);
    }
  }
}

TEST(TriangleTree, FirstHitCrossingsAndClosestPointAgreeWithBruteForce)
{
  const md::TriangleMesh femur = Femur();
  const md::TriangleTree tree(femur);
  std::mt19937 generator(5);
  int hits = 0;
  for (int i = 0; i < 300; ++i)
  {
    const Eigen::Vector3d from = RandomPoint(generator, femur, 30.0);
    const Eigen::Vector3d to = RandomPoint(generator, femur, 30.0);
    // Brute force: the smallest segment fraction over all triangles.
    double bestT = std::numeric_limits<double>::max();
    int crossings = 0;
    for (Eigen::Index t = 0; t < femur.triangles.rows(); ++t)
    {
      const Eigen::Vector3d a = femur.points.row(femur.triangles(t, 0)).transpose();
      const Eigen::Vector3d b = femur.points.row(femur.triangles(t, 1)).transpose();
      const Eigen::Vector3d c = femur.points.row(femur.triangles(t, 2)).transpose();
      const Eigen::Vector3d d = to - from;
      const Eigen::Matrix3d m = (Eigen::Matrix3d() << b - a, c - a, -d).finished();
      const Eigen::Vector3d uvt = m.fullPivLu().solve(from - a);
      if (uvt[0] >= 0 && uvt[1] >= 0 && uvt[0] + uvt[1] <= 1 && uvt[2] >= 0 && uvt[2] <= 1)
      {
        bestT = std::min(bestT, uvt[2]);
        ++crossings;
      }
    }
    EXPECT_EQ(tree.Crossings(from, to), crossings) << from.transpose() << " -> " << to.transpose();
    if (tree.ClosestPoint(to).distance > 1e-6 && tree.ClosestPoint(from).distance > 1e-6)
    {
      // An odd count: the ends are on opposite sides of the surface.
      EXPECT_EQ(crossings % 2 == 1, tree.Inside(from) != tree.Inside(to));
    }
    const auto hit = tree.FirstHit(from, to);
    ASSERT_EQ(hit.has_value(), bestT <= 1.0) << from.transpose() << " -> " << to.transpose();
    if (hit)
    {
      ++hits;
      EXPECT_NEAR(hit->t, bestT, 1e-9);
      EXPECT_LT((hit->point - (from + bestT * (to - from))).norm(), 1e-6);
    }
    // Closest point, against every triangle.
    double nearest = std::numeric_limits<double>::max();
    for (Eigen::Index t = 0; t < femur.triangles.rows(); ++t)
    {
      nearest = std::min(nearest,
        md::PointTriangleDistance(from, femur.points.row(femur.triangles(t, 0)).transpose(),
          femur.points.row(femur.triangles(t, 1)).transpose(), femur.points.row(femur.triangles(t, 2)).transpose()));
    }
    const md::TriangleTree::Closest closest = tree.ClosestPoint(from);
    EXPECT_NEAR(closest.distance, nearest, 1e-9);
    EXPECT_NEAR((closest.point - from).norm(), nearest, 1e-9);
  }
  EXPECT_GT(hits, 50);
}

TEST(TriangleTree, RefusesAnEmptyMesh)
{
  EXPECT_THROW(md::TriangleTree(md::TriangleMesh{ md::Points(0, 3), md::Triangles(0, 3) }), md::InputError);
}

TEST(TriangleTree, RefitAnswersLikeATreeBuiltOnTheMovedPoints)
{
  const md::TriangleMesh bone = md::BuildPhantom(md::PhantomParameters{}).bones[1].rest;
  md::TriangleMesh moved = bone;
  // Bend it: a smooth, non-rigid displacement.
  for (Eigen::Index i = 0; i < moved.points.rows(); ++i)
  {
    moved.points(i, 0) += 0.002 * moved.points(i, 2) * moved.points(i, 2);
  }
  md::TriangleTree refitted(bone);
  refitted.Refit(moved.points);
  const md::TriangleTree rebuilt(moved);
  std::mt19937 generator(3);
  const Eigen::Vector3d low = moved.points.colwise().minCoeff().transpose();
  const Eigen::Vector3d high = moved.points.colwise().maxCoeff().transpose();
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  for (int q = 0; q < 500; ++q)
  {
    const Eigen::Vector3d p =
      low + (high - low).cwiseProduct(Eigen::Vector3d(unit(generator), unit(generator), unit(generator)));
    const Eigen::Vector3d to =
      low + (high - low).cwiseProduct(Eigen::Vector3d(unit(generator), unit(generator), unit(generator)));
    EXPECT_EQ(refitted.Inside(p), rebuilt.Inside(p));
    EXPECT_NEAR(refitted.ClosestPoint(p).distance, rebuilt.ClosestPoint(p).distance, 1e-9);
    const auto a = refitted.FirstHit(p, to), b = rebuilt.FirstHit(p, to);
    ASSERT_EQ(a.has_value(), b.has_value());
    if (a)
    {
      EXPECT_NEAR(a->t, b->t, 1e-12);
    }
  }
  EXPECT_THROW(refitted.Refit(moved.points.topRows(3)), md::InputError);
}

// The distance grid's bounds hold the true signed distance (negative inside, by the winding
// number), at points near the surface and far from it, beyond the grid too; a refit drops it.
TEST(TriangleTree, DistanceGridBoundsHoldTheSignedDistance)
{
  const md::TriangleMesh femur = Femur();
  md::TriangleTree tree(femur);
  EXPECT_FALSE(tree.SignedDistanceBounds(femur.points.row(0).transpose()).has_value());
  tree.BuildDistanceGrid(4096);
  std::mt19937 generator(5);
  const double size = md::BoxDiagonal(femur.points);
  int decided = 0;
  for (int i = 0; i < 3000; ++i)
  {
    const Eigen::Vector3d p = RandomPoint(generator, femur, 0.2 * size);
    const double distance = tree.ClosestPoint(p).distance;
    const double signedDistance = md::WindingNumber(femur.points, femur.triangles, p) > 0.5 ? -distance : distance;
    const auto bounds = tree.SignedDistanceBounds(p);
    ASSERT_TRUE(bounds.has_value());
    EXPECT_LE(bounds->first, signedDistance) << i;
    EXPECT_GE(bounds->second, signedDistance) << i;
    decided += bounds->first > 0 || bounds->second < 0; // the side known without a search
  }
  EXPECT_GT(decided, 2000);
  tree.Refit(femur.points);
  EXPECT_FALSE(tree.SignedDistanceBounds(femur.points.row(0).transpose()).has_value());
}

// A bone collapsed to one point (a fuzzed input) gets no grid rather than a grid of no cell size.
TEST(TriangleTree, ASurfaceOfOnePointGetsNoDistanceGrid)
{
  md::TriangleMesh collapsed = Femur();
  collapsed.points.rowwise() = collapsed.points.row(0);
  md::TriangleTree tree(collapsed);
  tree.BuildDistanceGrid();
  EXPECT_FALSE(tree.SignedDistanceBounds(Eigen::Vector3d(1, 2, 3)).has_value());
}

TEST(TriangleTree, FirstEntryMeetsOnlyTrianglesEnteredFromOutside)
{
  // A unit cube (outward): from outside, the segment enters at x = 0; from inside, it passes the
  // face it leaves through and meets nothing; through the cube, the entry again.
  md::TriangleMesh cube;
  cube.points.resize(8, 3);
  for (int i = 0; i < 8; ++i)
  {
    cube.points.row(i) << (i & 1 ? 1.0 : 0.0), (i & 2 ? 1.0 : 0.0), (i & 4 ? 1.0 : 0.0);
  }
  cube.triangles.resize(12, 3);
  cube.triangles << 0, 2, 1, 1, 2, 3, 4, 5, 6, 5, 7, 6, 0, 1, 4, 1, 5, 4, 2, 6, 3, 3, 6, 7, 0, 4, 2, 2, 4, 6, 1, 3, 5,
    3, 7, 5;
  ASSERT_GT(md::SignedVolume(cube.points, cube.triangles), 0);
  const md::TriangleTree tree(cube);
  const auto entry = tree.FirstEntry({ -1, 0.3, 0.4 }, { 3, 0.3, 0.4 });
  ASSERT_TRUE(entry);
  EXPECT_NEAR(entry->point.x(), 0.0, 1e-12);
  EXPECT_FALSE(tree.FirstEntry({ 0.5, 0.3, 0.4 }, { 3, 0.3, 0.4 }));
  ASSERT_TRUE(tree.FirstHit({ 0.5, 0.3, 0.4 }, { 3, 0.3, 0.4 }));
  const auto back = tree.FirstEntry({ 3, 0.3, 0.4 }, { -1, 0.3, 0.4 });
  ASSERT_TRUE(back);
  EXPECT_NEAR(back->point.x(), 1.0, 1e-12);
}
