// SPDX-License-Identifier: BSD-3-Clause
#include "Method/InterpolatedDeformation.h"

#include "Method/HullSteps.h"
#include "Method/SettledSteps.h"

#include "Common/MuscleFailures.h"
#include "Deformation/VolumeConstrainedSolver.h"
#include "Geometry/MeshChecks.h"
#include "Motion/ActionLineMatching.h"

#include <Eigen/Cholesky>

#include <algorithm>
#include <cmath>
#include <exception>
#include <memory>
#include <numeric>
#include <set>

namespace md
{
namespace
{
/// What makes a muscle unusable before any work (empty when nothing does).
std::string ProblemOf(const MuscleMotion& m)
{
  if (m.muscle.points.rows() == 0 || m.muscle.triangles.rows() == 0)
  {
    return "muscle '" + m.name + "' has no surface";
  }
  if (m.lines.empty())
  {
    return "muscle '" + m.name + "' has no action line: nothing says where it goes";
  }
  for (const MatchedLine& line : m.lines)
  {
    if (line.rest.rows() < 2 || line.rest.rows() != line.current.rows())
    {
      return "an action line of muscle '" + m.name +
        "' is not matched: it needs at least two points, as many in the rest pose as in the current pose";
    }
    if (!KnotsFit(line.knots, line.rest.rows()))
    {
      return "an action line of muscle '" + m.name + "' names its own points wrongly: " + kKnotsRule;
    }
  }
  return {};
}

/// The bones concern every muscle (the muscles' own input is ProblemOf's, checked before).
void ValidateBones(const std::vector<BoneMotion>& bones)
{
  for (const BoneMotion& b : bones)
  {
    if (b.rest.points.rows() != b.current.rows())
    {
      throw InputError("bone '" + b.name + "' has " + std::to_string(b.rest.points.rows()) +
        " points in the rest pose but " + std::to_string(b.current.rows()) +
        " in the current pose: both poses must have the same points");
    }
    if (!AllFinite(b.rest.points) || !AllFinite(b.current))
    {
      throw InputError("bone '" + b.name + "' has non-finite coordinates (NaN or infinity)");
    }
    if (b.rest.triangles.rows() == 0)
    {
      throw InputError("bone '" + b.name + "' has no surface (no triangles)");
    }
  }
}

double LargestMotion(const std::vector<MuscleMotion>& muscles, const std::vector<BoneMotion>& bones)
{
  double largest = 0;
  for (const BoneMotion& b : bones)
  {
    largest = std::max(largest, MaximumDisplacement(b.rest.points, b.current));
  }
  for (const MuscleMotion& m : muscles)
  {
    for (const MatchedLine& line : m.lines)
    {
      if (line.rest.rows() == line.current.rows())
      {
        largest = std::max(largest, MaximumDisplacement(line.rest, line.current));
      }
    }
  }
  return largest;
}
}

std::vector<MatchedLine> MatchMuscleLines(const std::vector<Points>& rest, const std::vector<Points>& current,
  double tolerance, std::vector<std::string>& notes, const std::vector<Knots>& knots)
{
  if (rest.size() != current.size())
  {
    throw InputError("the rest pose has " + std::to_string(rest.size()) + " action lines but the current pose has " +
      std::to_string(current.size()) + ": the lines of a muscle pair by order");
  }
  std::vector<MatchedLine> lines;
  for (size_t l = 0; l < rest.size(); ++l)
  {
    const MatchedActionLines pair = MatchActionLines(rest[l], current[l], tolerance);
    if (l < knots.size() && !KnotsFit(knots[l], rest[l].rows()))
    {
      throw InputError("action line " + std::to_string(l + 1) + " names its own points wrongly: " + kKnotsRule);
    }
    const Knots own = l < knots.size() ? MatchedKnots(knots[l], pair.restInserted) : Knots();
    lines.push_back({ pair.rest, pair.current, own });
  }
  notes = LimitActionLinePoints(lines);
  return lines;
}

int ResolveNumberOfSteps(const std::vector<BoneMotion>& bones, const InterpolationParameters& parameters)
{
  if (parameters.numberOfSteps > 0)
  {
    return parameters.numberOfSteps;
  }
  double largest = 0;
  for (const BoneMotion& b : bones)
  {
    if (b.rest.points.rows() == b.current.rows())
    {
      largest = std::max(largest, MaximumDisplacement(b.rest.points, b.current));
    }
  }
  return AutomaticNumberOfSteps(largest, parameters.maximumStepDisplacement);
}

namespace
{
/// The MethodMotions of the muscles and bones; a bone that does not move rigidly is said in
/// `warnings`.
MethodMotions Interpolators(const std::vector<MuscleMotion>& muscles, const std::vector<BoneMotion>& bones,
  InterpolationMode mode, std::vector<std::string>& warnings)
{
  std::vector<Points> bonesRest, bonesCurrent;
  for (const BoneMotion& b : bones)
  {
    bonesRest.push_back(b.rest.points);
    bonesCurrent.push_back(b.current);
  }
  MethodMotions motions;
  motions.bones = PoseInterpolators(bonesRest, bonesCurrent, mode);
  for (size_t b = 0; b < bones.size(); ++b)
  {
    if (const std::string warning = motions.bones[b].NonRigidWarning("bone '" + bones[b].name + "'"); !warning.empty())
    {
      warnings.push_back(warning);
    }
  }
  motions.lines.resize(muscles.size());
  for (size_t m = 0; m < muscles.size(); ++m)
  {
    for (const MatchedLine& line : muscles[m].lines)
    {
      try
      {
        motions.lines[m].emplace_back(line.rest, line.current, mode);
      }
      catch (Error& e)
      {
        throw OfMuscle(InputError(std::string("an action line of muscle '") + muscles[m].name + "': " + e.what()), m);
      }
    }
  }
  return motions;
}

/// What the steps solved on the muscles' surfaces share (docs/DESIGN.md section 7): the
/// full-mesh energies (rest pose only, kept for every step), the matched lines at step 0, where
/// the last step's settle ended (each step's settle goes on from the last one's answer, from the
/// rest pose at the first, so the answer depends continuously on the input and not at all on a
/// hull), and the lines' samples inside the bones at rest (the scans' own overlap).
struct SurfaceSteps
{
  std::vector<std::shared_ptr<const SurfaceEnergy>> energies;
  std::vector<const SurfaceEnergy*> energyPointers;
  std::vector<std::vector<MatchedLine>> restLines; ///< StillLines
  SettleMotion settleMotion;
  LineSamplesInside linesInBonesAtRest;
};

/// The start of the steps on the surfaces, the muscles `current` in the rest pose and the bones
/// (`fixed`) too; the energies are built (or taken from `kept`), their seconds in `seconds`,
/// and a muscle part of which no line drives is said in `warnings`.
SurfaceSteps StartOnSurface(const std::vector<MuscleMotion>& muscles, const MethodMotions& motions, int steps,
  const std::vector<TriangleMesh>& current, const std::vector<FixedObstacle>& fixed,
  const InterpolationParameters& parameters, RestMappingCache* kept, std::vector<double>& seconds,
  std::vector<std::string>& warnings)
{
  const size_t count = muscles.size();
  SurfaceSteps s;
  s.restLines.resize(count);
  for (size_t m = 0; m < count; ++m)
  {
    for (size_t l = 0; l < motions.lines[m].size(); ++l)
    {
      const Points rest = motions.lines[m][l].AtStep(0, steps);
      s.restLines[m].push_back({ rest, rest, muscles[m].lines[l].knots });
    }
  }
  s.energies = BuildEnergies(muscles, s.restLines, parameters.settle, kept, seconds);
  for (size_t m = 0; m < count; ++m)
  {
    s.energyPointers.push_back(s.energies[m].get());
    if (const std::string warning = s.energies[m]->UndrivenWarning(muscles[m].name); !warning.empty())
    {
      warnings.push_back(warning);
    }
  }
  s.settleMotion = StartMotion(current, s.energyPointers, s.restLines, fixed);
  s.linesInBonesAtRest = LineSamplesInBones(s.restLines, fixed, parameters.settle.samplesPerSegment);
  return s;
}

/// Step j of `steps` solved on the muscles' surfaces (`in`): `next` gets the muscles settled
/// from where the last step left them (`current`, as `surface`'s settle motion holds them) to
/// the pose of step j; what to warn of is added to `warnings` (each once: `warned`).
std::vector<StepOutcome> SettleMethodStep(const SettleInput& in, int j, int steps,
  const std::vector<MuscleMotion>& muscles, const std::vector<TriangleMesh>& current,
  const std::vector<std::string>& names, SurfaceSteps& surface, std::vector<TriangleMesh>& next,
  std::set<std::string>& warned, std::vector<std::string>& warnings, const std::function<void(double)>& progress)
{
  const size_t count = muscles.size();
  for (size_t m = 0; m < count; ++m)
  {
    next[m].triangles = muscles[m].muscle.triangles; // the points come from settleMotion
    next[m].points = current[m].points;
  }
  const double to = static_cast<double>(j) / steps; // AtStep(j, steps)'s fraction
  const std::vector<SettleReport> settled =
    SettleStep(in, static_cast<double>(j - 1) / steps, to, next, surface.settleMotion, progress);
  for (const std::string& warning : SettleWarnings(in, to, names, surface.linesInBonesAtRest, settled, warned))
  {
    warnings.push_back("step " + std::to_string(j) + ": " + warning);
  }
  std::vector<StepOutcome> outcomes(count);
  for (size_t m = 0; m < count; ++m)
  {
    outcomes[m] = { settled[m].iterations, settled[m].converged, 0, settled[m].seconds };
  }
  return outcomes;
}

/// The bones' hierarchies in the rest pose.
std::vector<Obstacle> RestBoneObstacles(const std::vector<BoneMotion>& bones)
{
  std::vector<std::string> names;
  std::vector<TriangleMesh> meshes;
  for (const BoneMotion& b : bones)
  {
    names.push_back(b.name);
    meshes.push_back(b.rest);
  }
  return BuildObstacles(names, meshes);
}

/// The method's result with its step 0, the rest pose, and room for `steps` more.
InterpolationResult RestPoseResult(const std::vector<MuscleMotion>& muscles, int steps)
{
  InterpolationResult result;
  result.numberOfSteps = steps;
  std::vector<Points> restPoints;
  for (const MuscleMotion& m : muscles)
  {
    restPoints.push_back(m.muscle.points);
  }
  result.points.assign(1, restPoints);
  result.measures.assign(1, std::vector<MuscleStepMeasures>(muscles.size()));
  result.stepSeconds.assign(1, 0.0);
  result.restHullSeconds.assign(muscles.size(), 0.0);
  return result;
}

/// Each muscle's overlap at rest with the bones alone (OverlapMasks puts the `bones` first).
OverlapMasks BoneOverlapOf(const OverlapMasks& restOverlap, size_t bones)
{
  OverlapMasks overlap(restOverlap.size());
  for (size_t m = 0; m < restOverlap.size(); ++m)
  {
    overlap[m].assign(restOverlap[m].begin(), restOverlap[m].begin() + static_cast<std::ptrdiff_t>(bones));
  }
  return overlap;
}

/// Nothing moves: every step is the rest pose, exactly.
void ZeroMotion(InterpolationResult& result)
{
  result.zeroMotion = true;
  result.warnings.push_back("the motion has zero length (the current pose equals the rest pose): "
                            "the muscles are returned as they are");
  for (int j = 1; j <= result.numberOfSteps; ++j)
  {
    result.points.push_back(result.points[0]);
    result.measures.push_back(result.measures[0]);
    result.stepSeconds.push_back(0.0);
  }
}

/// DeformByInterpolation on input already in its local frame.
InterpolationResult DeformInLocalFrame(const std::vector<MuscleMotion>& muscles, const std::vector<BoneMotion>& bones,
  const InterpolationParameters& parameters, const std::function<void(double)>& progress, RestMappingCache* kept)
{
  const auto start = Clock::now();
  auto report = [&](double fraction) {
    if (progress)
    {
      progress(fraction);
    }
  };
  ValidateBones(bones);
  const size_t count = muscles.size();
  const int steps = ResolveNumberOfSteps(bones, parameters);
  InterpolationResult result = RestPoseResult(muscles, steps);
  if (LargestMotion(muscles, bones) == 0)
  {
    ZeroMotion(result);
    result.totalSeconds = SecondsSince(start);
    report(1.0);
    return result;
  }

  const MethodMotions motions = Interpolators(muscles, bones, parameters.interpolationMode, result.warnings);
  std::vector<double> restVolumes(count);
  for (size_t m = 0; m < count; ++m)
  {
    restVolumes[m] = EnclosedVolume(muscles[m].muscle.points, muscles[m].muscle.triangles);
  }
  const bool settle = parameters.settleOnSurface;
  HullPass hullPass;
  if (!settle)
  {
    hullPass = PrepareHullPass(muscles, parameters, kept, result.restHullSeconds, report);
  }

  // The bones' hierarchies, built once in the rest pose and refitted to the
  // pose of each step: the bones move rigidly, or nearly so, which keeps the
  // boxes tight, and a refit costs far less than a build. Overlap the rest
  // pose already has (the scans overlap the bones) is left alone by the
  // static resolution and not counted as new penetration.
  const std::vector<Obstacle> obstacles = RestBoneObstacles(bones);
  const std::vector<FixedObstacle> fixed = FixedObstacles(obstacles);
  std::vector<TriangleMesh> current(count);
  for (size_t m = 0; m < count; ++m)
  {
    current[m] = muscles[m].muscle;
  }
  OverlapMasks restOverlap = FindOverlaps(current, fixed);
  for (size_t m = 0; m < count; ++m)
  {
    if (const std::string problem = MostlyInAnObstacle(current[m], muscles[m].name, m, fixed, restOverlap);
        !problem.empty())
    {
      throw OfMuscle(InputError(problem), m);
    }
  }
  FuseAttachments(restOverlap, muscles);
  const std::vector<NewSharpEdges> sharpEdges = MuscleSharpEdges(muscles);
  std::vector<std::string> names;
  for (const MuscleMotion& m : muscles)
  {
    names.push_back(m.name);
  }
  SurfaceSteps surface;
  if (settle)
  {
    surface = StartOnSurface(
      muscles, motions, steps, current, fixed, parameters, kept, result.restHullSeconds, result.warnings);
    report(0.2);
  }
  else
  {
    // Contact rows leave the rest pose's overlap with each bone alone.
    hullPass.boneOverlap = BoneOverlapOf(restOverlap, bones.size());
  }
  double stepStart = 0.2;
  const double stepShare = 0.8 / steps;
  std::vector<MuscleStepMeasures> previous(count);
  std::set<std::string> warned;
  for (int j = 1; j <= steps; ++j)
  {
    const auto stepClock = Clock::now();
    auto stepProgress = [&](double fraction) {
      report(stepStart + 0.9 * stepShare * fraction);
    };
    std::vector<MuscleStepMeasures> measures(count);
    std::vector<TriangleMesh> next(count);
    std::vector<DeformationResult> deformed(count); // the hull-based pass's
    std::vector<StepOutcome> outcomes(count);
    if (settle)
    {
      const SettleInput in{ obstacles, motions.bones, motions.lines, surface.restLines, surface.energyPointers,
        restVolumes, fixed, restOverlap, parameters.settle };
      outcomes =
        SettleMethodStep(in, j, steps, muscles, current, names, surface, next, warned, result.warnings, stepProgress);
    }
    else
    {
      outcomes = HullMethodStep(hullPass, j, steps, muscles, motions, current, restVolumes, obstacles, parameters,
        measures, next, deformed, warned, result.warnings, stepProgress);
    }
    const std::vector<std::vector<char>> outsideBones = ProvenOutsideBones(surface.settleMotion.boneClearance);
    measures = ResolveAndMeasure(next, muscles, fixed, restOverlap, sharpEdges, restVolumes, parameters, outcomes,
      previous, measures, settle ? &outsideBones : nullptr);
    if (!settle)
    {
      RefitHulls(hullPass, next, deformed, muscles, parameters, measures);
    }
    std::vector<Points> stepPoints(count);
    for (size_t m = 0; m < count; ++m)
    {
      stepPoints[m] = next[m].points;
    }
    current = std::move(next);
    previous = measures;
    result.points.push_back(std::move(stepPoints));
    result.measures.push_back(std::move(measures));
    result.stepSeconds.push_back(SecondsSince(stepClock));
    stepStart += stepShare;
    report(stepStart);
  }
  result.totalSeconds = SecondsSince(start);
  report(1.0);
  return result;
}
}

namespace
{
/// DeformByInterpolation of every muscle or none: throws what the first failure throws.
InterpolationResult DeformEveryMuscle(const std::vector<MuscleMotion>& muscles, const std::vector<BoneMotion>& bones,
  const InterpolationParameters& parameters, const std::function<void(double)>& progress, RestMappingCache* kept)
{
  // Everything in the muscles' local frame, lengths given in data units with it.
  std::vector<const Points*> restPoints;
  for (const MuscleMotion& m : muscles)
  {
    restPoints.push_back(&m.muscle.points);
  }
  const LocalFrame frame = LocalFrame::Around(restPoints);
  std::vector<MuscleMotion> localMuscles = muscles;
  for (MuscleMotion& m : localMuscles)
  {
    frame.ToLocal(m.muscle.points);
    for (MatchedLine& line : m.lines)
    {
      frame.ToLocal(line.rest);
      frame.ToLocal(line.current);
    }
    for (Attachment& area : m.attachments)
    {
      frame.ToLocal(area.anchorsRest);
    }
  }
  std::vector<BoneMotion> localBones = bones;
  for (BoneMotion& b : localBones)
  {
    frame.ToLocal(b.rest.points);
    frame.ToLocal(b.current);
  }
  InterpolationParameters local = parameters;
  local.maximumStepDisplacement = frame.LengthToLocal(parameters.maximumStepDisplacement);
  local.deformation.convergenceTolerance = frame.LengthToLocal(parameters.deformation.convergenceTolerance);

  InterpolationResult result = DeformInLocalFrame(localMuscles, localBones, local, progress, kept);
  ResultToWorld(frame, restPoints, result);
  return result;
}
}

InterpolationResult DeformByInterpolation(const std::vector<MuscleMotion>& muscles,
  const std::vector<BoneMotion>& bones, const InterpolationParameters& parameters,
  const std::function<void(double)>& progress, RestMappingCache* kept)
{
  // A muscle that fails is left out and the method runs again on the others, exactly as if it
  // had not been given; the rest hulls built so far are kept. What is wrong with a muscle's own
  // input is found first, so that the local frame and the kept hulls are those of the muscles
  // that can go.
  const size_t count = muscles.size();
  RestMappingCache scratch;
  RestMappingCache& cache = kept ? *kept : scratch;
  cache.muscles.resize(count);
  std::vector<std::string> failures(count);
  std::transform(muscles.begin(), muscles.end(), failures.begin(), ProblemOf);
  const std::function<void(double)> forward = ForwardOnly(progress);
  InterpolationResult result = WithoutFailedMuscles(failures, [&](const std::vector<size_t>& active) {
    std::vector<MuscleMotion> subset;
    for (size_t m : active)
    {
      subset.push_back(muscles[m]);
    }
    InterpolationResult some = WithCacheSubset(cache, active,
      [&](RestMappingCache& subCache) { return DeformEveryMuscle(subset, bones, parameters, forward, &subCache); });
    if (active.size() == count)
    {
      return some;
    }
    // Back to the order of all muscles; a failed one has no points and default measures.
    auto spread = [&](auto& perActive, auto empty) {
      std::vector<decltype(empty)> perMuscle(count, empty);
      for (size_t k = 0; k < active.size(); ++k)
      {
        perMuscle[active[k]] = std::move(perActive[k]);
      }
      perActive = std::move(perMuscle);
    };
    for (size_t j = 0; j < some.points.size(); ++j)
    {
      spread(some.points[j], Points(0, 3));
      spread(some.measures[j], MuscleStepMeasures{});
    }
    spread(some.restHullSeconds, 0.0);
    return some;
  });
  result.failures = std::move(failures);
  return result;
}

void ResultToWorld(const LocalFrame& frame, const std::vector<const Points*>& restPoints, InterpolationResult& result)
{
  for (size_t j = 0; j < result.points.size(); ++j)
  {
    for (size_t m = 0; m < result.points[j].size(); ++m)
    {
      if (j == 0 || result.zeroMotion)
      {
        result.points[j][m] = *restPoints[m]; // the input itself, not its round trip
      }
      else
      {
        frame.ToWorld(result.points[j][m]);
      }
      MeasuresToWorld(frame, result.measures[j][m]);
    }
  }
}
}
