// SPDX-License-Identifier: BSD-3-Clause
// Mean value coordinates (MeanValueCoordinates.h) against the reference formula, on and near the cage too.
#include "Geometry/MeanValueCoordinates.h"
#include "Hull/ProgressiveHull.h"
#include "Phantom/Phantom.h"
#include "TestMeshes.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

using md::Points;
using md::TriangleMesh;
using md::Triangles;

namespace
{
/// Mean value coordinates by the pseudo-code of Ju, Schaefer & Warren 2005
/// (for points well inside: the reference the robust implementation must match).
Eigen::RowVectorXd ReferenceMeanValueCoordinates(const TriangleMesh& cage, const Eigen::Vector3d& x)
{
  const Eigen::Index n = cage.points.rows();
  Eigen::RowVectorXd w = Eigen::RowVectorXd::Zero(n);
  std::vector<double> d(n);
  std::vector<Eigen::Vector3d> u(n);
  for (Eigen::Index j = 0; j < n; ++j)
  {
    const Eigen::Vector3d v = cage.points.row(j).transpose() - x;
    d[j] = v.norm();
    u[j] = v / d[j];
  }
  for (Eigen::Index t = 0; t < cage.triangles.rows(); ++t)
  {
    const std::int64_t p[3] = { cage.triangles(t, 0), cage.triangles(t, 1), cage.triangles(t, 2) };
    double theta[3];
    for (int i = 0; i < 3; ++i)
    {
      const double l = (u[p[(i + 1) % 3]] - u[p[(i + 2) % 3]]).norm();
      theta[i] = 2 * std::asin(l / 2);
    }
    const double h = (theta[0] + theta[1] + theta[2]) / 2;
    const double sign = u[p[0]].dot(u[p[1]].cross(u[p[2]])) < 0 ? -1 : 1;
    double c[3], s[3];
    for (int i = 0; i < 3; ++i)
    {
      c[i] =
        2 * std::sin(h) * std::sin(h - theta[i]) / (std::sin(theta[(i + 1) % 3]) * std::sin(theta[(i + 2) % 3])) - 1;
      s[i] = sign * std::sqrt(1 - c[i] * c[i]);
    }
    for (int i = 0; i < 3; ++i)
    {
      const int a = (i + 1) % 3, b = (i + 2) % 3;
      w(p[i]) += (theta[i] - c[a] * theta[b] - c[b] * theta[a]) / (d[p[i]] * std::sin(theta[a]) * s[b]);
    }
  }
  return w / w.sum();
}

double Size(const Points& p)
{
  return (p.colwise().maxCoeff() - p.colwise().minCoeff()).norm();
}
}

TEST(MeanValueCoordinates, MatchTheReferenceFormulaInside)
{
  const TriangleMesh muscle = md::BuildPhantom(md::PhantomParameters{}).muscles[1].rest;
  md::HullParameters parameters;
  parameters.targetNumberOfPoints = 60;
  const TriangleMesh cage = md::BuildProgressiveHull(muscle, parameters).hull;
  const md::MeanValueCoordinateCalculator mvc(cage);
  Eigen::RowVectorXd weights(cage.points.rows());
  std::mt19937 generator(7);
  std::uniform_int_distribution<Eigen::Index> pick(0, muscle.points.rows() - 1);
  const Eigen::RowVector3d centre = muscle.points.colwise().mean();
  for (int sample = 0; sample < 50; ++sample)
  {
    // Halfway between the centre and a muscle point: well inside the cage.
    const Eigen::Vector3d x = (0.5 * (centre + muscle.points.row(pick(generator)))).transpose();
    mvc.Compute(x, weights);
    const Eigen::RowVectorXd reference = ReferenceMeanValueCoordinates(cage, x);
    EXPECT_LT((weights - reference).cwiseAbs().maxCoeff(), 1e-10);
  }
}

TEST(MeanValueCoordinates, ReproduceLinearFunctionsEverywhereIncludingOnAndNearTheCage)
{
  const TriangleMesh cage = Octahedron();
  const md::MeanValueCoordinateCalculator mvc(cage);
  Eigen::RowVectorXd w(6);
  const Eigen::Vector3d faceCentre = (cage.points.row(0) + cage.points.row(2) + cage.points.row(4)).transpose() / 3;
  const Eigen::Vector3d faceNormal = Eigen::Vector3d(1, 1, 1).normalized();
  const Eigen::Vector3d edgeMiddle = 0.5 * (cage.points.row(0) + cage.points.row(2)).transpose();
  std::vector<Eigen::Vector3d> points = {
    Eigen::Vector3d::Zero(), Eigen::Vector3d(0.2, -0.1, 0.3),                   // inside
    faceCentre, faceCentre + 1e-9 * faceNormal, faceCentre - 1e-9 * faceNormal, // on and near a face
    faceCentre + 1e-13 * faceNormal, edgeMiddle, edgeMiddle * (1 - 1e-10),      // on and near an edge
    Eigen::Vector3d(1, 0, 0), Eigen::Vector3d(1 - 1e-10, 1e-11, 0),             // on and near a cage point
    Eigen::Vector3d(2, 1, -1), Eigen::Vector3d(0.7, 0.7, 0.0),                  // outside
  };
  for (const Eigen::Vector3d& x : points)
  {
    mvc.Compute(x, w);
    EXPECT_NEAR(w.sum(), 1.0, 1e-13) << x.transpose();
    EXPECT_LT((w * cage.points - x.transpose()).norm(), 1e-13) << x.transpose();
    EXPECT_TRUE(w.allFinite()) << x.transpose();
  }
  mvc.Compute(Eigen::Vector3d::Zero(), w);
  EXPECT_LT((w.array() - 1.0 / 6.0).abs().maxCoeff(), 1e-14) << "symmetry: equal weights at the centre";
  // Positive inside a convex cage (a non-convex one can give small negative weights).
  std::mt19937 generator(3);
  std::uniform_real_distribution<double> coordinate(-0.3, 0.3);
  for (int sample = 0; sample < 100; ++sample)
  {
    mvc.Compute(Eigen::Vector3d(coordinate(generator), coordinate(generator), coordinate(generator)), w);
    EXPECT_GT(w.minCoeff(), 0.0);
  }
  mvc.Compute(faceCentre, w);
  EXPECT_NEAR(w(0), 1.0 / 3, 1e-13);
  EXPECT_NEAR(w(1), 0.0, 1e-13);
  mvc.Compute(Eigen::Vector3d(1, 0, 0), w);
  EXPECT_NEAR(w(0), 1.0, 1e-15);
}

TEST(MeanValueCoordinates, WeightMatrixOfManyPoints)
{
  const TriangleMesh muscle = md::BuildPhantom(md::PhantomParameters{}).muscles[0].rest;
  const TriangleMesh cage = md::BuildProgressiveHull(muscle, md::HullParameters{}).hull;
  const md::WeightMatrix weights = md::MeanValueCoordinates(cage, muscle.points);
  ASSERT_EQ(weights.rows(), muscle.points.rows());
  ASSERT_EQ(weights.cols(), cage.points.rows());
  EXPECT_LT((weights * cage.points - muscle.points).rowwise().norm().maxCoeff(), 1e-9 * Size(muscle.points));
  EXPECT_LT((weights.rowwise().sum().array() - 1.0).abs().maxCoeff(), 1e-13);
  EXPECT_THROW(md::MeanValueCoordinateCalculator(TriangleMesh{ Points(3, 3), Triangles(1, 3) }), md::InputError);
}
