// SPDX-License-Identifier: BSD-3-Clause
// One rest-pose -> current-pose pass of the muscle deformation
// (Filters/Algorithms/Deformation/MuscleDeformer.h) on the phantom and, when present, the LHDL
// right hip at hip flexion 30 and 60 degrees and adduction -40 and 40: per
// muscle and pose, iterations, time, volume change, flipped triangles, points
// held by obstacles and left inside them, action-line samples inside. Prints
// figures; asserts nothing (see the tests).
//
//   BenchmarkDeformation [data folder]
#include "Deformation/MuscleDeformer.h"
#include "Geometry/SurfaceRepair.h"
#include "Hull/ProgressiveHull.h"
#include "Motion/ActionLineMatching.h"
#include "Phantom/Phantom.h"
#include "RealData.h"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

namespace
{
using Clock = std::chrono::steady_clock;
double Seconds(Clock::time_point since)
{
  return std::chrono::duration<double>(Clock::now() - since).count();
}

struct Case
{
  std::string name;
  std::vector<std::string> muscleNames;
  std::vector<md::TriangleMesh> muscles;
  std::vector<std::vector<md::Points>> linesRest, linesCurrent;
  std::vector<std::string> boneNames;
  std::vector<md::TriangleMesh> bonesCurrent;
};

/// What depends on the rest pose only: each muscle's hull and mean value coordinates.
struct Prepared
{
  std::vector<md::TriangleMesh> hulls;
  std::vector<md::WeightMatrix> weights;
  std::vector<double> hullSeconds, weightSeconds;
};

Prepared Prepare(const Case& c)
{
  Prepared p;
  for (const md::TriangleMesh& muscle : c.muscles)
  {
    auto start = Clock::now();
    md::RepairReport report;
    const md::TriangleMesh clean = md::RepairClosedSurface(muscle, report);
    p.hulls.push_back(md::BuildProgressiveHull(clean, md::HullParameters{}, &report.pointsToEnclose).hull);
    p.hullSeconds.push_back(Seconds(start));
    start = Clock::now();
    p.weights.push_back(md::MeanValueCoordinates(p.hulls.back(), muscle.points));
    p.weightSeconds.push_back(Seconds(start));
  }
  return p;
}

/// One pass, every muscle together; `single` >= 0 deforms that muscle alone.
void Run(const Case& c, const Prepared& prepared, int single)
{
  std::vector<md::MuscleToDeform> muscles;
  for (size_t m = 0; m < c.muscles.size(); ++m)
  {
    if (single >= 0 && static_cast<int>(m) != single)
    {
      continue;
    }
    md::MuscleToDeform muscle{ c.muscleNames[m], &c.muscles[m], &prepared.hulls[m], {}, &prepared.weights[m] };
    for (size_t l = 0; l < c.linesRest[m].size(); ++l)
    {
      const md::MatchedActionLines matched = md::MatchActionLines(c.linesRest[m][l], c.linesCurrent[m][l], 0.01);
      muscle.lines.push_back({ matched.rest, matched.current });
    }
    muscles.push_back(std::move(muscle));
  }
  // Median of three passes; the obstacle hierarchies are built inside each timing.
  constexpr int runs = 3;
  std::vector<double> totals, treeTimes;
  std::vector<md::DeformationResult> results;
  for (int run = 0; run < runs; ++run)
  {
    const auto start = Clock::now();
    const std::vector<md::Obstacle> bones = md::BuildObstacles(c.boneNames, c.bonesCurrent);
    treeTimes.push_back(Seconds(start));
    results = md::DeformMuscles(muscles, bones, md::DeformationParameters{});
    totals.push_back(Seconds(start));
  }
  std::sort(totals.begin(), totals.end());
  std::sort(treeTimes.begin(), treeTimes.end());
  // Points inside a bone at the end (every point tested).
  std::vector<std::unique_ptr<md::TriangleTree>> bones;
  for (const md::TriangleMesh& bone : c.bonesCurrent)
  {
    bones.push_back(std::make_unique<md::TriangleTree>(bone));
  }
  for (size_t m = 0; m < results.size(); ++m)
  {
    const md::DeformationResult& r = results[m];
    std::int64_t inside = 0;
    for (const auto& bone : bones)
    {
      inside += md::CountInsideTree(*bone, r.points);
    }
    const size_t index = single >= 0 ? static_cast<size_t>(single) : m;
    std::printf("%-22s %-18s %6ld %7.1f %6.1f %4d (%3d) %s %7.1f %+10.5f %5ld %6ld %6ld %6ld %6.2f %6.2f\n",
      c.name.c_str(), muscles[m].name.c_str(), static_cast<long>(c.muscles[index].points.rows()),
      1e3 * prepared.hullSeconds[index], 1e3 * prepared.weightSeconds[index], r.iterations, r.coarseIterations,
      r.converged ? "yes" : " no", 1e3 * r.seconds, r.volumeChangePercent, static_cast<long>(r.flippedTriangles),
      static_cast<long>(r.verticesFrozen), static_cast<long>(r.verticesStopped), static_cast<long>(inside),
      r.restSamplesInside, r.currentSamplesInside);
    for (const std::string& warning : r.warnings)
    {
      std::printf("    warning: %s\n", warning.c_str());
    }
  }
  std::printf("%-22s %-18s pass %.1f ms (median of %d), of which obstacle hierarchies %.1f ms\n\n", c.name.c_str(),
    single >= 0 ? "(this muscle alone)" : "(all muscles)", 1e3 * totals[runs / 2], runs, 1e3 * treeTimes[runs / 2]);
}
}

