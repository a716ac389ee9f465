// SPDX-License-Identifier: BSD-3-Clause
// The one pass solved on the muscles' surfaces (SurfacePass.h): no point ends inside a bone, the
// volume is held, a line through a bone is said, a muscle that fails is left out, and the answer
// moves with rounding noise of the input continuously where the motion is moderate (on the
// phantom and the LHDL hip at 30 degrees of flexion).
#include "Geometry/TriangleTree.h"
#include "MotionCases.h"
#include "RealData.h"
#include "Settle/SurfacePass.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <memory>
#include <string>

namespace
{
/// A motion case's one pass on the surface: every muscle from its rest pose to its current pose,
/// the bones in the current pose.
struct OnePass
{
  std::vector<std::unique_ptr<md::SurfaceEnergy>> energies;
  std::vector<md::TriangleMesh> bones;
  std::vector<std::unique_ptr<md::TriangleTree>> trees;
  std::vector<md::FixedObstacle> obstacles;
  std::vector<md::MuscleToSettle> muscles;

  explicit OnePass(const MotionCase& c)
  {
    for (const md::BoneMotion& b : c.bones)
    {
      bones.push_back({ b.current, b.rest.triangles });
      trees.push_back(std::make_unique<md::TriangleTree>(bones.back()));
      obstacles.push_back({ b.name, trees.back().get() });
    }
    for (const md::MuscleMotion& m : c.muscles)
    {
      const std::vector<md::MatchedLine> restLines = md::StillLines(m.lines);
      energies.push_back(std::make_unique<md::SurfaceEnergy>(m.muscle, restLines, md::SettleParameters()));
      muscles.push_back({ m.name, &m.muscle, m.lines, energies.back().get() });
    }
  }
  std::vector<md::SurfacePassResult> Run(const md::SettleParameters& parameters = {}) const
  {
    return md::SettleInOnePass(muscles, obstacles, parameters);
  }
};

double Largest(const std::vector<md::SurfacePassResult>& a, const std::vector<md::SurfacePassResult>& b)
{
  double largest = 0;
  for (size_t m = 0; m < a.size(); ++m)
  {
    largest = std::max(largest, (a[m].points - b[m].points).rowwise().norm().maxCoeff());
  }
  return largest;
}
}

TEST(SurfacePass, OnThePhantomNoPointEndsInABoneAndRoundingChangesNothing)
{
  // The phantom at 30 degrees: the femur sweeps over the rectus femoris's action line, and the
  // paper's pass leaves the points the femur swept over inside it (530 of them at resolution 24).
  const MotionCase exact = PhantomMotion(30);
  const OnePass pass(exact);
  const std::vector<md::SurfacePassResult> settled = pass.Run();
  ASSERT_EQ(settled.size(), exact.muscles.size());
  for (size_t m = 0; m < settled.size(); ++m)
  {
    SCOPED_TRACE(exact.muscles[m].name);
    const md::SurfacePassResult& r = settled[m];
    EXPECT_TRUE(r.report.converged);
    EXPECT_LT(std::abs(r.volumeChangePercent), 1e-6);
    EXPECT_EQ(r.flippedTriangles, 0);
    EXPECT_GT((r.points - exact.muscles[m].muscle.points).rowwise().norm().maxCoeff(), 10.0); // it moved
    for (size_t b = 0; b < pass.trees.size(); ++b)
    {
      EXPECT_EQ(md::CountInsideTree(*pass.trees[b], r.points), 0) << exact.bones[b].name;
    }
    // Only the rectus femoris's line crosses a bone (the femur, by design of the phantom).
    EXPECT_EQ(r.warnings.size(), exact.muscles[m].name == "RectusFemoris" ? 1u : 0u);
  }
  // Measured: 1e-4 mm for noise and for split duplicates (the paper's pass: 3.2-4.8 mm).
  EXPECT_LT(Largest(settled, OnePass(Perturbed(exact, 1)).Run()), 0.001) << "1e-7 noise";
  EXPECT_LT(Largest(settled, OnePass(Perturbed(exact, 2, true)).Run()), 0.001) << "duplicates split";
}

