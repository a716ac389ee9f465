// SPDX-License-Identifier: BSD-3-Clause
#include "Geometry/RigidMotion.h"
#include "Motion/BoneInterpolation.h"
#include "TestMeshes.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>

using md::Points;

namespace
{
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

const Eigen::Vector3d joint(143.5, 243.4, -432.7);
const Eigen::Vector3d axis = Eigen::Vector3d(1, 0.1, -0.05).normalized();
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
  // 5 off in a cloud 100 x 100 x 300 across: 1.5 % of its size, said, naming the bone.
  const std::string warning = rigid.NonRigidWarning("bone 'Femur'");
  EXPECT_NE(warning.find("the motion of bone 'Femur' is not rigid"), std::string::npos) << warning;
  EXPECT_NE(warning.find(" % of its size"), std::string::npos) << warning;
  // Rigid to rounding, or Linear (no fit): nothing to say.
  const Points moved = md::RigidTransform::AboutPoint(axis, 0.5, joint).Apply(rest);
  EXPECT_EQ(md::PoseInterpolator(rest, moved, md::InterpolationMode::Rigid).NonRigidWarning("b"), "");
  EXPECT_EQ(md::PoseInterpolator(rest, current, md::InterpolationMode::Linear).NonRigidWarning("b"), "");
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
