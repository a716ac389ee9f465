// SPDX-License-Identifier: BSD-3-Clause
// Moment arms along a motion: exact for a length linear in the coordinate, OpenSim's sign,
// one-sided at the ends and where the motion turns, NaN where several coordinates move at once.
#include "Anatomy/TendonExcursion.h"

#include <gtest/gtest.h>

#include <cmath>

TEST(TendonExcursion, ALengthThatShortensAsTheJointFlexesHasAPositiveArm)
{
  // L = 100 - 20 q about q0, q1 still: r0 = 20 at every frame, r1 NaN (q1 never moves).
  std::vector<std::vector<double>> q;
  std::vector<double> lengths;
  for (int k = 0; k < 6; ++k)
  {
    q.push_back({ 0.1 * k, 0.3 });
    lengths.push_back(100 - 20 * q.back()[0]);
  }
  const auto arms = md::MomentArmsAlongMotion(q, lengths);
  ASSERT_EQ(arms.size(), 6u);
  for (const auto& frame : arms)
  {
    EXPECT_NEAR(frame[0], 20.0, 1e-9);
    EXPECT_TRUE(std::isnan(frame[1]));
  }
}

TEST(TendonExcursion, CentralWhereItCanOneSidedWhereTheMotionTurns)
{
  // L = q^2: the central difference is exact for a quadratic (r = -2 q).
  std::vector<std::vector<double>> q{ { 0.0 }, { 0.1 }, { 0.2 }, { 0.3 } };
  std::vector<double> lengths;
  for (const auto& f : q)
  {
    lengths.push_back(f[0] * f[0]);
  }
  auto arms = md::MomentArmsAlongMotion(q, lengths);
  EXPECT_NEAR(arms[1][0], -0.2, 1e-12);
  EXPECT_NEAR(arms[2][0], -0.4, 1e-12);
  EXPECT_NEAR(arms[0][0], -0.1, 1e-12); // forward at the first frame
  EXPECT_NEAR(arms[3][0], -0.5, 1e-12); // backward at the last
  // The motion turns at frame 2 (0.1, 0.2, 0.1): its neighbours agree, so backward.
  q = { { 0.1 }, { 0.2 }, { 0.1 } };
  lengths = { 0.01, 0.04, 0.01 };
  arms = md::MomentArmsAlongMotion(q, lengths);
  EXPECT_NEAR(arms[1][0], -(0.04 - 0.01) / 0.1, 1e-12);
}

TEST(TendonExcursion, SeveralCoordinatesMovingAtOnceGiveNoArm)
{
  const std::vector<std::vector<double>> q{ { 0.0, 0.0 }, { 0.1, 0.1 }, { 0.2, 0.2 }, { 0.2, 0.3 } };
  const std::vector<double> lengths{ 1.0, 0.9, 0.8, 0.75 };
  const auto arms = md::MomentArmsAlongMotion(q, lengths);
  EXPECT_TRUE(std::isnan(arms[0][0]) && std::isnan(arms[0][1]));
  EXPECT_TRUE(std::isnan(arms[1][0]) && std::isnan(arms[1][1]));
  // Frame 2 to 3 moves q1 alone: frame 3 (backward) and frame 2 (forward, as central mixes).
  EXPECT_NEAR(arms[3][1], 0.5, 1e-12);
  EXPECT_NEAR(arms[2][1], 0.5, 1e-12);
  EXPECT_TRUE(std::isnan(arms[3][0]));
}
