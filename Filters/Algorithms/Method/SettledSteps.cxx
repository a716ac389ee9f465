// SPDX-License-Identifier: BSD-3-Clause
#include "Method/SettledSteps.h"

#include "Common/Clock.h"
#include "Common/MuscleFailures.h"
#include "Deformation/VolumeConstrainedSolver.h"
#include "Geometry/MeshChecks.h"

#include <algorithm>
#include <exception>

namespace md
{
namespace
{
/// Adds `more` (a later settle's reports) to `reports`: iterations and seconds add up, the
/// contacts are the later settle's, and converged is whether both were.
void AddReports(std::vector<SettleReport>& reports, const std::vector<SettleReport>& more)
{
  for (size_t m = 0; m < reports.size(); ++m)
  {
    reports[m].iterations += more[m].iterations;
    reports[m].seconds += more[m].seconds;
    reports[m].converged = reports[m].converged && more[m].converged;
    reports[m].pointsInContact = more[m].pointsInContact;
  }
}

/// Adds an attempt that did not converge (`failed`) to the reports of the settles that replaced
/// it: its iterations and seconds were spent too.
void AddFailedAttempt(std::vector<SettleReport>& reports, const std::vector<SettleReport>& failed)
{
  for (size_t m = 0; m < reports.size(); ++m)
  {
    reports[m].iterations += failed[m].iterations;
    reports[m].seconds += failed[m].seconds;
  }
}

/// A settle that starts with the last one's contacts (SettleMotion::carryContacts) converges in
/// 5 to 23 iterations through the LHDL hip's motions; one that has not in this many started from
/// contacts that no longer hold and is done again from none, as every settle that carries none
/// is. (A step whose muscles jump, where an OpenSim path point comes or goes, is settled in parts
/// that each move no farther than an ordinary frame's few times over: SettleParameters::
/// largestCarriedMove.)
constexpr int kCarriedContactIterations = 30;

/// Settles the muscles (`muscles`' points out) from where `motion` is, the pose at fraction
/// `from` of the motion, to the pose at `to`, the bones' trees already refitted there (and
/// there again on return). A settle that
/// does not converge (it diverged, or swung to the end of its iterations) is done again from
/// the same start in two halves, through the pose halfway, each halved again while it does not
/// converge, `halvings` times at most: which iterate a settle stops at is no answer (it moves
/// with rounding noise by millimetres). The reports add up every attempt's iterations and
/// seconds; `converged` is that of the settles kept. `progress` runs from 0 to 1 over each
/// attempt. `freeMinima`: FreeMinima of the pose at `to` when the caller has them (empty: found
/// by the settle).
std::vector<SettleReport> SettleToPose(const SettleInput& in, double from, double to, int halvings,
  std::vector<TriangleMesh>& muscles, SettleMotion& motion, const std::function<void(double)>& progress,
  std::vector<Points> freeMinima = {})
{
  if (motion.carryContacts && !motion.held.empty())
  {
    SettleMotion carried = motion;
    SettleParameters brief = in.parameters;
    brief.maximumIterations = std::min(brief.maximumIterations, kCarriedContactIterations);
    const std::vector<SettleReport> tried = SettleMuscles(muscles, in.energies, LinesAt(in, to), in.volumes, in.fixed,
      &in.restOverlap, brief, &carried, progress, freeMinima);
    if (std::all_of(tried.begin(), tried.end(), [](const SettleReport& r) { return r.converged; }))
    {
      motion = std::move(carried);
      return tried;
    }
    motion.held.clear();
    std::vector<SettleReport> again =
      SettleToPose(in, from, to, halvings, muscles, motion, progress, std::move(freeMinima));
    AddFailedAttempt(again, tried);
    return again;
  }
  const SettleMotion start = halvings > 0 ? motion : SettleMotion();
  std::vector<SettleReport> reports = SettleMuscles(muscles, in.energies, LinesAt(in, to), in.volumes, in.fixed,
    &in.restOverlap, in.parameters, &motion, progress, std::move(freeMinima));
  if (halvings == 0 || std::all_of(reports.begin(), reports.end(), [](const SettleReport& r) { return r.converged; }))
  {
    return reports;
  }
  motion = start;
  const double halfway = 0.5 * (from + to);
  RefitBones(in, halfway);
  std::vector<SettleReport> halves = SettleToPose(in, from, halfway, halvings - 1, muscles, motion, progress);
  RefitBones(in, to);
  AddReports(halves, SettleToPose(in, halfway, to, halvings - 1, muscles, motion, progress));
  AddFailedAttempt(halves, reports);
  return halves;
}

}

/// The muscles' matched lines from the rest pose to the pose at `fraction` of the motion.
std::vector<std::vector<MatchedLine>> LinesAt(const SettleInput& in, double fraction)
{
  std::vector<std::vector<MatchedLine>> lines(in.lineMotions.size());
  for (size_t m = 0; m < lines.size(); ++m)
  {
    for (size_t l = 0; l < in.lineMotions[m].size(); ++l)
    {
      MatchedLine line = in.restLines[m][l];
      line.current = in.lineMotions[m][l].AtFraction(fraction);
      lines[m].push_back(std::move(line));
    }
  }
  return lines;
}

/// The bones' trees refitted to the pose at `fraction` of the motion.
void RefitBones(const SettleInput& in, double fraction)
{
#pragma omp parallel for schedule(dynamic, 1)
  for (int b = 0; b < static_cast<int>(in.obstacles.size()); ++b)
  {
    in.obstacles[b].tree->Refit(in.boneMotions[b].AtFraction(fraction));
  }
}

/// the pose at `to`, in as many equal parts as SettleParts asks (each by SettleToPose): the
/// number of parts depends on how far the muscles' minimum moves, continuously in the input,
/// where SettleToPose's halving depends on whether a settle converged. A step of one part is
/// settled as it was before either, to the bit.
std::vector<SettleReport> SettleStep(const SettleInput& in, double from, double to, std::vector<TriangleMesh>& muscles,
  SettleMotion& motion, const std::function<void(double)>& progress)
{
  RefitBones(in, to);
  std::vector<Points> freeMinima = FreeMinima(in.energies, LinesAt(in, to), in.fixed);
  const double move = LargestStartMove(motion, in.energies, freeMinima);
  // A motion carries each settle's contacts to the next (SettleMotion::carryContacts) in parts
  // whose minimum moves no farther than an ordinary frame's few times over, so that even where
  // the muscles jump (an OpenSim path point comes or goes) each part goes on from the equilibrium
  // the last one ended in.
  const int parts = SettleParts(move, in.parameters, motion.carryContacts);
  std::vector<SettleReport> reports;
  auto settlePart = [&](int k, std::vector<Points> minima) {
    const double start = k == 1 ? from : from + (to - from) * (k - 1) / parts;
    const double end = k == parts ? to : from + (to - from) * k / parts;
    if (parts > 1) // one part: the bones are at `to` already
    {
      RefitBones(in, end);
    }
    const std::vector<SettleReport> part = SettleToPose(
      in, start, end, kSettleHalvings, muscles, motion, [&](double fraction) { progress((k - 1 + fraction) / parts); },
      std::move(minima));
    if (reports.empty())
    {
      reports = part;
    }
    else
    {
      AddReports(reports, part);
    }
  };
  for (int k = 1; k < parts; ++k)
  {
    settlePart(k, {});
  }
  settlePart(parts, std::move(freeMinima)); // the last part settles to `to`, whose minima are found above
  return reports;
}

std::vector<std::string> SettleWarnings(const SettleInput& in, double to, const std::vector<std::string>& names,
  const LineSamplesInside& linesInBonesAtRest, const std::vector<SettleReport>& settled, std::set<std::string>& warned)
{
  const std::vector<std::vector<MatchedLine>> wholeMotion = LinesAt(in, to); // rest pose -> this pose
  std::vector<std::string> said =
    LinesThroughBones(names, wholeMotion, in.fixed, &linesInBonesAtRest, in.parameters.samplesPerSegment);
  if (std::any_of(settled.begin(), settled.end(), [](const SettleReport& r) { return !r.converged; }))
  {
    said.push_back("the muscles did not settle within " + std::to_string(in.parameters.maximumIterations) +
      " iterations, not even with the step split into " + std::to_string(1 << kSettleHalvings) +
      " (the last iterate is kept, with Converged 0): another NumberOfSteps may settle them");
  }
  std::vector<std::string> news;
  for (std::string& warning : said)
  {
    if (warned.insert(warning).second) // said once, at the first step that has it
    {
      news.push_back(std::move(warning));
    }
  }
  return news;
}

std::vector<MuscleStepMeasures> ResolveAndMeasure(std::vector<TriangleMesh>& next,
  const std::vector<MuscleMotion>& muscles, const std::vector<FixedObstacle>& fixed, const OverlapMasks& restOverlap,
  const std::vector<NewSharpEdges>& sharpEdges, const std::vector<double>& restVolumes,
  const InterpolationParameters& parameters, const std::vector<StepOutcome>& outcomes,
  const std::vector<MuscleStepMeasures>& previous, std::vector<MuscleStepMeasures> measures,
  const std::vector<std::vector<char>>* outsideBones)
{
  const size_t count = next.size();
  StaticResolveResult resolved =
    ResolveStaticIntersections(next, fixed, &restOverlap, parameters.staticResolve, outsideBones);
  // The volume is given back over the whole surface, except at the overlap
  // the rest pose has (which stays where it is); a point against an obstacle
  // cannot move outwards through it anyway.
  std::vector<std::vector<char>> held(count);
  std::vector<Points> given(count); // the points the static resolution found its penetration at
  for (size_t m = 0; m < count; ++m)
  {
    given[m] = std::move(next[m].points);
    next[m].points = resolved.points[m];
    held[m].assign(static_cast<size_t>(next[m].points.rows()), 0);
    for (const std::vector<char>& overlap : restOverlap[m])
    {
      for (size_t i = 0; i < overlap.size(); ++i)
      {
        held[m][i] = held[m][i] || overlap[i];
      }
    }
  }
  if (parameters.deformation.preserveVolume)
  {
    RestoreVolumes(next, restVolumes, fixed, held);
  }
  // Where nothing moved (a settle leaves nothing inside an obstacle and the volume held), the
  // penetration is what the static resolution found at the same points.
  bool moved = false;
  for (size_t m = 0; m < count && !moved; ++m)
  {
    moved = given[m] != next[m].points;
  }
  const std::vector<Penetration> penetration =
    moved ? MeasureNewPenetration(next, fixed, &restOverlap) : std::move(resolved.found);
  // The muscles' measures in parallel (each its own; counts and sums within one muscle as before).
#pragma omp parallel for schedule(dynamic, 1)
  for (int k = 0; k < static_cast<int>(count); ++k)
  {
    const size_t m = static_cast<size_t>(k);
    MuscleStepMeasures& s = measures[m];
    const TriangleMesh& rest = muscles[m].muscle;
    s.volumeChangePercent = 100.0 * (EnclosedVolume(next[m].points, rest.triangles) - restVolumes[m]) / restVolumes[m];
    s.newPenetrationCount = penetration[m].count;
    s.maxNewPenetrationDepth = penetration[m].maxDepth;
    s.newBonePenetrationCount = penetration[m].fixedCount;
    s.maxNewBonePenetrationDepth = penetration[m].fixedMaxDepth;
    s.stepStaticShift = resolved.reports[m].maxShift;
    s.maxStaticShift = std::max(previous[m].maxStaticShift, s.stepStaticShift);
    s.staticallyMovedPoints = resolved.reports[m].penetratingPoints;
    s.sharpEdgeCount = sharpEdges[m].Count(next[m].points);
    s.flippedTriangleCount = CountFlippedTriangles(rest.points, next[m].points, rest.triangles);
    s.stepIterations = outcomes[m].iterations;
    s.iterations = previous[m].iterations + s.stepIterations;
    s.converged = previous[m].converged && outcomes[m].converged;
    s.pointsFrozenInObstacles = outcomes[m].pointsFrozen;
    s.deformationSeconds = outcomes[m].seconds;
    s.staticShift = std::move(resolved.shift[m]);
  }
  return measures;
}

std::vector<NewSharpEdges> MuscleSharpEdges(const std::vector<MuscleMotion>& muscles)
{
  std::vector<NewSharpEdges> edges(muscles.size());
#pragma omp parallel for schedule(dynamic, 1)
  for (int m = 0; m < static_cast<int>(muscles.size()); ++m)
  {
    edges[m] = NewSharpEdges(muscles[m].muscle.points, muscles[m].muscle.triangles);
  }
  return edges;
}

void FuseAttachments(OverlapMasks& masks, const std::vector<MuscleMotion>& muscles)
{
  for (size_t m = 0; m < muscles.size() && m < masks.size(); ++m)
  {
    for (const Attachment& area : muscles[m].attachments)
    {
      const auto bone = static_cast<size_t>(area.boneIndex);
      if (area.boneIndex < 0 || bone >= masks[m].size() || masks[m][bone].empty())
      {
        continue;
      }
      for (Eigen::Index i : area.points)
      {
        masks[m][bone][static_cast<size_t>(i)] = 1;
      }
    }
  }
}

std::vector<std::shared_ptr<const SurfaceEnergy>> BuildEnergies(const std::vector<MuscleMotion>& muscles,
  const std::vector<std::vector<MatchedLine>>& restLines, const SettleParameters& parameters, RestMappingCache* kept,
  std::vector<double>& seconds)
{
  const size_t count = muscles.size();
  RestMappingCache scratch;
  RestMappingCache& rest = kept ? *kept : scratch;
  rest.muscles.resize(count);
  std::vector<std::shared_ptr<const SurfaceEnergy>> energies(count);
  std::vector<std::exception_ptr> failed(count); // no exception may leave a parallel region
  for (size_t m = 0; m < count; ++m)
  {
    const KeptSurfaceEnergy& entry = rest.muscles[m].surfaceEnergy;
    if (entry.Holds(muscles[m].muscle, restLines[m], parameters, muscles[m].attachments))
    {
      energies[m] = entry.energy;
    }
  }
#pragma omp parallel for schedule(dynamic, 1)
  for (int k = 0; k < static_cast<int>(count); ++k)
  {
    const size_t m = static_cast<size_t>(k);
    if (energies[m])
    {
      continue;
    }
    const auto energyStart = Clock::now();
    try
    {
      energies[m] =
        std::make_shared<const SurfaceEnergy>(muscles[m].muscle, restLines[m], parameters, muscles[m].attachments);
    }
    catch (const InputError& e)
    {
      failed[m] = std::make_exception_ptr(OfMuscle(InputError("muscle '" + muscles[m].name + "': " + e.what()), m));
    }
    catch (const ComputationError& e)
    {
      failed[m] =
        std::make_exception_ptr(OfMuscle(ComputationError("muscle '" + muscles[m].name + "': " + e.what()), m));
    }
    catch (...)
    {
      failed[m] = std::current_exception();
    }
    seconds[m] += SecondsSince(energyStart);
  }
  for (size_t m = 0; m < count; ++m)
  {
    KeptSurfaceEnergy& entry = rest.muscles[m].surfaceEnergy;
    if (energies[m] && energies[m] != entry.energy)
    {
      entry.Keep(energies[m], muscles[m].muscle, restLines[m], parameters, muscles[m].attachments);
      ++rest.energyBuildCount;
    }
  }
  for (const std::exception_ptr& failure : failed)
  {
    if (failure)
    {
      std::rethrow_exception(failure);
    }
  }
  return energies;
}

void MeasuresToWorld(const LocalFrame& frame, MuscleStepMeasures& s)
{
  s.maxNewPenetrationDepth = frame.LengthToWorld(s.maxNewPenetrationDepth);
  s.maxNewBonePenetrationDepth = frame.LengthToWorld(s.maxNewBonePenetrationDepth);
  s.stepStaticShift = frame.LengthToWorld(s.stepStaticShift);
  s.maxStaticShift = frame.LengthToWorld(s.maxStaticShift);
  frame.VectorsToWorld(s.staticShift);
}
}
