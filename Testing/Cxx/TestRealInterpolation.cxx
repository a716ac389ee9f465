// The interpolation method on the LHDL right hip, hip flexion 60 degrees
// (frame 35), four muscles together, obstacles iliac bone, sacrum and femur:
// the one-pass method, the interpolation with the hull refitted (N = 4) and
// with the hull rebuilt before every step (the paper), judged by the measures
// of METHOD.md. Skipped when ../shared/data is absent.
#include "InterpolatedDeformation.h"
#include "RealData.h"

#include <gtest/gtest.h>

namespace
{
md::InterpolationResult RunMethod(const MotionCase& c, int steps, md::HullMode mode)
{
  md::InterpolationParameters parameters;
  parameters.numberOfSteps = steps;
  parameters.hullMode = mode;
  return md::DeformByInterpolation(c.muscles, c.bones, parameters);
}

double Largest(const md::InterpolationResult& r, double md::MuscleStepMeasures::*measure)
{
  double largest = 0;
  for (const md::MuscleStepMeasures& m : r.measures.back())
  {
    largest = std::max(largest, m.*measure);
  }
  return largest;
}

std::int64_t Total(const md::InterpolationResult& r, std::int64_t md::MuscleStepMeasures::*measure)
{
  std::int64_t total = 0;
  for (const md::MuscleStepMeasures& m : r.measures.back())
  {
    total += m.*measure;
  }
  return total;
}
}

TEST(RealInterpolation, HipFlexion60InFourStepsBeatsTheOnePassMethodAndRefitIsComparableToRebuild)
{
  MotionCase c;
  if (!LhdlMotion("hip_flexion", 35, c))
  {
    GTEST_SKIP() << "LHDL data not found (set MUSCLEDEFORMATION_DATA_DIR)";
  }
  ASSERT_EQ(c.muscles.size(), 4u);
  ASSERT_EQ(c.bones.size(), 3u);
  const md::InterpolationResult one = RunMethod(c, 1, md::HullMode::Refit);
  const md::InterpolationResult refit = RunMethod(c, 4, md::HullMode::Refit);
  const md::InterpolationResult rebuild = RunMethod(c, 4, md::HullMode::Rebuild);
  ASSERT_EQ(refit.points.size(), 5u);
  for (const md::InterpolationResult* r : { &one, &refit, &rebuild })
  {
    for (size_t m = 0; m < c.muscles.size(); ++m)
    {
      const md::MuscleStepMeasures& f = r->measures.back()[m];
      SCOPED_TRACE(c.muscles[m].name + ", " + std::to_string(r->numberOfSteps) + " steps");
      EXPECT_LE(std::abs(f.volumeChangePercent), 0.1);
      EXPECT_LE(f.maxNewBonePenetrationDepth, 0.5); // no new penetration of a bone deeper than 0.5 mm
      EXPECT_TRUE(r->points.back()[m].allFinite());
    }
  }
  const auto shift = &md::MuscleStepMeasures::maxStaticShift;
  const auto sharp = &md::MuscleStepMeasures::sharpEdgeCount;
  const auto flips = &md::MuscleStepMeasures::flippedTriangleCount;
  // Measured here: largest static shift 16.6 mm against 18.2 mm in one pass
  // (0.91; the target, 0.6, is not met: the femur sweeps under the
  // gluteus maximus by about as much in each step), 343 new sharp edges
  // against 432, 11 flipped triangles against 62. The largest shift is one
  // point's and moves by millimetres when the inputs move by 1e-7: over such
  // perturbations it is 0.60-0.91 of the one-pass figure, the flips always
  // fewer, the sharp edges fewer in 5 of 7 (BENCHMARKS.md).
  EXPECT_LT(Largest(refit, shift), Largest(one, shift));
  EXPECT_LT(Total(refit, sharp), Total(one, sharp));
  EXPECT_LT(Total(refit, flips), Total(one, flips));
  // Refit against the paper's Rebuild: comparable quality (here 16.6 against
  // 13.9 mm, 343 against 330 sharp edges; over the perturbations Refit's
  // largest shift is 0.85-1.20 of Rebuild's and its sharp edges 0.89-1.26).
  EXPECT_LE(Largest(refit, shift), 1.25 * Largest(rebuild, shift));
  EXPECT_LE(Total(refit, sharp), 1.3 * Total(rebuild, sharp));
}

TEST(RealInterpolation, InputsMovedBy1e7StillGiveSoundMuscles)
{
  // The same case with every coordinate moved by up to 1e-7 of itself and
  // rounded to float (as VTK pipelines carry points). Without the follow rows
  // (DeformationParameters::followWeight) the least-squares system's
  // near-null modes tore a muscle apart in runs like these (the gluteus
  // medius, the iliacus or the psoas spanning 1.6 to 6.5 times its size;
  // with followWeight 0, seed 4 is refused as diverged); now each run
  // completes, every muscle keeps its volume and its size.
  MotionCase c;
  if (!LhdlMotion("hip_flexion", 35, c))
  {
    GTEST_SKIP() << "LHDL data not found (set MUSCLEDEFORMATION_DATA_DIR)";
  }
  auto span = [](const md::Points& p) { return (p.colwise().maxCoeff() - p.colwise().minCoeff()).norm(); };
  for (int seed : { 1, 2, 4 })
  {
    SCOPED_TRACE("seed " + std::to_string(seed));
    const MotionCase perturbed = Perturbed(c, seed);
    md::InterpolationResult r;
    ASSERT_NO_THROW(r = RunMethod(perturbed, 4, md::HullMode::Refit));
    for (size_t m = 0; m < c.muscles.size(); ++m)
    {
      SCOPED_TRACE(c.muscles[m].name);
      const md::MuscleStepMeasures& f = r.measures.back()[m];
      EXPECT_LE(std::abs(f.volumeChangePercent), 0.1);
      EXPECT_LE(f.maxNewBonePenetrationDepth, 0.5);
      EXPECT_LT(span(r.points.back()[m]), 1.2 * span(perturbed.muscles[m].muscle.points));
    }
  }
}
