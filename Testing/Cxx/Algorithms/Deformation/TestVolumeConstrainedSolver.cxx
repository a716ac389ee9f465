// SPDX-License-Identifier: BSD-3-Clause
#include "Deformation/VolumeConstrainedSolver.h"
#include "Hull/ProgressiveHull.h"
#include "Phantom/Phantom.h"
#include "TestMeshes.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

using md::Points;
using md::SparseMatrix;
using md::TriangleMesh;

namespace
{
TriangleMesh CoarseMuscleHull()
{
  const TriangleMesh muscle = md::BuildPhantom(md::PhantomParameters{}).muscles[0].rest;
  md::HullParameters parameters;
  parameters.targetNumberOfPoints = 60;
  return md::BuildProgressiveHull(muscle, parameters).hull;
}

/// Laplacian rows (targets: the rest-pose Laplacian coordinates) stacked on
/// rows fixing a few anchor points (targets: where the anchors should go).
struct Problem
{
  SparseMatrix rows;
  Points targets;
};

Problem StretchProblem(const TriangleMesh& hull, double stretch)
{
  const SparseMatrix laplacian = md::CotangentLaplacian(hull);
  const Eigen::Index n = hull.points.rows();
  // Anchors at both ends of the muscle's long axis, moved apart by `stretch`.
  const Eigen::RowVector3d centre = hull.points.colwise().mean();
  Eigen::Index top = 0, bottom = 0;
  for (Eigen::Index i = 0; i < n; ++i)
  {
    top = hull.points(i, 2) > hull.points(top, 2) ? i : top;
    bottom = hull.points(i, 2) < hull.points(bottom, 2) ? i : bottom;
  }
  std::vector<Eigen::Triplet<double>> entries;
  for (Eigen::Index i = 0; i < laplacian.outerSize(); ++i)
  {
    for (SparseMatrix::InnerIterator it(laplacian, i); it; ++it)
    {
      entries.emplace_back(it.row(), it.col(), it.value());
    }
  }
  entries.emplace_back(n, top, 1.0);
  entries.emplace_back(n + 1, bottom, 1.0);
  Problem problem;
  problem.rows.resize(n + 2, n);
  problem.rows.setFromTriplets(entries.begin(), entries.end());
  problem.targets.resize(n + 2, 3);
  problem.targets.topRows(n) = laplacian * hull.points;
  problem.targets.row(n) = centre + stretch * (hull.points.row(top) - centre);
  problem.targets.row(n + 1) = centre + stretch * (hull.points.row(bottom) - centre);
  return problem;
}
}

TEST(CotangentLaplacian, RowsSumToZeroAndARegularOctahedronHasEqualWeights)
{
  const TriangleMesh octahedron = Octahedron();
  const SparseMatrix l = md::CotangentLaplacian(octahedron);
  for (Eigen::Index i = 0; i < 6; ++i)
  {
    EXPECT_NEAR(l.row(i).sum(), 0.0, 1e-15);
    EXPECT_DOUBLE_EQ(l.coeff(i, i), -1.0);
  }
  EXPECT_NEAR(l.coeff(0, 2), 0.25, 1e-15);
  EXPECT_NEAR(l.coeff(0, 1), 0.0, 1e-15); // opposite points are not neighbours
  const TriangleMesh hull = CoarseMuscleHull();
  const SparseMatrix m = md::CotangentLaplacian(hull);
  EXPECT_LT((m * Eigen::VectorXd::Ones(hull.points.rows())).cwiseAbs().maxCoeff(), 1e-13);
}

