// SPDX-License-Identifier: BSD-3-Clause
// The interpolation method on the LHDL right hip, hip flexion 60 degrees
// (frame 35), four muscles together, obstacles iliac bone, sacrum and femur:
// the one-pass method, the interpolation with the hull refitted (N = 4) and
// with the hull rebuilt before every step (the paper), judged by the measures
// of docs/DESIGN.md. Skipped when ../shared/data is absent.
#include "Hull/ProgressiveHull.h"
#include "Method/InterpolatedDeformation.h"
#include "RealData.h"

#include <gtest/gtest.h>

#include <cstdio>

namespace
{
/// The hull-based method with its own deformation step (bones push the muscle), or with
/// `contactWeight` 0 the paper's step.
md::InterpolationResult RunMethod(
  const MotionCase& c, int steps, md::HullMode mode, double contactWeight = md::StepDeformationDefaults().contactWeight)
{
  md::InterpolationParameters parameters;
  parameters.numberOfSteps = steps;
  parameters.hullMode = mode;
  parameters.deformation.contactWeight = contactWeight;
  parameters.settleOnSurface = false;
  return md::DeformByInterpolation(c.muscles, c.bones, parameters);
}

/// The method with each step solved on the muscle's own surface, N = 4.
md::InterpolationResult RunOnSurface(const MotionCase& c)
{
  md::InterpolationParameters parameters;
  parameters.settleOnSurface = true;
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
  // The one-pass method as the paper has it (its deformation step: bones only
  // stop points) and with the method's own step (bones push the muscle).
  const md::InterpolationResult paper = RunMethod(c, 1, md::HullMode::Refit, 0.0);
  const md::InterpolationResult one = RunMethod(c, 1, md::HullMode::Refit);
  const md::InterpolationResult refit = RunMethod(c, 4, md::HullMode::Refit);
  const md::InterpolationResult rebuild = RunMethod(c, 4, md::HullMode::Rebuild);
  const md::InterpolationResult settled = RunOnSurface(c);
  ASSERT_EQ(refit.points.size(), 5u);
  ASSERT_EQ(settled.points.size(), 5u);
  for (const md::InterpolationResult* r : { &paper, &one, &refit, &rebuild, &settled })
  {
    for (size_t m = 0; m < c.muscles.size(); ++m)
    {
      const md::MuscleStepMeasures& f = r->measures.back()[m];
      SCOPED_TRACE(c.muscles[m].name + ", " + std::to_string(r->numberOfSteps) + " steps");
      EXPECT_LE(std::abs(f.volumeChangePercent), 0.1);
      EXPECT_LE(f.maxNewBonePenetrationDepth, 0.5); // no new penetration of a bone deeper than 0.5 mm
      EXPECT_TRUE(f.converged);
      EXPECT_TRUE(r->points.back()[m].allFinite());
    }
  }
  const auto shift = &md::MuscleStepMeasures::maxStaticShift;
  const auto sharp = &md::MuscleStepMeasures::sharpEdgeCount;
  const auto flips = &md::MuscleStepMeasures::flippedTriangleCount;
  // Measured here: largest static shift 5.4 mm against 18.2 mm in one pass
  // with the paper's step and 17.1 mm with the method's own (0.29 and 0.31;
  // the issue asks for at most 0.6, the paper reports about half); 266 new
  // sharp edges against 414 and 476, 19 flipped triangles against 61 and 109.
  // The largest shift is one point's and moves by millimetres when the inputs
  // move by 1e-7: over six such perturbations it is 0.32-0.64 of the
  // one-pass figure, the sharp edges and flips always fewer (BENCHMARKS.md).
  // Solved on the muscle itself, no point enters a bone or another muscle: the
  // static resolution moves nothing (measured 0 mm), 131 sharp edges and 11 flips.
  for (const md::InterpolationResult* onePass : { &paper, &one })
  {
    SCOPED_TRACE(onePass == &paper ? "against the paper's one-pass method" : "against one pass of the method's step");
    for (const md::InterpolationResult* r : { &refit, &settled })
    {
      SCOPED_TRACE(r == &refit ? "hull-based, Refit" : "on the muscle's surface");
      EXPECT_LE(Largest(*r, shift), 0.6 * Largest(*onePass, shift));
      EXPECT_LT(Total(*r, sharp), Total(*onePass, sharp));
      EXPECT_LT(Total(*r, flips), Total(*onePass, flips));
    }
  }
  EXPECT_EQ(Total(settled, &md::MuscleStepMeasures::newPenetrationCount), 0);
  EXPECT_LE(Largest(settled, shift), 0.01);
  EXPECT_LT(Total(settled, sharp), Total(refit, sharp));
  // Refit against the paper's Rebuild: comparable quality (here 5.4 against
  // 8.1 mm, 266 against 274 sharp edges, 19 against 18 flips; over the
  // perturbations, BENCHMARKS.md).
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
  // completes, every muscle keeps its volume and its size. And the method
  // keeps its lead over the paper's one-pass method: hull-based, over seeds
  // 0-5 its largest static shift is 0.27-0.58 of the one-pass figure and it
  // has fewer flipped triangles over the three seeds together (seed by seed a
  // sample of its spread, issue 13: seed 1 has 33 against the one pass's 22);
  // solved on the muscle's surface, on every seed no static shift and fewer
  // sharp edges and flipped triangles.
  MotionCase c;
  if (!LhdlMotion("hip_flexion", 35, c))
  {
    GTEST_SKIP() << "LHDL data not found (set MUSCLEDEFORMATION_DATA_DIR)";
  }
  auto span = [](const md::Points& p) {
    return (p.colwise().maxCoeff() - p.colwise().minCoeff()).norm();
  };
  std::int64_t flips = 0, surfaceFlips = 0, paperFlips = 0;
  for (int seed : { 1, 2, 4 })
  {
    SCOPED_TRACE("seed " + std::to_string(seed));
    const MotionCase perturbed = Perturbed(c, seed);
    md::InterpolationResult r;
    md::InterpolationResult onSurface;
    ASSERT_NO_THROW(r = RunMethod(perturbed, 4, md::HullMode::Refit));
    ASSERT_NO_THROW(onSurface = RunOnSurface(perturbed));
    for (size_t m = 0; m < c.muscles.size(); ++m)
    {
      SCOPED_TRACE(c.muscles[m].name);
      const md::MuscleStepMeasures& f = r.measures.back()[m];
      EXPECT_LE(std::abs(f.volumeChangePercent), 0.1);
      EXPECT_LE(f.maxNewBonePenetrationDepth, 0.5);
      EXPECT_LT(span(r.points.back()[m]), 1.2 * span(perturbed.muscles[m].muscle.points));
    }
    const md::InterpolationResult paper = RunMethod(perturbed, 1, md::HullMode::Refit, 0.0);
    EXPECT_LE(Largest(r, &md::MuscleStepMeasures::maxStaticShift),
      0.6 * Largest(paper, &md::MuscleStepMeasures::maxStaticShift));
    const std::int64_t seedPaperFlips = Total(paper, &md::MuscleStepMeasures::flippedTriangleCount);
    for (size_t m = 0; m < c.muscles.size(); ++m)
    {
      const md::MuscleStepMeasures& f = onSurface.measures.back()[m];
      EXPECT_LE(std::abs(f.volumeChangePercent), 1e-4) << c.muscles[m].name;
      EXPECT_EQ(f.newPenetrationCount, 0) << c.muscles[m].name;
      EXPECT_TRUE(f.converged) << c.muscles[m].name;
    }
    EXPECT_LE(Largest(onSurface, &md::MuscleStepMeasures::maxStaticShift), 0.01);
    EXPECT_LT(Total(onSurface, &md::MuscleStepMeasures::flippedTriangleCount), seedPaperFlips);
    EXPECT_LT(
      Total(onSurface, &md::MuscleStepMeasures::sharpEdgeCount), Total(paper, &md::MuscleStepMeasures::sharpEdgeCount));
    flips += Total(r, &md::MuscleStepMeasures::flippedTriangleCount);
    surfaceFlips += Total(onSurface, &md::MuscleStepMeasures::flippedTriangleCount);
    paperFlips += seedPaperFlips;
  }
  std::printf(
    "[ measured ] flipped triangles over seeds 1, 2, 4: hull-based %lld, on the surface %lld, one pass %lld\n",
    static_cast<long long>(flips), static_cast<long long>(surfaceFlips), static_cast<long long>(paperFlips));
  EXPECT_LT(flips, paperFlips);
}

TEST(RealInterpolation, OnTheSurfaceNoTriangleTurnsOverInAnyPose)
{
  // The four poses of the benchmarks, solved on the muscles' surfaces (N = 4): no triangle turns over, no
  // step fails to converge, nothing is left in a bone for the static resolution to move, and
  // the volume is kept. With the cotangent weights unclamped, the gluteus medius's slivers at
  // its femoral insertion turned four triangles over at adduction -40 degrees, and one muscle
  // turned one over in each other pose.
  const std::pair<const char*, int> poses[] = { { "hip_flexion", 20 }, { "hip_flexion", 35 }, { "hip_adduction", 0 },
    { "hip_adduction", 40 } };
  for (const auto& [motion, frame] : poses)
  {
    MotionCase c;
    if (!LhdlMotion(motion, frame, c))
    {
      GTEST_SKIP() << "LHDL data not found (set MUSCLEDEFORMATION_DATA_DIR)";
    }
    // Rounded to float; adduction -40 degrees (where the folds were) also moved by 1e-7 with
    // its duplicates split (one such input costs 6 s to make, so not every pose).
    std::vector<int> seeds{ 0 };
    if (std::string(motion) == "hip_adduction" && frame == 0)
    {
      seeds.push_back(1);
    }
    for (int seed : seeds)
    {
      SCOPED_TRACE(std::string(motion) + " frame " + std::to_string(frame) + ", seed " + std::to_string(seed));
      const md::InterpolationResult r = RunOnSurface(Perturbed(c, seed, seed > 0));
      for (size_t m = 0; m < c.muscles.size(); ++m)
      {
        SCOPED_TRACE(c.muscles[m].name);
        for (int step = 1; step <= r.numberOfSteps; ++step)
        {
          EXPECT_TRUE(r.measures[step][m].converged) << "step " << step;
        }
        const md::MuscleStepMeasures& f = r.measures.back()[m];
        EXPECT_EQ(f.flippedTriangleCount, 0);
        EXPECT_EQ(f.newBonePenetrationCount, 0);
        EXPECT_LE(std::abs(f.volumeChangePercent), 1e-4);
      }
      EXPECT_LE(Largest(r, &md::MuscleStepMeasures::maxStaticShift), 0.01);
    }
  }
}

TEST(RealInterpolation, OnePassWithBonesPushingReportsTheFoldsItLeft)
{
  // Where bones push (contact rows), the unfolding keeps to the bones and can
  // leave folds it may not undo; DeformMuscles must still report them (it
  // once reported none). In one pass to 60 degrees the gluteus maximus and
  // the iliacus keep some (measured: 1 and 7).
  MotionCase c;
  if (!LhdlMotion("hip_flexion", 35, c))
  {
    GTEST_SKIP() << "LHDL data not found (set MUSCLEDEFORMATION_DATA_DIR)";
  }
  std::vector<md::TriangleMesh> hulls;
  for (const md::MuscleMotion& m : c.muscles)
  {
    hulls.push_back(md::BuildMuscleHull(m.muscle, md::HullParameters{}).result.hull);
  }
  std::vector<md::MuscleToDeform> toDeform;
  for (size_t m = 0; m < c.muscles.size(); ++m)
  {
    toDeform.push_back({ c.muscles[m].name, &c.muscles[m].muscle, &hulls[m], c.muscles[m].lines });
  }
  std::vector<std::string> names;
  std::vector<md::TriangleMesh> current;
  for (const md::BoneMotion& b : c.bones)
  {
    names.push_back(b.name);
    current.push_back(md::TriangleMesh{ b.current, b.rest.triangles });
  }
  const std::vector<md::Obstacle> bones = md::BuildObstacles(names, current);
  const std::vector<md::DeformationResult> results = md::DeformMuscles(toDeform, bones, md::StepDeformationDefaults());
  std::int64_t left = 0;
  for (size_t m = 0; m < results.size(); ++m)
  {
    const md::TriangleMesh& muscle = c.muscles[m].muscle;
    const std::int64_t recount = md::CountFlippedTriangles(muscle.points, results[m].points, muscle.triangles);
    EXPECT_EQ(results[m].flippedTriangles, recount) << c.muscles[m].name;
    left += recount;
  }
  ASSERT_GT(left, 0) << "no fold is left here any more: this case no longer checks how left folds are reported";
}