int main(int argc, char** argv)
{
  const std::string folder = argc > 1 ? argv[1] : "";
#ifdef NDEBUG
  const char* build = "Release";
#else
  const char* build = "Debug (figures not representative)";
#endif
  std::printf("One RP -> CP pass of the muscle deformation (%s build). Times: median of 3 passes.\n", build);
  std::printf("Columns: case, muscle, points, hull ms, mean value coordinates ms (both once per muscle, before\n"
              "any pass), iterations (of them coarse), converged, pass ms (this muscle's share),\n"
              "volume change %%, flipped triangles, points frozen inside a bone, points stopped at an obstacle,\n"
              "points inside a bone at the end, action-line samples inside the rest / deformed muscle.\n\n");

  {
    const md::Phantom phantom = md::BuildPhantom(md::PhantomParameters{});
    Case c;
    c.name = "phantom 60 deg";
    for (const md::PhantomMuscle& muscle : phantom.muscles)
    {
      c.muscleNames.push_back(muscle.name);
      c.muscles.push_back(muscle.rest);
      c.linesRest.push_back(muscle.actionLinesRest);
      c.linesCurrent.push_back(muscle.actionLinesCurrent);
    }
    for (const md::PhantomBone& bone : phantom.bones)
    {
      c.boneNames.push_back(bone.name);
      c.bonesCurrent.push_back(md::TriangleMesh{ bone.currentPoints, bone.rest.triangles });
    }
    Run(c, Prepare(c), -1);
  }

  const std::pair<const char*, int> poses[] = { { "hip_flexion", 20 }, { "hip_flexion", 35 }, { "hip_adduction", 0 },
    { "hip_adduction", 40 } };
  for (const auto& [motion, frame] : poses)
  {
    LhdlCase lhdl;
    if (!LoadLhdlCase(motion, frame, lhdl, folder))
    {
      std::printf("LHDL data not found: skipped (pass the data folder or set MUSCLEDEFORMATION_DATA_DIR)\n");
      break;
    }
    Case c;
    char name[64];
    std::snprintf(name, sizeof name, "LHDL flex %.0f add %.0f", lhdl.frame.hipFlexion, lhdl.frame.hipAdduction);
    c.name = name;
    for (const LhdlCase::Muscle& muscle : lhdl.muscles)
    {
      c.muscleNames.push_back(muscle.name);
      c.muscles.push_back(muscle.surface);
      c.linesRest.push_back(muscle.linesRest);
      c.linesCurrent.push_back(muscle.linesCurrent);
    }
    c.boneNames = lhdl.boneNames;
    c.bonesCurrent = lhdl.bonesCurrent;
    static Prepared prepared; // the rest pose is the same in every frame
    if (prepared.hulls.empty())
    {
      prepared = Prepare(c);
    }
    Run(c, prepared, 0); // the gluteus maximus alone: the speed target
    Run(c, prepared, -1);
  }
  return 0;
}
