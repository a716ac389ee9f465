// SPDX-License-Identifier: BSD-3-Clause
// The whole interpolation method (Filters/Algorithms/Method/InterpolatedDeformation.h) on
// the phantom (30 degrees of flexion unless told) and, when present, the LHDL right hip at
// hip flexion 60 degrees: the one-pass method (one step, then the static
// resolution), the interpolation method with the hull refitted (Refit) and
// rebuilt before every step (Rebuild, the paper), side by side; the one-pass
// method with the paper's deformation step and with the method's own. Per muscle and
// in total: hull time, per-step time, total, and every quality measure, and a checksum of every
// step's points and measures (to compare two builds to the bit). Prints figures; asserts nothing
// (see the tests).
//
//   BenchmarkInterpolation [data folder] [number of steps] [phantom flexion]
//   [all|one-pass|refit|rebuild|refit-paper-step|settle]
//                          [LHDL motion] [frame]      (default hip_flexion 35: 60 degrees of flexion)
//                          [perturbation]  (-1: none, the default; 0: inputs rounded to float; s > 0: rounded
//                                           after a seeded random move of 1e-7 of each coordinate)
#include "RealData.h"
#include "StepChecksum.h"

#include <cstdio>
#include <cstdlib>
#include <string>

namespace
{
void Run(const MotionCase& c, const char* label, int steps, md::HullMode mode, double contactWeight,
  bool settleOnSurface = false)
{
  md::InterpolationParameters parameters;
  parameters.numberOfSteps = steps;
  parameters.hullMode = mode;
  parameters.deformation.contactWeight = contactWeight;
  parameters.settleOnSurface = settleOnSurface;
  md::InterpolationResult r;
  try
  {
    r = md::DeformByInterpolation(c.muscles, c.bones, parameters);
  }
  catch (const md::InputError& e)
  {
    std::printf("\n%s, %s (N = %d): failed: %s\n", c.name.c_str(), label, steps, e.what());
    return;
  }
  std::printf("\n%s, %s (N = %d): total %.2f s\n", c.name.c_str(), label, r.numberOfSteps, r.totalSeconds);
  double restHulls = 0;
  for (double s : r.restHullSeconds)
  {
    restHulls += s;
  }
  std::printf("  rest hulls and mappings %.2f s; steps:", restHulls);
  for (int j = 1; j <= r.numberOfSteps; ++j)
  {
    double hull = 0;
    for (const md::MuscleStepMeasures& m : r.measures[j])
    {
      hull += m.hullSeconds;
    }
    std::printf(" %.2f s (hull %.3f s)", r.stepSeconds[j], hull);
  }
  std::printf("\n  %-18s %7s %7s %7s %6s %7s %6s %8s %6s %6s %5s %5s %6s\n", "muscle", "hull s", "dV %", "newPen",
    "depth", "bonePen", "depth", "maxShift", "sharp", "flips", "iter", "conv", "frozen");
  for (size_t m = 0; m < c.muscles.size(); ++m)
  {
    const md::MuscleStepMeasures& f = r.measures.back()[m];
    double hull = r.restHullSeconds[m];
    std::int64_t frozen = 0;
    for (int j = 1; j <= r.numberOfSteps; ++j)
    {
      hull += r.measures[j][m].hullSeconds;
      frozen += r.measures[j][m].pointsFrozenInObstacles;
    }
    std::printf("  %-18s %7.3f %7.4f %7lld %6.2f %7lld %6.2f %8.3f %6lld %6lld %5d %5s %6lld\n",
      c.muscles[m].name.c_str(), hull, f.volumeChangePercent, static_cast<long long>(f.newPenetrationCount),
      f.maxNewPenetrationDepth, static_cast<long long>(f.newBonePenetrationCount), f.maxNewBonePenetrationDepth,
      f.maxStaticShift, static_cast<long long>(f.sharpEdgeCount), static_cast<long long>(f.flippedTriangleCount),
      f.iterations, f.converged ? "yes" : "no", static_cast<long long>(frozen));
  }
  std::printf("  largest static shift (mm) and new sharp edges at each step:\n");
  for (size_t m = 0; m < c.muscles.size(); ++m)
  {
    std::printf("  %-18s", c.muscles[m].name.c_str());
    for (int j = 1; j <= r.numberOfSteps; ++j)
    {
      std::printf(
        " %7.3f (%lld)", r.measures[j][m].stepStaticShift, static_cast<long long>(r.measures[j][m].sharpEdgeCount));
    }
    std::printf("\n");
  }
  md::Fnv1a checksum; // every step's points and measures: two runs compared to the bit
  for (int j = 0; j <= r.numberOfSteps; ++j)
  {
    AddStepToChecksum(checksum, r.points[static_cast<size_t>(j)], r.measures[static_cast<size_t>(j)]);
  }
  std::printf(
    "  checksum of every step's points and measures: %016llx\n", static_cast<unsigned long long>(checksum.Value()));
  for (const std::string& w : r.warnings)
  {
    std::printf("  warning: %s\n", w.c_str());
  }
  for (const std::string& f : r.failures)
  {
    if (!f.empty())
    {
      std::printf("  FAILED: %s\n", f.c_str());
    }
  }
}

/// `runs`: "all", or one of "one-pass", "refit", "rebuild", "refit-paper-step"
/// (Refit with the paper's deformation step, not in "all"). The one-pass
/// method runs twice: with the paper's deformation step (bones only stop
/// points) and with the method's own (bones push the muscle).
void Compare(const MotionCase& c, int steps, const std::string& runs)
{
  const double contact = md::StepDeformationDefaults().contactWeight;
  if (runs == "all" || runs == "one-pass")
  {
    Run(c, "one-pass method, paper's step", 1, md::HullMode::Refit, 0.0);
    Run(c, "one-pass method, bones push", 1, md::HullMode::Refit, contact);
  }
  if (runs == "all" || runs == "refit")
  {
    Run(c, "interpolation, Refit", steps, md::HullMode::Refit, contact);
  }
  if (runs == "all" || runs == "rebuild")
  {
    Run(c, "interpolation, Rebuild", steps, md::HullMode::Rebuild, contact);
  }
  if (runs == "refit-paper-step") // what bones pushing adds
  {
    Run(c, "interpolation, Refit, paper's step", steps, md::HullMode::Refit, 0.0);
  }
  if (runs == "all" || runs == "settle")
  {
    Run(c, "interpolation, settled on the full mesh", steps, md::HullMode::Refit, contact, true);
  }
}
}