TEST(CotangentLaplacian, ClampedWeightsAreNeverNegativeAndASliverDoesNotTieItsShortEdge)
{
  // A coarse hull has obtuse angles: unclamped, some weights are negative; clamped to [0, 3],
  // none is, and the rows still sum to zero.
  auto offDiagonalRange = [](const SparseMatrix& l) {
    std::pair<double, double> range{ 0, 0 };
    for (Eigen::Index i = 0; i < l.outerSize(); ++i)
    {
      for (SparseMatrix::InnerIterator it(l, i); it; ++it)
      {
        if (it.col() != i)
        {
          range = { std::min(range.first, it.value()), std::max(range.second, it.value()) };
        }
      }
    }
    return range;
  };
  const TriangleMesh hull = CoarseMuscleHull();
  EXPECT_LT(offDiagonalRange(md::CotangentLaplacian(hull)).first, -0.1);
  const SparseMatrix clampedHull = md::CotangentLaplacian(hull, 3.0);
  EXPECT_EQ(offDiagonalRange(clampedHull).first, 0.0);
  EXPECT_LT((clampedHull * Eigen::VectorXd::Ones(hull.points.rows())).cwiseAbs().maxCoeff(), 1e-13);

  // An octahedron with its top pulled down next to point 0: the triangles between them are
  // slivers. Unclamped, point 0's row puts 99 % of its weight on the short edge to the top
  // and next to none on its other neighbours; clamped, they keep a share.
  TriangleMesh sliver = Octahedron();
  sliver.points.row(4) << 0.98, 0, 0.02;
  const SparseMatrix plain = md::CotangentLaplacian(sliver);
  const SparseMatrix clamped = md::CotangentLaplacian(sliver, 3.0);
  EXPECT_GT(plain.coeff(0, 4), 0.98);
  EXPECT_LT(plain.coeff(0, 2), 0.001);
  EXPECT_LT(clamped.coeff(0, 4), 0.75);
  EXPECT_GT(clamped.coeff(0, 2), 0.05);
  EXPECT_NEAR(clamped.row(0).sum(), 0.0, 1e-15);

  // Well-shaped triangles are left as they are.
  const TriangleMesh octahedron = Octahedron();
  EXPECT_LT(
    (Eigen::MatrixXd(md::CotangentLaplacian(octahedron, 3.0)) - Eigen::MatrixXd(md::CotangentLaplacian(octahedron)))
      .cwiseAbs()
      .maxCoeff(),
    1e-15);
}

TEST(EnclosedVolume, GradientMatchesFiniteDifferences)
{
  const TriangleMesh hull = CoarseMuscleHull();
  Points gradient;
  const double volume = md::EnclosedVolume(hull.points, hull.triangles, &gradient);
  EXPECT_NEAR(volume, md::EnclosedVolume(hull.points, hull.triangles), 0.0);
  const double h = 1e-4;
  for (Eigen::Index i : { 0, 7, 31 })
  {
    for (int c = 0; c < 3; ++c)
    {
      Points plus = hull.points, minus = hull.points;
      plus(i, c) += h;
      minus(i, c) -= h;
      const double difference =
        (md::EnclosedVolume(plus, hull.triangles) - md::EnclosedVolume(minus, hull.triangles)) / (2 * h);
      EXPECT_NEAR(gradient(i, c), difference, 1e-6 * std::abs(difference) + 1e-9);
    }
  }
}

namespace
{
/// The original implementation's step, written out here to show its error: the J A L^T r term of
/// lambda with the wrong sign (VolumeConstrainedSolver::Step is the corrected one).
Points OriginalStep(
  const md::VolumeConstrainedSolver& solver, const Points& x, const Points& targets, double targetVolume, double alpha)
{
  Points gradient;
  const double volume = md::EnclosedVolume(x, solver.Faces, &gradient);
  const Eigen::MatrixXd aPulled =
    solver.Normal.solve(Eigen::MatrixXd(solver.Rows.transpose() * (solver.Rows * x - targets)));
  const Eigen::MatrixXd aGradient = solver.Normal.solve(Eigen::MatrixXd(gradient));
  const double jaj = (gradient.array() * aGradient.array()).sum();
  const double jalr = (gradient.array() * aPulled.array()).sum();
  const double lambda = ((volume - targetVolume) / alpha + jalr) / jaj;
  return x - alpha * (aPulled + lambda * aGradient);
}
}

TEST(VolumeConstrainedSolver, VolumeConvergesToTheRestVolumeWhereTheOriginalFormulaMisses)
{
  const TriangleMesh hull = CoarseMuscleHull();
  const Problem problem = StretchProblem(hull, 1.3); // unconstrained, the muscle would swell by ~30 %
  const md::VolumeConstrainedSolver solver(problem.rows, hull.triangles);
  const double restVolume = md::EnclosedVolume(hull.points, hull.triangles);
  for (double alpha : { 0.1, 0.3 })
  {
    Points corrected = hull.points, original = hull.points;
    for (int iteration = 0; iteration < 400; ++iteration)
    {
      corrected = solver.Step(corrected, problem.targets, restVolume, alpha);
      original = OriginalStep(solver, original, problem.targets, restVolume, alpha);
    }
    const double correctedError = std::abs(md::EnclosedVolume(corrected, hull.triangles) / restVolume - 1);
    const double originalError = std::abs(md::EnclosedVolume(original, hull.triangles) / restVolume - 1);
    std::cout << "[ measured ] step length " << alpha << ": volume error " << 100 * correctedError << " % (corrected), "
              << 100 * originalError << " % (original sign)\n";
    EXPECT_LT(correctedError, 1e-8) << "alpha " << alpha;
    EXPECT_GT(originalError, 1e-3) << "alpha " << alpha;
    // The anchors did move: the muscle was stretched, at constant volume.
    const Eigen::Index n = hull.points.rows();
    const Points anchors = problem.rows.bottomRows(2) * corrected;
    EXPECT_LT((anchors - problem.targets.bottomRows(2)).rowwise().norm().maxCoeff(),
      0.25 * (problem.targets.row(n) - problem.targets.row(n + 1)).norm());
  }
}

