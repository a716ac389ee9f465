// SPDX-License-Identifier: BSD-3-Clause
// Rigid motions: composing and undoing them, fitting one to moved points (Kabsch) and the best
// rotation in closed form, and the screw motion that moves a body part of the way.
#include "Geometry/RigidMotion.h"
#include "TestMeshes.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>

using md::Points;

namespace
{
/// A rotation drawn from four coordinates uniform in [-1, 1] (a quaternion normalised).
Eigen::Matrix3d RandomRotation(std::mt19937& generator)
{
  std::uniform_real_distribution<double> entry(-1, 1);
  return Eigen::Quaterniond(Eigen::Vector4d::NullaryExpr([&](Eigen::Index) { return entry(generator); }).normalized())
    .toRotationMatrix();
}

const Eigen::Vector3d joint(143.5, 243.4, -432.7);
const Eigen::Vector3d axis = Eigen::Vector3d(1, 0.1, -0.05).normalized();
}

TEST(RigidMotion, ComposeAndInverseUndoEachOther)
{
  md::RigidTransform t = md::RigidTransform::AboutPoint(axis, 0.7, joint);
  t.translation += Eigen::Vector3d(0.4, 0.1, -2.0);
  const md::RigidTransform identity = md::Compose(md::Inverse(t), t);
  EXPECT_LE((identity.rotation - Eigen::Matrix3d::Identity()).norm(), 1e-14);
  EXPECT_LE(identity.translation.norm(), 1e-12);
  const Eigen::Vector3d x(0.3, -2, 5);
  EXPECT_LE((md::Compose(t, t).Apply(x) - t.Apply(t.Apply(x))).norm(), 1e-12);
}

TEST(RigidMotion, AboutPointTurnsAboutTheCentre)
{
  const Eigen::Vector3d centre(3, -1, 2);
  const md::RigidTransform t = md::RigidTransform::AboutPoint(Eigen::Vector3d(0, 0, 2), M_PI / 2, centre);
  EXPECT_LE((t.Apply(centre) - centre).norm(), 1e-15);
  EXPECT_LE((t.Apply(Eigen::Vector3d(4, -1, 2)) - Eigen::Vector3d(3, 0, 2)).norm(), 1e-15);
  EXPECT_NEAR(t.rotation.determinant(), 1.0, 1e-15);
}

TEST(RigidMotion, KabschRecoversAKnownTransform)
{
  const Points rest = RandomCloud(200, 1, 50);
  md::RigidTransform truth = md::RigidTransform::AboutPoint(axis, 1.1, joint);
  truth.translation += Eigen::Vector3d(3, -4, 5);
  const md::RigidFit fit = md::FitRigidTransform(rest, truth.Apply(rest));
  EXPECT_TRUE(fit.transform.rotation.isApprox(truth.rotation, 1e-12));
  EXPECT_TRUE(fit.transform.translation.isApprox(truth.translation, 1e-10));
  EXPECT_LT(fit.maxResidual, 1e-10);
  EXPECT_NEAR(fit.transform.rotation.determinant(), 1.0, 1e-12);
}

TEST(RigidMotion, TheDirectBestRotationIsTheSvdsToRounding)
{
  // Covariances as the flipped-triangle count builds them: general, flat (rank 2: a surface's
  // edges), mirrored (det < 0), with two singular values nearly equal (a regular fan, where the
  // closed form's eigenvectors lose digits), with one clear of zero only, and mirrored with the two
  // smaller alike (no one rotation is the answer in these two: any of the best will do, as the
  // SVD's pick does).
  std::mt19937 generator(7);
  std::uniform_real_distribution<double> entry(-1, 1);
  auto rotation = [&] {
    return RandomRotation(generator);
  };
  double worst = 0;
  for (int k = 0; k < 2000; ++k)
  {
    Eigen::Vector3d singular(1 + entry(generator), 1 + entry(generator), 1 + entry(generator));
    switch (k % 6)
    {
      case 1:
        singular(2) = 0;
        break;
      case 2:
        singular(2) = -singular(2);
        break;
      case 3:
        singular(1) = singular(0) * (1 + 1e-9 * entry(generator));
        break;
      case 4:
        singular(1) = singular(2) = 0;
        break;
      case 5:
        singular(2) = -singular(1);
        break;
      default:
        break;
    }
    const Eigen::Matrix3d covariance = 30 * rotation() * singular.asDiagonal() * rotation();
    const Eigen::Matrix3d direct = md::BestRotationDirect(covariance);
    const Eigen::Matrix3d svd = md::BestRotation(covariance);
    EXPECT_NEAR(direct.determinant(), 1.0, 1e-12) << "case " << k % 6 << " singular values " << singular.transpose();
    EXPECT_TRUE((direct.transpose() * direct).isApprox(Eigen::Matrix3d::Identity(), 1e-12));
    // As good a fit as the SVD's: the largest trace(R^T C) a rotation reaches.
    EXPECT_NEAR(
      (direct.transpose() * covariance).trace(), (svd.transpose() * covariance).trace(), 1e-12 * covariance.norm())
      << "case " << k % 6;
    if (k % 6 < 4)
    {
      worst = std::max(worst, (direct - svd).cwiseAbs().maxCoeff());
    }
  }
  EXPECT_LT(worst, 1e-12);
}

