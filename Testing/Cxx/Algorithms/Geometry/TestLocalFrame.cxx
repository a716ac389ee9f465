// SPDX-License-Identifier: BSD-3-Clause
// The local frame: exact near the origin, an exact shift far from it, the same numbers in metres
// and in millimetres.
#include "Geometry/LocalFrame.h"

#include <gtest/gtest.h>

#include <cmath>

namespace
{
md::Points Corners(double scale, const Eigen::RowVector3d& offset)
{
  md::Points points(4, 3);
  points << 0, 0, 0, 3, 0, 0, 0, 5, 0, 0, 0, 7;
  return (points * scale).rowwise() + offset;
}
}

TEST(LocalFrame, NearTheOriginOnlyAPowerOfTwoDividesAndTheWayBackIsExact)
{
  const md::Points world = Corners(1.1, Eigen::RowVector3d(10, -4, 2));
  const md::LocalFrame frame = md::LocalFrame::Around({ &world });
  EXPECT_EQ(frame.origin, Eigen::RowVector3d::Zero());
  EXPECT_EQ(frame.unit, 8.0); // the largest extent is 7.7
  md::Points points = world;
  frame.ToLocal(points);
  EXPECT_LE(points.cwiseAbs().maxCoeff(), 4.0);
  frame.ToWorld(points);
  EXPECT_EQ(points, world); // bit for bit
  EXPECT_EQ(frame.LengthToWorld(frame.LengthToLocal(0.01)), 0.01);
  EXPECT_EQ(frame.VolumeToWorld(1.0), 512.0);
}

TEST(LocalFrame, FarFromTheOriginTheShiftIsAMultipleOfTheUnitAndLocalNumbersAreSmall)
{
  const md::Points world = Corners(1.0, Eigen::RowVector3d(1e12, -3e11, 5e9));
  const md::LocalFrame frame = md::LocalFrame::Around({ &world });
  EXPECT_NE(frame.origin, Eigen::RowVector3d::Zero());
  for (int c = 0; c < 3; ++c)
  {
    const double multiple = frame.origin[c] / (16 * frame.unit);
    EXPECT_EQ(multiple, std::round(multiple)) << c;
  }
  md::Points points = world;
  frame.ToLocal(points);
  EXPECT_LE(points.cwiseAbs().maxCoeff(), 16.0);
  EXPECT_GT(frame.rounding, 0.0);
  frame.ToWorld(points);
  EXPECT_LE((points - world).cwiseAbs().maxCoeff(), frame.rounding * frame.unit);
}

TEST(LocalFrame, MetresAndMillimetresGiveTheSameLocalNumbersToRounding)
{
  const Eigen::RowVector3d offset(0.31, -0.12, 0.9);
  const md::Points metres = Corners(0.01, offset);
  const md::Points millimetres = metres * 1000.0;
  const md::LocalFrame inMetres = md::LocalFrame::Around({ &metres });
  const md::LocalFrame inMillimetres = md::LocalFrame::Around({ &millimetres });
  md::Points a = metres, b = millimetres;
  inMetres.ToLocal(a);
  inMillimetres.ToLocal(b);
  // The units differ by 1000 to the nearest powers of two: the local sizes agree within a factor 2.
  const double ratio = (a.colwise().maxCoeff() - a.colwise().minCoeff()).maxCoeff() /
    (b.colwise().maxCoeff() - b.colwise().minCoeff()).maxCoeff();
  EXPECT_GE(ratio, 0.5);
  EXPECT_LE(ratio, 2.0);
}

TEST(LocalFrame, NoDataIsTheIdentity)
{
  const md::LocalFrame frame = md::LocalFrame::Around({ nullptr });
  EXPECT_EQ(frame.origin, Eigen::RowVector3d::Zero());
  EXPECT_EQ(frame.unit, 1.0);
}