int main(int argc, char* argv[])
{
  const std::string folder = argc > 1 ? argv[1] : "";
  const int steps = argc > 2 ? std::atoi(argv[2]) : 4;
  std::printf("Columns (final step): hull time (rest hull + per-step refit or rebuild), volume change %%, new\n"
              "penetration of bones and other muscles, count and deepest (mm), the same of bones only, largest static "
              "shift over the steps (mm), new sharp edges\n"
              "(> 60 deg), flipped triangles, iterations, converged in every step, points frozen in bones\n"
              "(summed over steps).\n");
  const std::string runs = argc > 4 ? argv[4] : "all";
  if (runs != "all" && runs != "one-pass" && runs != "refit" && runs != "rebuild" && runs != "refit-paper-step" &&
    runs != "settle")
  {
    std::fprintf(stderr, "unknown run '%s': all, one-pass, refit, rebuild, refit-paper-step or settle\n", runs.c_str());
    return 2;
  }
  Compare(PhantomMotion(argc > 3 ? std::atof(argv[3]) : 30), steps, runs);
  MotionCase lhdl;
  const std::string motion = argc > 5 ? argv[5] : "hip_flexion";
  const int frame = argc > 6 ? std::atoi(argv[6]) : 35;
  if (!LhdlMotion(motion, frame, lhdl, folder))
  {
    std::printf("\nLHDL data not found: skipped (pass the data folder or set MUSCLEDEFORMATION_DATA_DIR)\n");
    return 0;
  }
  const int perturbation = argc > 7 ? std::atoi(argv[7]) : -1;
  Compare(perturbation < 0 ? lhdl : Perturbed(lhdl, perturbation), steps, runs);
  return 0;
}