TEST(SurfacePass, AMuscleThatFailsIsLeftOutAndTheOthersAreSettled)
{
  const MotionCase c = PhantomMotion(30);
  const OnePass pass(c);
  std::vector<std::string> failures(c.muscles.size());
  failures[1] = "muscle '" + c.muscles[1].name + "' failed before";
  const std::vector<md::SurfacePassResult> some =
    md::SettleInOnePassThatCan(pass.muscles, pass.obstacles, md::SettleParameters(), failures);
  const std::vector<md::SurfacePassResult> all = pass.Run();
  ASSERT_EQ(some.size(), c.muscles.size());
  EXPECT_EQ(some[1].points.rows(), 0);
  EXPECT_GT(some[0].points.rows(), 0);
  EXPECT_GT(some[2].points.rows(), 0);
  EXPECT_EQ(failures[0], "");
  EXPECT_EQ(failures[2], "");
}

TEST(SurfacePass, OnTheHipAModerateMotionIsReproducible)
{
  // LHDL hip, flexion 30 degrees (hip_flexion.mot frame 20), four muscles in one pass. Measured:
  // 1e-7 noise 0.0005 mm, split duplicates 0.0009 mm (the paper's pass: millimetres). A large
  // motion in one pass (flexion 60, adduction -40) can end on either side of a bone under noise:
  // that is what the interpolation method's steps are for (BENCHMARKS.md).
  MotionCase exact;
  if (!LhdlMotion("hip_flexion", 20, exact))
  {
    GTEST_SKIP() << "LHDL data not found (set MUSCLEDEFORMATION_DATA_DIR)";
  }
  const std::vector<md::SurfacePassResult> settled = OnePass(exact).Run();
  for (size_t m = 0; m < settled.size(); ++m)
  {
    EXPECT_TRUE(settled[m].report.converged) << exact.muscles[m].name;
    EXPECT_LT(std::abs(settled[m].volumeChangePercent), 1e-4) << exact.muscles[m].name;
  }
  EXPECT_LT(Largest(settled, OnePass(Perturbed(exact, 1)).Run()), 0.005) << "1e-7 noise";
  EXPECT_LT(Largest(settled, OnePass(Perturbed(exact, 1, true)).Run()), 0.01) << "duplicates split";
}

TEST(SurfacePass, AtALargeAdductionOpposedContactsDoNotBlowTheSettleUp)
{
  // LHDL hip, adduction 40 degrees (hip_adduction.mot frame 40) in one pass. Where the gluteus
  // maximus and medius cross, two contacts can bound the same gap from opposite sides; kept
  // both, seed 3's settle (duplicates kept and split) blew up (in BenchmarkStability's run, at
  // its third iteration) and handed all four muscles back unsettled, 8.2 mm from the exact
  // input's answer. Measured with the
  // outside contact left out: every run settles, seed 3 within 0.0003 mm. (Seeds 1 and 2 can
  // still settle on another side, up to 4.6 mm away: a one pass cannot know which way the bones
  // went, BENCHMARKS.md.)
  MotionCase exact;
  if (!LhdlMotion("hip_adduction", 40, exact))
  {
    GTEST_SKIP() << "LHDL data not found (set MUSCLEDEFORMATION_DATA_DIR)";
  }
  const std::vector<md::SurfacePassResult> settled = OnePass(exact).Run();
  for (const bool split : { false, true })
  {
    const std::vector<md::SurfacePassResult> perturbed = OnePass(Perturbed(exact, 3, split)).Run();
    for (size_t m = 0; m < perturbed.size(); ++m)
    {
      EXPECT_TRUE(perturbed[m].report.converged) << exact.muscles[m].name << (split ? ", split" : "");
      EXPECT_LT(std::abs(perturbed[m].volumeChangePercent), 1e-4) << exact.muscles[m].name;
    }
    EXPECT_LT(Largest(settled, perturbed), 0.005) << (split ? "duplicates split" : "1e-7 noise");
  }
}

TEST(SurfacePass, AMuscleThatDoesNotSettleIsSaid)
{
  // The phantom at 65 degrees settles in one pass in 68 iterations; given 5, no muscle settles,
  // and each says so by name, with Converged false.
  const MotionCase c = PhantomMotion(65);
  const OnePass pass(c);
  md::SettleParameters parameters;
  EXPECT_TRUE(pass.Run(parameters)[0].report.converged);
  parameters.maximumIterations = 5;
  const std::vector<md::SurfacePassResult> unsettled = pass.Run(parameters);
  for (size_t m = 0; m < c.muscles.size(); ++m)
  {
    EXPECT_FALSE(unsettled[m].report.converged) << c.muscles[m].name;
    const std::string said = "muscle '" + c.muscles[m].name + "' did not settle within 5 iterations";
    EXPECT_TRUE(std::any_of(unsettled[m].warnings.begin(), unsettled[m].warnings.end(),
      [&](const std::string& w) { return w.find(said) != std::string::npos; }))
      << c.muscles[m].name;
  }
}
