// SPDX-License-Identifier: BSD-3-Clause
#include "Motion/ActionLineMatching.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

using md::Points;

namespace
{
Points Line(std::initializer_list<std::array<double, 3>> points)
{
  Points out(static_cast<Eigen::Index>(points.size()), 3);
  Eigen::Index i = 0;
  for (const auto& p : points)
  {
    out.row(i++) << p[0], p[1], p[2];
  }
  return out;
}

/// Rows of `original` appear, in order and bit for bit, among the rows of `matched`.
bool KeepsAllPoints(const Points& original, const Points& matched)
{
  Eigen::Index next = 0;
  for (Eigen::Index i = 0; i < original.rows(); ++i)
  {
    while (next < matched.rows() && matched.row(next) != original.row(i))
    {
      ++next;
    }
    if (next == matched.rows())
    {
      return false;
    }
    ++next;
  }
  return true;
}

/// Largest distance of the points of `matched` from the polyline `original`.
double DistanceFromPolyline(const Points& matched, const Points& original)
{
  double worst = 0;
  for (Eigen::Index i = 0; i < matched.rows(); ++i)
  {
    double best = std::numeric_limits<double>::max();
    for (Eigen::Index k = 0; k + 1 < original.rows(); ++k)
    {
      const Eigen::RowVector3d a = original.row(k), b = original.row(k + 1);
      const double f = std::clamp((matched.row(i) - a).dot(b - a) / (b - a).squaredNorm(), 0.0, 1.0);
      best = std::min(best, (matched.row(i) - (a + f * (b - a))).norm());
    }
    worst = std::max(worst, best);
  }
  return worst;
}

// RP: 4 unevenly spaced points; CP: 6 unevenly spaced points, a different path.
const Points rest = Line({ { 0, 0, 0 }, { 1, 0, 0 }, { 1, 7, 0 }, { 3, 7, 1 } });
const Points current =
  Line({ { 10, 0, 0 }, { 10.2, 0.1, 0 }, { 11, 2, 0 }, { 12, 5, 1 }, { 12, 5.5, 4 }, { 20, 6, 4 } });
}

TEST(ActionLineMatching, ArcLengthParametersRunFromZeroToOne)
{
  const std::vector<double> t = md::NormalisedArcLength(rest);
  ASSERT_EQ(t.size(), 4u);
  EXPECT_EQ(t.front(), 0.0);
  EXPECT_EQ(t.back(), 1.0);
  const double length = 1 + 7 + std::sqrt(5.0);
  EXPECT_NEAR(t[1], 1 / length, 1e-15);
  EXPECT_NEAR(t[2], 8 / length, 1e-15);
}

TEST(ActionLineMatching, DifferentCountsComeOutEqualAndMatchedAtEqualArcLength)
{
  const double tolerance = 1e-6; // nothing here is that close: every pair but the ends is inserted
  const md::MatchedActionLines m = md::MatchActionLines(rest, current, tolerance);
  ASSERT_EQ(m.rest.rows(), m.current.rows());
  // 2 shared ends + 2 interior RP points + 4 interior CP points.
  EXPECT_EQ(m.rest.rows(), 8);
  EXPECT_TRUE(KeepsAllPoints(rest, m.rest));
  EXPECT_TRUE(KeepsAllPoints(current, m.current));
  // Inserted points lie on the original lines, so the arc length is unchanged
  // and can be recomputed from the outputs themselves.
  EXPECT_LT(DistanceFromPolyline(m.rest, rest), 1e-12);
  EXPECT_LT(DistanceFromPolyline(m.current, current), 1e-12);
  const std::vector<double> tRest = md::NormalisedArcLength(m.rest);
  const std::vector<double> tCurrent = md::NormalisedArcLength(m.current);
  for (size_t k = 0; k < tRest.size(); ++k)
  {
    EXPECT_NEAR(tRest[k], tCurrent[k], 1e-9) << "pair " << k;
    EXPECT_NEAR(tRest[k], m.restParameters[k], 1e-12);
    EXPECT_NEAR(tCurrent[k], m.currentParameters[k], 1e-12);
    if (k > 0)
    {
      EXPECT_GT(tRest[k], tRest[k - 1]) << "order along the line is kept";
    }
  }
  int restInserted = 0, currentInserted = 0;
  for (size_t k = 0; k < m.restInserted.size(); ++k)
  {
    restInserted += m.restInserted[k];
    currentInserted += m.currentInserted[k];
    EXPECT_FALSE(m.restInserted[k] && m.currentInserted[k]);
  }
  EXPECT_EQ(restInserted, 4);
  EXPECT_EQ(currentInserted, 2);
}

