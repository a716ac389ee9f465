// SPDX-License-Identifier: BSD-3-Clause
// What the method's steps share (SettledSteps): measures brought back to the data's units, and
// every muscle's sharp-edge count prepared at rest. The settle in parts and halves itself is
// tested through the method (TestInterpolatedDeformation, TestMotionDeformation).
#include "Method/SettledSteps.h"
#include "Phantom/Phantom.h"

#include <gtest/gtest.h>

TEST(SettledSteps, MeasuresInTheLocalFrameComeBackInTheDataUnitsCountsUnchanged)
{
  md::LocalFrame frame;
  frame.origin = Eigen::RowVector3d(100, 0, -50); // lengths and moves have no origin
  frame.unit = 4.0;
  md::MuscleStepMeasures s;
  s.volumeChangePercent = 0.5;
  s.newPenetrationCount = 3;
  s.maxNewPenetrationDepth = 0.25;
  s.maxNewBonePenetrationDepth = 0.125;
  s.stepStaticShift = 0.5;
  s.maxStaticShift = 0.75;
  s.sharpEdgeCount = 7;
  s.staticShift = md::Points::Constant(2, 3, 0.5);
  md::MeasuresToWorld(frame, s);
  EXPECT_EQ(s.maxNewPenetrationDepth, 1.0);
  EXPECT_EQ(s.maxNewBonePenetrationDepth, 0.5);
  EXPECT_EQ(s.stepStaticShift, 2.0);
  EXPECT_EQ(s.maxStaticShift, 3.0);
  EXPECT_EQ(s.staticShift, md::Points::Constant(2, 3, 2.0));
  EXPECT_EQ(s.volumeChangePercent, 0.5); // a ratio
  EXPECT_EQ(s.newPenetrationCount, 3);
  EXPECT_EQ(s.sharpEdgeCount, 7);
}

TEST(SettledSteps, EveryMusclesSharpEdgesAreThoseOfItsOwnRestSurface)
{
  const md::Phantom phantom = md::BuildPhantom(md::PhantomParameters());
  std::vector<md::MuscleMotion> muscles;
  for (const auto& muscle : phantom.muscles)
  {
    muscles.push_back({ muscle.name, muscle.rest, {} });
  }
  const std::vector<md::NewSharpEdges> edges = md::MuscleSharpEdges(muscles);
  ASSERT_EQ(edges.size(), muscles.size());
  for (size_t m = 0; m < muscles.size(); ++m)
  {
    // Folded along a plane through its middle: each count is that of its own rest edges.
    md::Points folded = muscles[m].muscle.points;
    const double middle = folded.col(2).mean();
    for (Eigen::Index i = 0; i < folded.rows(); ++i)
    {
      if (folded(i, 2) > middle)
      {
        folded(i, 0) += 3.0 * (folded(i, 2) - middle);
      }
    }
    const md::NewSharpEdges alone(muscles[m].muscle.points, muscles[m].muscle.triangles);
    EXPECT_EQ(edges[m].Count(muscles[m].muscle.points), 0) << m;
    EXPECT_GT(alone.Count(folded), 0) << m;
    EXPECT_EQ(edges[m].Count(folded), alone.Count(folded)) << m;
  }
}