TEST(RigidMotion, SignUnderBestRotationAgreesWithTheRotationAndDecidesForSurfaces)
{
  // The same kinds of covariance as above, and the triangles' normals as FlippedTriangles asks
  // about them: where the sign is told without the rotation it is the rotation's, and a surface
  // moved near rigidly (a flat covariance, singular values within a factor 3) is told at once
  // for all but a few pairs whose product is near zero.
  std::mt19937 generator(11);
  std::uniform_real_distribution<double> entry(-1, 1);
  auto rotation = [&] {
    return RandomRotation(generator);
  };
  auto vector = [&] {
    return Eigen::Vector3d(entry(generator), entry(generator), entry(generator));
  };
  int told = 0, disagreed = 0, flat = 0, flatTold = 0;
  for (int k = 0; k < 12000; ++k)
  {
    Eigen::Vector3d singular(1 + 0.5 * entry(generator), 1 + 0.5 * entry(generator), 0.05 * entry(generator));
    switch (k % 6)
    {
      case 1:
        singular(2) = 1 + entry(generator); // general
        break;
      case 2:
        singular(2) = -singular(1); // mirrored, the smaller two alike
        break;
      case 3:
        singular(1) = singular(2) = 0; // one clear of zero
        break;
      case 4:
        singular(2) = -std::abs(singular(2)) - 0.5; // mirrored
        break;
      default:
        break; // flat, as a surface's edges give
    }
    const Eigen::Matrix3d u = rotation(), v = rotation();
    const Eigen::Matrix3d covariance = 30 * u * singular.asDiagonal() * v.transpose();
    // The rest normal near the flat covariance's normal direction, the deformed one near where
    // the motion takes it or against it (a flip), or anywhere.
    const Eigen::Vector3d n0 = v.col(2) + 0.3 * vector(), n1 = (k % 12 < 6 ? 1.0 : -1.0) * u.col(2) + 0.3 * vector();
    const int sign = md::SignUnderBestRotation(covariance, n0, n1);
    const double exact = n1.dot(md::BestRotationDirect(covariance) * n0);
    told += sign != 0 ? 1 : 0;
    disagreed += sign != 0 && (sign > 0) != (exact > 0) ? 1 : 0;
    if (k % 6 == 0 || k % 6 == 5)
    {
      ++flat;
      flatTold += sign != 0 ? 1 : 0;
    }
    const Eigen::Vector3d a = vector(), b = vector(); // any directions
    const int anySign = md::SignUnderBestRotation(covariance, a, b);
    disagreed += anySign != 0 && (anySign > 0) != (b.dot(md::BestRotationDirect(covariance) * a) > 0) ? 1 : 0;
  }
  EXPECT_EQ(disagreed, 0);
  EXPECT_GT(flatTold, 0.97 * flat) << "of " << flat << " flat covariances";
  EXPECT_LT(told, 12000); // the mirrored and singular ones are left to the rotation
  EXPECT_EQ(md::SignUnderBestRotation(Eigen::Matrix3d::Zero(), Eigen::Vector3d::UnitX(), Eigen::Vector3d::UnitX()), 0);
  Eigen::Matrix3d broken = Eigen::Matrix3d::Identity();
  broken(0, 1) = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(md::SignUnderBestRotation(broken, Eigen::Vector3d::UnitX(), Eigen::Vector3d::UnitX()), 0);
}