TEST(VolumeConstrainedSolver, FollowsATranslationExactly)
{
  const TriangleMesh hull = CoarseMuscleHull();
  Problem problem = StretchProblem(hull, 1.0);
  const Eigen::RowVector3d shift(12.0, -3.0, 7.5);
  const Eigen::Index n = hull.points.rows();
  problem.targets.bottomRows(2).rowwise() += shift;
  const md::VolumeConstrainedSolver solver(problem.rows, hull.triangles);
  const double restVolume = md::EnclosedVolume(hull.points, hull.triangles);
  Points x = hull.points;
  for (int iteration = 0; iteration < 200; ++iteration)
  {
    x = solver.Step(x, problem.targets, restVolume, 0.3);
  }
  const Points expected = hull.points.rowwise() + shift;
  EXPECT_LT((x - expected).rowwise().norm().maxCoeff(), 1e-8 * (hull.points.row(0) - hull.points.row(n - 1)).norm());
}

TEST(VolumeConstrainedSolver, RefusesASystemThatDoesNotFixThePosition)
{
  const TriangleMesh hull = CoarseMuscleHull();
  EXPECT_THROW(md::VolumeConstrainedSolver(md::CotangentLaplacian(hull), hull.triangles), md::InputError);
}

TEST(VolumeConstrainedSolver, RowsAppendedGiveTheSameStepsAsTheStackedSystem)
{
  // The contact rows of the deformation are appended to a solver already
  // factored: the result must be the solver of all the rows stacked.
  const TriangleMesh hull = CoarseMuscleHull();
  const Problem problem = StretchProblem(hull, 1.2);
  const Eigen::Index n = hull.points.rows(), rows = problem.rows.rows();
  Eigen::MatrixXd extra = Eigen::MatrixXd::Zero(3, n);
  extra(0, 3) = 0.5;
  extra(1, 7) = 0.3;
  extra(1, 8) = 0.2;
  extra(2, n - 1) = 1.0;
  Points extraTargets(3, 3);
  extraTargets << 1.0, 2.0, 3.0, -4.0, 0.5, 2.0, 0.0, 0.0, 9.0;

  SparseMatrix stacked(rows + 3, n);
  std::vector<Eigen::Triplet<double>> entries;
  for (Eigen::Index r = 0; r < rows; ++r)
  {
    for (SparseMatrix::InnerIterator it(problem.rows, r); it; ++it)
    {
      entries.emplace_back(r, it.col(), it.value());
    }
  }
  for (Eigen::Index r = 0; r < 3; ++r)
  {
    for (Eigen::Index c = 0; c < n; ++c)
    {
      if (extra(r, c) != 0)
      {
        entries.emplace_back(rows + r, c, extra(r, c));
      }
    }
  }
  stacked.setFromTriplets(entries.begin(), entries.end());
  Points targets(rows + 3, 3);
  targets << problem.targets, extraTargets;

  const md::VolumeConstrainedSolver base(problem.rows, hull.triangles);
  const md::VolumeConstrainedSolver appended(base, extra);
  const md::VolumeConstrainedSolver direct(stacked, hull.triangles);
  ASSERT_EQ(appended.Rows.rows(), rows + 3);
  const double restVolume = md::EnclosedVolume(hull.points, hull.triangles);
  Points a = hull.points, d = hull.points;
  for (int iteration = 0; iteration < 5; ++iteration)
  {
    a = appended.Step(a, targets, restVolume, 1.0);
    d = direct.Step(d, targets, restVolume, 1.0);
  }
  const double scale = (hull.points.colwise().maxCoeff() - hull.points.colwise().minCoeff()).norm();
  EXPECT_LT((a - d).cwiseAbs().maxCoeff(), 1e-9 * scale);
  EXPECT_GT((a - hull.points).cwiseAbs().maxCoeff(), 1e-3 * scale); // the rows did move it
}
