// SPDX-License-Identifier: BSD-3-Clause
#include "Settle/SurfacePass.h"

namespace md
{
std::vector<SurfacePassResult> SettleInOnePass(const std::vector<MuscleToSettle>& muscles,
  const std::vector<FixedObstacle>& obstacles, const SettleParameters& parameters,
  const std::function<void(double)>& progress)
{
  const size_t count = muscles.size();
  std::vector<TriangleMesh> rest(count), settled(count);
  std::vector<const SurfaceEnergy*> energies(count);
  std::vector<std::vector<MatchedLine>> lines(count);
  std::vector<std::vector<MatchedLine>> restLines(count);
  std::vector<std::string> names(count);
  std::vector<double> volumes(count);
  for (size_t m = 0; m < count; ++m)
  {
    rest[m] = *muscles[m].muscle;
    settled[m] = rest[m];
    energies[m] = muscles[m].energy;
    lines[m] = muscles[m].lines;
    restLines[m] = StillLines(lines[m]);
    names[m] = muscles[m].name;
    volumes[m] = EnclosedVolume(rest[m].points, rest[m].triangles);
  }
  // The muscles' overlap with each other at rest is theirs; the obstacles' entries stay empty.
  OverlapMasks overlap = FindOverlaps(rest, {});
  for (std::vector<std::vector<char>>& masks : overlap)
  {
    masks.insert(masks.begin(), obstacles.size(), std::vector<char>{});
  }
  // The first step of a motion from the rest pose, with no bone known at rest.
  SettleMotion motion = StartMotion(rest, energies, restLines, {});
  // Near contacts are not watched (SettleParameters::contactLookahead): a settle from the rest
  // pose starts far from its answer, with many points deep in obstacles, and watched contacts
  // multiplied each iteration's solves without settling it (LHDL adduction -40 degrees: four of
  // six perturbed inputs stopped unsettled, one after 457 s). The one pass stays as it was.
  SettleParameters unwatched = parameters;
  unwatched.contactLookahead = 0;
  const std::vector<SettleReport> reports =
    SettleMuscles(settled, energies, lines, volumes, obstacles, &overlap, unwatched, &motion, progress);
  std::vector<SurfacePassResult> results(count);
  for (size_t m = 0; m < count; ++m)
  {
    SurfacePassResult& r = results[m];
    r.points = std::move(settled[m].points);
    r.report = reports[m];
    r.volumeChangePercent = 100.0 * (EnclosedVolume(r.points, rest[m].triangles) - volumes[m]) / volumes[m];
    r.flippedTriangles = CountFlippedTriangles(rest[m].points, r.points, rest[m].triangles);
    r.warnings = LinesThroughBones({ names[m] }, { lines[m] }, obstacles, nullptr, parameters.samplesPerSegment);
    if (!r.report.converged)
    {
      r.warnings.push_back("muscle '" + names[m] + "' did not settle within " +
        std::to_string(parameters.maximumIterations) + " iterations (its volume is off by " +
        std::to_string(r.volumeChangePercent) +
        " %): the motion may be too large for one pass; the interpolation method "
        "(InterpolatedMuscleDeformation) follows it step by step");
    }
  }
  return results;
}

std::vector<SurfacePassResult> SettleInOnePassThatCan(const std::vector<MuscleToSettle>& muscles,
  const std::vector<FixedObstacle>& obstacles, const SettleParameters& parameters, std::vector<std::string>& failures,
  const std::function<void(double)>& progress)
{
  return ForMusclesThatCan(muscles, failures, progress,
    [&](const std::vector<MuscleToSettle>& subset, const std::function<void(double)>& forward) {
      return SettleInOnePass(subset, obstacles, parameters, forward);
    });
}
}