TEST(RigidMotion, ScrewInterpolationKeepsTheJointCentreFixed)
{
  const Points rest = RandomCloud(50, 2, 40);
  const md::RigidTransform motion = md::RigidTransform::AboutPoint(axis, M_PI / 3, joint);
  const md::ScrewInterpolation screw(motion, rest.colwise().mean().transpose());
  for (double s : { 0.0, 0.1, 0.25, 0.5, 0.9, 1.0 })
  {
    const md::RigidTransform at = screw.At(s);
    EXPECT_LT((at.Apply(joint) - joint).norm(), 1e-9) << "s = " << s;
    EXPECT_NEAR(Eigen::AngleAxisd(at.rotation).angle(), s * M_PI / 3, 1e-12);
  }
  EXPECT_TRUE(screw.At(1.0).rotation.isApprox(motion.rotation, 1e-12));
  EXPECT_TRUE(screw.At(1.0).translation.isApprox(motion.translation, 1e-9));
}

TEST(RigidMotion, ScrewInterpolationSlidesAlongItsAxisLinearly)
{
  md::RigidTransform motion = md::RigidTransform::AboutPoint(axis, 0.8, joint);
  motion.translation += 12.0 * axis; // a screw: rotate and slide along the axis
  const md::ScrewInterpolation screw(motion, joint + Eigen::Vector3d(30, 0, 0));
  const Eigen::Vector3d half = screw.At(0.5).Apply(joint);
  EXPECT_LT((half - (joint + 6.0 * axis)).norm(), 1e-9);
}

TEST(RigidMotion, TinyRotationsStayAccurate)
{
  const Eigen::Vector3d shift(10, 20, -30);
  md::RigidTransform motion = md::RigidTransform::AboutPoint(axis, 1e-11, joint);
  motion.translation += shift;
  const Eigen::Vector3d centroid(5, 5, 5);
  const md::ScrewInterpolation screw(motion, centroid);
  const Eigen::Vector3d x(100, -50, 20);
  const Eigen::Vector3d expected = x + 0.5 * (motion.Apply(x) - x);
  EXPECT_LT((screw.At(0.5).Apply(x) - expected).norm(), 1e-8);
  const md::ScrewInterpolation none(md::RigidTransform{}, centroid);
  EXPECT_LT((none.At(0.5).Apply(x) - x).norm(), 1e-12);
}

TEST(RigidMotion, TheFitsResidualsSayWhatIsNotRigid)
{
  const Points from = RandomCloud(50, 3, 5);
  Points to = md::RigidTransform::AboutPoint(axis, 0.4, joint).Apply(from);
  to.row(7) += Eigen::RowVector3d(0, 1, 0); // one point off the rigid motion by 1
  const md::RigidFit fit = md::FitRigidTransform(from, to);
  EXPECT_GT(fit.maxResidual, 0.9);
  EXPECT_LT(fit.maxResidual, 1.0);
  EXPECT_LT(fit.rmsResidual, fit.maxResidual / 5);
}

TEST(RigidMotion, ARotationTableEntryThatIsNoRotationIsSaidWhy)
{
  md::RigidTransform t = md::RigidTransform::AboutPoint(Eigen::Vector3d(1, 2, 3), 0.7, Eigen::Vector3d(4, 5, 6));
  EXPECT_EQ(md::NotARigidMotion(t), "");
  md::RigidTransform rounded = t; // written with 7 significant digits
  rounded.rotation = (t.rotation.array() * 1e7).round() / 1e7;
  EXPECT_EQ(md::NotARigidMotion(rounded), "");
  md::RigidTransform scaled = t;
  scaled.rotation *= 2.0;
  EXPECT_NE(md::NotARigidMotion(scaled).find("is not a rotation"), std::string::npos);
  md::RigidTransform mirrored = t;
  mirrored.rotation.col(0) *= -1.0;
  EXPECT_NE(md::NotARigidMotion(mirrored).find("reflection"), std::string::npos);
  md::RigidTransform broken = t;
  broken.translation[1] = std::nan("");
  EXPECT_NE(md::NotARigidMotion(broken).find("NaN or infinite"), std::string::npos);
  broken = t;
  broken.rotation(2, 2) = std::numeric_limits<double>::infinity();
  EXPECT_NE(md::NotARigidMotion(broken).find("NaN or infinite"), std::string::npos);
}