TEST(ActionLineMatching, NothingIsInsertedWhereAPointIsWithinTolerance)
{
  // CP interior points at t = 0.3 + 0.004 and 0.7 - 0.003 of a straight line;
  // RP interior points at t = 0.3 and 0.7.
  const Points straightRest = Line({ { 0, 0, 0 }, { 3, 0, 0 }, { 7, 0, 0 }, { 10, 0, 0 } });
  const Points straightCurrent = Line({ { 0, 5, 0 }, { 0, 5, 3.04 }, { 0, 5, 6.97 }, { 0, 5, 10 } });
  const md::MatchedActionLines m = md::MatchActionLines(straightRest, straightCurrent, 0.01);
  ASSERT_EQ(m.rest.rows(), 4);
  EXPECT_EQ(m.rest, straightRest);
  EXPECT_EQ(m.current, straightCurrent);
  for (size_t k = 0; k < 4; ++k)
  {
    EXPECT_FALSE(m.restInserted[k]);
    EXPECT_FALSE(m.currentInserted[k]);
    EXPECT_LE(std::abs(m.restParameters[k] - m.currentParameters[k]), 0.01);
  }
  // With a tolerance below those differences both points are inserted instead.
  const md::MatchedActionLines strict = md::MatchActionLines(straightRest, straightCurrent, 0.001);
  EXPECT_EQ(strict.rest.rows(), 6);
}

TEST(ActionLineMatching, IdenticalParameterisationsMatchOneToOne)
{
  const Points moved = (rest * 2.0).rowwise() + Eigen::RowVector3d(5, -1, 2);
  const md::MatchedActionLines m = md::MatchActionLines(rest, moved, 0.0);
  EXPECT_EQ(m.rest, rest);
  EXPECT_EQ(m.current, moved);
}

TEST(ActionLineMatching, LargeToleranceIsCappedSoThatPairsNeverCross)
{
  // The paper's greedy rule with tolerance 0.1 would pair RP t=0.3 with CP
  // t=0.36 and then insert t=0.35 after it on the CP line: a line that doubles back.
  const Points r = Line({ { 0, 0, 0 }, { 0.3, 0, 0 }, { 0.35, 0, 0 }, { 1, 0, 0 } });
  const Points c = Line({ { 0, 0, 0 }, { 0.36, 0, 0 }, { 1, 0, 0 } });
  const md::MatchedActionLines m = md::MatchActionLines(r, c, 0.1);
  EXPECT_NEAR(m.tolerance, 0.025, 1e-12); // half of the smallest spacing, 0.05
  for (Eigen::Index k = 1; k < m.current.rows(); ++k)
  {
    EXPECT_GT(m.current(k, 0), m.current(k - 1, 0)) << "matched CP line doubles back at " << k;
    EXPECT_GT(m.rest(k, 0), m.rest(k - 1, 0));
  }
  EXPECT_TRUE(KeepsAllPoints(r, m.rest));
  EXPECT_TRUE(KeepsAllPoints(c, m.current));
}

TEST(ActionLineMatching, RepeatedPointsAreKeptWithoutBreakingTheOrder)
{
  const Points r = Line({ { 0, 0, 0 }, { 1, 0, 0 }, { 1, 0, 0 }, { 2, 0, 0 } });
  const Points c = Line({ { 0, 0, 0 }, { 0, 3, 0 } });
  const md::MatchedActionLines m = md::MatchActionLines(r, c, 0.01);
  ASSERT_EQ(m.rest.rows(), 4);
  EXPECT_NEAR(m.current(1, 1), 1.5, 1e-12);
  EXPECT_NEAR(m.current(2, 1), 1.5, 1e-12);
}

TEST(ActionLineMatching, PointAtParameterInterpolatesAlongSegments)
{
  const std::vector<double> t = md::NormalisedArcLength(rest);
  EXPECT_TRUE(md::PointAtParameter(rest, t, 0.0).isApprox(rest.row(0)));
  EXPECT_EQ(md::PointAtParameter(rest, t, 1.0), rest.row(3));
  EXPECT_EQ(md::PointAtParameter(rest, t, t[2]), rest.row(2));
  const Eigen::RowVector3d half = md::PointAtParameter(rest, t, 0.5 * (t[1] + t[2]));
  EXPECT_NEAR(half(1), 3.5, 1e-12);
}

TEST(ActionLineMatching, RejectsUnusableLines)
{
  const Points single = Line({ { 1, 2, 3 } });
  const Points zeroLength = Line({ { 1, 2, 3 }, { 1, 2, 3 }, { 1, 2, 3 } });
  Points withNaN = rest;
  withNaN(2, 1) = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(md::MatchActionLines(single, current, 0.01), md::InputError);
  EXPECT_THROW(md::MatchActionLines(rest, zeroLength, 0.01), md::InputError);
  EXPECT_THROW(md::MatchActionLines(withNaN, current, 0.01), md::InputError);
  try
  {
    md::MatchActionLines(rest, zeroLength, 0.01);
  }
  catch (const md::InputError& e)
  {
    EXPECT_NE(std::string(e.what()).find("zero length"), std::string::npos);
  }
}
