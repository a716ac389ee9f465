// SPDX-License-Identifier: BSD-3-Clause
#include "BoneInterpolation.h"
#include "RigidMotion.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>

using md::Points;

namespace
{
Points RandomCloud(int n, unsigned seed, double size)
{
  std::mt19937 generator(seed);
  std::uniform_real_distribution<double> coordinate(-size, size);
  Points p(n, 3);
  for (int i = 0; i < n; ++i)
  {
    p.row(i) << coordinate(generator), coordinate(generator), 3 * coordinate(generator);
  }
  return p;
}

double LargestRelativeDistanceChange(const Points& a, const Points& b)
{
  double worst = 0;
  for (Eigen::Index i = 0; i < a.rows(); ++i)
  {
    for (Eigen::Index j = i + 1; j < a.rows(); ++j)
    {
      const double da = (a.row(i) - a.row(j)).norm();
      const double db = (b.row(i) - b.row(j)).norm();
      worst = std::max(worst, std::abs(db - da) / da);
    }
  }
  return worst;
}

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

TEST(BoneInterpolation, PoseInterpolatorsAreTheOnesBuiltOneByOneAndPassOnTheirErrors)
{
  std::vector<Points> rest, current;
  for (unsigned k = 0; k < 3; ++k)
  {
    rest.push_back(RandomCloud(40 + 10 * static_cast<int>(k), 20 + k, 30));
    const md::RigidTransform motion = md::RigidTransform::AboutPoint(axis, 0.3 * (k + 1), joint);
    current.push_back(motion.Apply(rest.back()) + 1e-3 * RandomCloud(rest.back().rows(), 30 + k, 1));
  }
  const std::vector<md::PoseInterpolator> built = md::PoseInterpolators(rest, current, md::InterpolationMode::Rigid);
  ASSERT_EQ(built.size(), 3u);
  for (size_t k = 0; k < 3; ++k)
  {
    const md::PoseInterpolator alone(rest[k], current[k], md::InterpolationMode::Rigid);
    EXPECT_EQ(built[k].AtFraction(0.37), alone.AtFraction(0.37)) << "bone " << k;
  }
  current[1] = current[1].topRows(5); // a bone that lost points
  EXPECT_THROW(md::PoseInterpolators(rest, current, md::InterpolationMode::Rigid), md::InputError);
  current.pop_back();
  EXPECT_THROW(md::PoseInterpolators(rest, current, md::InterpolationMode::Linear), md::InputError);
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

// Collinear points fix no rotation about their own axis. The LHDL gluteus medius's action lines
// are two points each: rounding made the fit of one line turn by 0.32 rad in one export and by
// 2.85 rad (a twist about the line) in the other, and the line halfway through the motion
// moved by 12 mm. Of the rotations that fit, the one nearest the identity is taken.
TEST(BoneInterpolation, AStraightLineTurnsTheShortestWayWhateverItsRounding)
{
  for (const int points : { 2, 5 })
  {
    Points rest(points, 3), current(points, 3);
    const md::RigidTransform turn = md::RigidTransform::AboutPoint(Eigen::Vector3d::UnitZ(), 0.6, joint);
    for (int i = 0; i < points; ++i)
    {
      const Eigen::Vector3d along(90.0 * i / (points - 1), 0, 0);
      rest.row(i) = (joint + Eigen::Vector3d(40, 10, 5) + along).transpose();
      // The line turns and stretches by 5 %.
      current.row(i) = turn.Apply(Eigen::Vector3d(joint + Eigen::Vector3d(40, 10, 5) + 1.05 * along)).transpose();
    }
    const md::PoseInterpolator exact(rest, current, md::InterpolationMode::Rigid);
    EXPECT_NEAR(exact.RotationAngle(), 0.6, 1e-5) << points << " points";
    // Halfway, the line has turned half the way in its own plane (z = joint's + 5).
    const Points half = exact.AtFraction(0.5);
    EXPECT_LT((half.col(2).array() - (joint.z() + 5)).abs().maxCoeff(), 1e-3) << points << " points";
    std::mt19937 generator(7);
    std::uniform_real_distribution<double> noise(-1e-7, 1e-7);
    for (int seed = 0; seed < 20; ++seed)
    {
      Points rounded = rest, roundedCurrent = current;
      for (Points* p : { &rounded, &roundedCurrent })
      {
        for (Eigen::Index k = 0; k < p->size(); ++k)
        {
          p->data()[k] *= 1 + noise(generator);
        }
      }
      const md::PoseInterpolator perturbed(rounded, roundedCurrent, md::InterpolationMode::Rigid);
      for (const double s : { 0.25, 0.5, 0.75 })
      {
        EXPECT_LT((perturbed.AtFraction(s) - exact.AtFraction(s)).rowwise().norm().maxCoeff(), 1e-3)
          << points << " points, seed " << seed << ", s = " << s;
      }
    }
  }
}

TEST(BoneInterpolation, EndStepsReproduceBothPosesExactly)
{
  const Points rest = RandomCloud(300, 3, 100);
  const Points current = md::RigidTransform::AboutPoint(axis, 1.0, joint).Apply(rest);
  for (auto mode : { md::InterpolationMode::Linear, md::InterpolationMode::Rigid })
  {
    const md::PoseInterpolator interpolator(rest, current, mode);
    EXPECT_TRUE((interpolator.AtStep(0, 5).array() == rest.array()).all());
    EXPECT_TRUE((interpolator.AtStep(5, 5).array() == current.array()).all());
  }
}

TEST(BoneInterpolation, LinearIsThePapersEquationOne)
{
  const Points rest = RandomCloud(40, 4, 100);
  const Points current = RandomCloud(40, 5, 100);
  const md::PoseInterpolator linear(rest, current, md::InterpolationMode::Linear);
  const Points step = linear.AtStep(1, 3);
  EXPECT_TRUE(step.isApprox(rest + (current - rest) / 3.0, 1e-14));
}

TEST(BoneInterpolation, RigidKeepsTheBoneCongruentWhileLinearShrinksItAsPredicted)
{
  const Points rest = RandomCloud(150, 6, 80);
  const double angle = M_PI / 3; // 60 degrees
  const Points current = md::RigidTransform::AboutPoint(axis, angle, joint).Apply(rest);
  const md::PoseInterpolator rigid(rest, current, md::InterpolationMode::Rigid);
  const md::PoseInterpolator linear(rest, current, md::InterpolationMode::Linear);
  constexpr int steps = 4;
  for (int j = 0; j <= steps; ++j)
  {
    EXPECT_LT(LargestRelativeDistanceChange(rest, rigid.AtStep(j, steps)), 1e-12) << "step " << j;
  }
  // Linear: a difference vector d keeps its axial part and its normal part
  // shrinks by f(s) = sqrt((1-s)^2 + s^2 + 2 s (1-s) cos(angle)); at s = 1/2
  // that is cos(angle / 2), 13.4 % short for 60 degrees.
  const Points middle = linear.AtStep(2, steps);
  const double f = std::cos(angle / 2);
  double smallestRatio = 1;
  for (Eigen::Index i = 0; i + 1 < rest.rows(); ++i)
  {
    const Eigen::Vector3d d = (rest.row(i + 1) - rest.row(i)).transpose();
    const double axial = d.dot(axis);
    const double predicted = std::sqrt(axial * axial + f * f * (d.squaredNorm() - axial * axial));
    const double measured = (middle.row(i + 1) - middle.row(i)).norm();
    EXPECT_NEAR(measured / predicted, 1.0, 1e-12);
    smallestRatio = std::min(smallestRatio, measured / d.norm());
  }
  EXPECT_LT(smallestRatio, 0.88);
  EXPECT_GE(smallestRatio, f - 1e-12);
  EXPECT_NEAR(rigid.RotationAngle(), angle, 1e-12);
}

TEST(BoneInterpolation, RigidBlendsANonRigidResidualAndReportsIt)
{
  const Points rest = RandomCloud(100, 7, 50);
  Points current = md::RigidTransform::AboutPoint(axis, 0.5, joint).Apply(rest);
  current(0, 0) += 5.0; // one point does not follow the bone
  const md::PoseInterpolator rigid(rest, current, md::InterpolationMode::Rigid);
  ASSERT_TRUE(rigid.Fit().has_value());
  EXPECT_GT(rigid.Fit()->maxResidual, 4.0);
  EXPECT_GT(rigid.Fit()->rmsResidual, 0.1);
  EXPECT_TRUE((rigid.AtStep(3, 3).array() == current.array()).all());
  const Points half = rigid.AtFraction(0.5);
  EXPECT_TRUE(half.allFinite());
}

TEST(BoneInterpolation, AutomaticNumberOfSteps)
{
  EXPECT_EQ(md::AutomaticNumberOfSteps(0.0, 10.0), 1);
  EXPECT_EQ(md::AutomaticNumberOfSteps(10.0, 10.0), 1);
  EXPECT_EQ(md::AutomaticNumberOfSteps(10.5, 10.0), 2);
  EXPECT_EQ(md::AutomaticNumberOfSteps(95.0, 10.0), 10);
  EXPECT_THROW(md::AutomaticNumberOfSteps(10.0, 0.0), md::InputError);
  EXPECT_THROW(md::AutomaticNumberOfSteps(1e9, 1e-3), md::InputError);
  const Points rest = RandomCloud(10, 8, 10);
  Points current = rest;
  current(3, 2) += 7.5;
  EXPECT_DOUBLE_EQ(md::MaximumDisplacement(rest, current), 7.5);
}

TEST(BoneInterpolation, RejectsUnusableInput)
{
  const Points rest = RandomCloud(10, 9, 10);
  const Points fewer = RandomCloud(9, 9, 10);
  Points withNaN = rest;
  withNaN(4, 0) = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(md::PoseInterpolator(rest, fewer, md::InterpolationMode::Linear), md::InputError);
  EXPECT_THROW(md::PoseInterpolator(rest, withNaN, md::InterpolationMode::Rigid), md::InputError);
  EXPECT_THROW(md::PoseInterpolator(Points(0, 3), Points(0, 3), md::InterpolationMode::Rigid), md::InputError);
  const md::PoseInterpolator ok(rest, rest, md::InterpolationMode::Rigid);
  EXPECT_THROW(ok.AtStep(0, 0), md::InputError);
}
