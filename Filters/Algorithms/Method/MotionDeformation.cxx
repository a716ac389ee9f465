// SPDX-License-Identifier: BSD-3-Clause
#include "Method/MotionDeformation.h"

#include "Common/Clock.h"
#include "Common/MuscleFailures.h"
#include "Deformation/VolumeConstrainedSolver.h"
#include "Geometry/LocalFrame.h"
#include "Geometry/MeshChecks.h"
#include "Method/SettledSteps.h"
#include "Motion/ActionLineMatching.h"

#include <algorithm>
#include <set>

namespace md
{
namespace
{
/// What makes a muscle unusable before any work (empty when nothing does).
std::string ProblemOf(const MotionDeformation::Muscle& m)
{
  if (m.rest.points.rows() == 0 || m.rest.triangles.rows() == 0)
  {
    return "muscle '" + m.name + "' has no surface";
  }
  if (m.restLines.empty())
  {
    return "muscle '" + m.name + "' has no action line: nothing says where it goes";
  }
  for (size_t l = 0; l < m.restLines.size(); ++l)
  {
    const Points& line = m.restLines[l];
    if (line.rows() < 2 || !AllFinite(line))
    {
      return "an action line of muscle '" + m.name + "' has fewer than two points or non-finite coordinates";
    }
    if (l < m.restKnots.size() && !KnotsFit(m.restKnots[l], line.rows()))
    {
      return "action line " + std::to_string(l + 1) + " of muscle '" + m.name +
        "' names its own points wrongly: " + kKnotsRule;
    }
  }
  if (!AllFinite(m.rest.points))
  {
    return "muscle '" + m.name + "' has non-finite coordinates (NaN or infinity)";
  }
  return {};
}

/// The bones of the rest pose checked: each has a surface and finite coordinates.
void CheckRestBones(const std::vector<MotionDeformation::Bone>& bones)
{
  for (const MotionDeformation::Bone& b : bones)
  {
    if (b.rest.triangles.rows() == 0)
    {
      throw InputError("bone '" + b.name + "' has no surface (no triangles)");
    }
    if (!AllFinite(b.rest.points))
    {
      throw InputError("bone '" + b.name + "' has non-finite coordinates (NaN or infinity)");
    }
  }
}

/// The full-mesh energies of the muscles (`local`, their rest lines `localLines`) whose
/// `failures` entry is empty, as WithoutFailedMuscles: a muscle whose energy cannot be built gets
/// its message there and is left out. `active` gets the muscles that go, in order; `kept` (when
/// given) keeps the energies by muscle for a later motion of the same rest pose.
std::vector<std::shared_ptr<const SurfaceEnergy>> ActiveEnergies(const std::vector<MuscleMotion>& local,
  const std::vector<std::vector<MatchedLine>>& localLines, const SettleParameters& parameters, RestMappingCache* kept,
  std::vector<std::string>& failures, std::vector<size_t>& active)
{
  RestMappingCache scratch;
  RestMappingCache& cache = kept ? *kept : scratch;
  cache.muscles.resize(local.size());
  std::vector<double> seconds(local.size(), 0.0);
  return WithoutFailedMuscles(failures, [&](const std::vector<size_t>& going) {
    std::vector<MuscleMotion> subset;
    std::vector<std::vector<MatchedLine>> subsetLines;
    for (size_t m : going)
    {
      subset.push_back(local[m]);
      subsetLines.push_back(localLines[m]);
    }
    auto built = WithCacheSubset(cache, going,
      [&](RestMappingCache& subCache) { return BuildEnergies(subset, subsetLines, parameters, &subCache, seconds); });
    active = going;
    return built;
  });
}
}

Points AtRestParameters(const Points& restLine, const Points& line)
{
  if (line.rows() == restLine.rows())
  {
    NormalisedArcLength(line); // the same checks
    return line;
  }
  const std::vector<double> restParameters = NormalisedArcLength(restLine);
  const std::vector<double> parameters = NormalisedArcLength(line);
  Points out(restLine.rows(), 3);
  for (Eigen::Index i = 0; i < restLine.rows(); ++i)
  {
    out.row(i) = PointAtParameter(line, parameters, restParameters[static_cast<size_t>(i)]);
  }
  return out;
}

double LargestSecondDifference(const Points& older, const Points& old, const Points& now)
{
  if (older.rows() != old.rows() || old.rows() != now.rows() || now.rows() == 0)
  {
    return 0.0;
  }
  return (now - 2.0 * old + older).rowwise().norm().maxCoeff();
}

double LargestSecondDifference(const MotionPose& older, const MotionPose& old, const MotionPose& now)
{
  double largest = 0;
  for (size_t b = 0; b < now.bones.size() && b < old.bones.size() && b < older.bones.size(); ++b)
  {
    largest = std::max(largest, LargestSecondDifference(older.bones[b], old.bones[b], now.bones[b]));
  }
  for (size_t m = 0; m < now.lines.size() && m < old.lines.size() && m < older.lines.size(); ++m)
  {
    for (size_t l = 0; l < now.lines[m].size() && l < old.lines[m].size() && l < older.lines[m].size(); ++l)
    {
      largest = std::max(largest, LargestSecondDifference(older.lines[m][l], old.lines[m][l], now.lines[m][l]));
    }
  }
  return largest;
}

struct MotionDeformation::State
{
  std::vector<TriangleMesh> current; ///< [active muscle], after the last frame's static resolution and volume
  SettleMotion settle;               ///< where the last settle ended
  std::vector<MuscleStepMeasures> previous;
  MotionPose pose; ///< the last frame's, in the local frame ([active muscle] for the lines)
  std::set<std::string> warned;
  int frames = 0; ///< frames advanced to from the rest pose
};

struct MotionDeformation::Internals
{
  LocalFrame frame;
  InterpolationParameters parameters; ///< lengths local
  std::vector<size_t> active;         ///< the muscles that go, in order
  std::vector<std::string> failures;  ///< [muscle]
  std::vector<std::string> warnings;
  std::vector<std::string> names;                  ///< [active]
  std::vector<MuscleMotion> muscles;               ///< [active], local; their lines are not used
  std::vector<std::vector<MatchedLine>> restLines; ///< [active], local, StillLines
  std::vector<std::shared_ptr<const SurfaceEnergy>> energies;
  std::vector<const SurfaceEnergy*> energyPointers;
  std::vector<double> restVolumes;
  std::vector<Obstacle> obstacles;
  std::vector<FixedObstacle> fixed;
  std::vector<std::string> boneNames;
  OverlapMasks restOverlap;
  std::vector<NewSharpEdges> sharpEdges; ///< [active]
  LineSamplesInside linesInBonesAtRest;
  size_t muscleCount = 0;
  double preparationSeconds = 0;
};

MotionDeformation::MotionDeformation(const std::vector<Muscle>& muscles, const std::vector<Bone>& bones,
  const InterpolationParameters& parameters, RestMappingCache* kept)
  : In(std::make_unique<Internals>())
{
  const auto start = Clock::now();
  Internals& in = *this->In;
  in.muscleCount = muscles.size();
  CheckRestBones(bones);
  in.failures.resize(muscles.size());
  std::transform(muscles.begin(), muscles.end(), in.failures.begin(), ProblemOf);
  std::vector<const Points*> restPoints;
  for (size_t m = 0; m < muscles.size(); ++m)
  {
    if (in.failures[m].empty())
    {
      restPoints.push_back(&muscles[m].rest.points);
    }
  }
  in.frame = LocalFrame::Around(restPoints);
  in.parameters = parameters;
  in.parameters.maximumStepDisplacement = in.frame.LengthToLocal(parameters.maximumStepDisplacement);
  in.parameters.deformation.convergenceTolerance = in.frame.LengthToLocal(parameters.deformation.convergenceTolerance);

  // Every muscle in the local frame; those whose energy cannot be built are left out.
  std::vector<MuscleMotion> local(muscles.size());
  std::vector<std::vector<MatchedLine>> localLines(muscles.size());
  for (size_t m = 0; m < muscles.size(); ++m)
  {
    local[m].name = muscles[m].name;
    local[m].muscle = muscles[m].rest;
    in.frame.ToLocal(local[m].muscle.points);
    local[m].attachments = muscles[m].attachments;
    for (Attachment& area : local[m].attachments)
    {
      in.frame.ToLocal(area.anchorsRest);
    }
    localLines[m] = StillLines(muscles[m].restLines, muscles[m].restKnots);
    for (MatchedLine& line : localLines[m])
    {
      in.frame.ToLocal(line.rest);
      line.current = line.rest;
    }
  }
  std::vector<TriangleMesh> restBones;
  for (const Bone& b : bones)
  {
    in.boneNames.push_back(b.name);
    restBones.push_back(b.rest);
    in.frame.ToLocal(restBones.back().points);
  }
  in.obstacles = BuildObstacles(in.boneNames, restBones);
  in.fixed = FixedObstacles(in.obstacles);
  // A muscle that lies in a bone (given as a bone too) is left out, as the interpolation method
  // leaves it out (MostlyInAnObstacle).
  for (size_t m = 0; m < muscles.size(); ++m)
  {
    if (in.failures[m].empty())
    {
      in.failures[m] =
        MostlyInAnObstacle(local[m].muscle, muscles[m].name, 0, in.fixed, FindOverlaps({ local[m].muscle }, in.fixed));
    }
  }
  in.energies = ActiveEnergies(local, localLines, in.parameters.settle, kept, in.failures, in.active);
  for (size_t k = 0; k < in.active.size(); ++k)
  {
    const size_t m = in.active[k];
    in.muscles.push_back(local[m]);
    in.restLines.push_back(localLines[m]);
    in.names.push_back(muscles[m].name);
    in.energyPointers.push_back(in.energies[k].get());
    in.restVolumes.push_back(EnclosedVolume(local[m].muscle.points, local[m].muscle.triangles));
    if (const std::string warning = in.energies[k]->UndrivenWarning(muscles[m].name); !warning.empty())
    {
      in.warnings.push_back(warning);
    }
  }

  auto state = std::make_shared<State>();
  for (const MuscleMotion& m : in.muscles)
  {
    state->current.push_back(m.muscle);
  }
  in.restOverlap = FindOverlaps(state->current, in.fixed);
  FuseAttachments(in.restOverlap, in.muscles);
  in.sharpEdges = MuscleSharpEdges(in.muscles);
  state->settle = StartMotion(state->current, in.energyPointers, in.restLines, in.fixed);
  state->settle.carryContacts = true; // a frame's contacts are the last frame's, moved on
  in.linesInBonesAtRest = LineSamplesInBones(in.restLines, in.fixed, in.parameters.settle.samplesPerSegment);
  state->previous.resize(in.muscles.size());
  for (const TriangleMesh& b : restBones)
  {
    state->pose.bones.push_back(b.points);
  }
  for (const std::vector<MatchedLine>& lines : in.restLines)
  {
    state->pose.lines.emplace_back();
    for (const MatchedLine& line : lines)
    {
      state->pose.lines.back().push_back(line.rest);
    }
  }
  this->Rest = std::move(state);
  this->Now = this->Rest;
  in.preparationSeconds = SecondsSince(start);
}

MotionDeformation::~MotionDeformation() = default;

const std::vector<std::string>& MotionDeformation::Failures() const
{
  return this->In->failures;
}

const std::vector<std::string>& MotionDeformation::Warnings() const
{
  return this->In->warnings;
}

double MotionDeformation::PreparationSeconds() const
{
  return this->In->preparationSeconds;
}

std::shared_ptr<const MotionDeformation::State> MotionDeformation::Save() const
{
  return this->Now;
}

void MotionDeformation::Resume(const std::shared_ptr<const State>& state)
{
  this->Now = state ? state : this->Rest;
}

size_t MotionDeformation::StateBytes(const State& state)
{
  size_t bytes = sizeof(State);
  auto add = [&](const Points& p) {
    bytes += static_cast<size_t>(p.size()) * sizeof(double);
  };
  for (const TriangleMesh& m : state.current)
  {
    add(m.points);
    bytes += static_cast<size_t>(m.triangles.size()) * sizeof(m.triangles(0, 0));
  }
  for (const Points& p : state.settle.points)
  {
    add(p);
  }
  for (const Points& p : state.settle.free)
  {
    add(p);
  }
  bytes += state.settle.held.size() * sizeof(state.settle.held[0]);
  for (const std::vector<double>& clearance : state.settle.boneClearance)
  {
    bytes += clearance.size() * sizeof(double);
  }
  bytes += state.settle.bonePlacements.size() * sizeof(RigidFit); // boneReference is shared by every state
  for (const MuscleStepMeasures& s : state.previous)
  {
    add(s.staticShift);
  }
  for (const Points& p : state.pose.bones)
  {
    add(p);
  }
  for (const std::vector<Points>& lines : state.pose.lines)
  {
    for (const Points& p : lines)
    {
      add(p);
    }
  }
  return bytes;
}

MotionPose MotionDeformation::ToLocalPose(const MotionPose& worldPose) const
{
  const Internals& in = *this->In;
  const State& from = *this->Now;
  if (worldPose.bones.size() != in.obstacles.size())
  {
    throw InputError("the pose has " + std::to_string(worldPose.bones.size()) + " bones, the rest pose " +
      std::to_string(in.obstacles.size()));
  }
  if (worldPose.lines.size() != in.muscleCount)
  {
    throw InputError("the pose has the action lines of " + std::to_string(worldPose.lines.size()) +
      " muscles, the rest pose " + std::to_string(in.muscleCount));
  }
  MotionPose pose;
  for (size_t b = 0; b < worldPose.bones.size(); ++b)
  {
    const Points& points = worldPose.bones[b];
    if (points.rows() != from.pose.bones[b].rows())
    {
      throw InputError("bone '" + in.boneNames[b] + "' has " + std::to_string(points.rows()) +
        " points in this pose but " + std::to_string(from.pose.bones[b].rows()) +
        " in the rest pose: a bone must keep its points through the motion");
    }
    if (!AllFinite(points))
    {
      throw InputError("bone '" + in.boneNames[b] + "' has non-finite coordinates (NaN or infinity) in this pose");
    }
    pose.bones.push_back(points);
    in.frame.ToLocal(pose.bones.back());
  }
  for (size_t k = 0; k < in.active.size(); ++k)
  {
    const std::vector<Points>& lines = worldPose.lines[in.active[k]];
    if (lines.size() != in.restLines[k].size())
    {
      throw InputError("muscle '" + in.names[k] + "' has " + std::to_string(lines.size()) +
        " action lines in this pose but " + std::to_string(in.restLines[k].size()) + " in the rest pose");
    }
    pose.lines.emplace_back();
    for (size_t l = 0; l < lines.size(); ++l)
    {
      if (lines[l].rows() != in.restLines[k][l].rest.rows() || !AllFinite(lines[l]))
      {
        throw InputError("action line " + std::to_string(l) + " of muscle '" + in.names[k] + "' has " +
          std::to_string(lines[l].rows()) + " points in this pose but " +
          std::to_string(in.restLines[k][l].rest.rows()) +
          " in the rest pose, or non-finite coordinates: its points must be the same through the motion");
      }
      pose.lines.back().push_back(lines[l]);
      in.frame.ToLocal(pose.lines.back().back());
    }
  }
  return pose;
}

int MotionDeformation::FrameSteps(const MotionPose& pose) const
{
  const Internals& in = *this->In;
  const State& from = *this->Now;
  double largest = 0;
  for (size_t b = 0; b < pose.bones.size(); ++b)
  {
    largest = std::max(largest, MaximumDisplacement(from.pose.bones[b], pose.bones[b]));
  }
  double linesMove = 0;
  for (size_t k = 0; k < pose.lines.size(); ++k)
  {
    for (size_t l = 0; l < pose.lines[k].size(); ++l)
    {
      linesMove = std::max(linesMove, MaximumDisplacement(from.pose.lines[k][l], pose.lines[k][l]));
    }
  }
  if (largest == 0 && linesMove == 0)
  {
    return 0;
  }
  return from.frames == 0 && in.parameters.numberOfSteps > 0
    ? in.parameters.numberOfSteps
    : AutomaticNumberOfSteps(largest, in.parameters.maximumStepDisplacement);
}

void MotionDeformation::SettleFrame(const MotionPose& pose, int steps, State& next,
  std::vector<MuscleStepMeasures>& frameMeasures, std::vector<std::string>& warnings,
  const std::function<void(double)>& progress) const
{
  const Internals& in = *this->In;
  const State& from = *this->Now;
  const size_t count = in.muscles.size();
  const std::vector<PoseInterpolator> boneMotions =
    PoseInterpolators(from.pose.bones, pose.bones, in.parameters.interpolationMode);
  std::vector<std::vector<PoseInterpolator>> lineMotions(count);
  for (size_t k = 0; k < count; ++k)
  {
    for (size_t l = 0; l < pose.lines[k].size(); ++l)
    {
      lineMotions[k].emplace_back(from.pose.lines[k][l], pose.lines[k][l], in.parameters.interpolationMode);
    }
  }
  const SettleInput settleInput{ in.obstacles, boneMotions, lineMotions, in.restLines, in.energyPointers,
    in.restVolumes, in.fixed, in.restOverlap, in.parameters.settle };
  for (int j = 1; j <= steps; ++j)
  {
    std::vector<TriangleMesh> muscles = next.current;
    const double to = static_cast<double>(j) / steps;
    const std::vector<SettleReport> settled =
      SettleStep(settleInput, static_cast<double>(j - 1) / steps, to, muscles, next.settle, [&](double fraction) {
        if (progress)
        {
          progress((j - 1 + 0.9 * fraction) / steps);
        }
      });
    for (std::string& warning : SettleWarnings(settleInput, to, in.names, in.linesInBonesAtRest, settled, next.warned))
    {
      warnings.push_back(std::move(warning));
    }
    std::vector<StepOutcome> outcomes(count);
    for (size_t k = 0; k < count; ++k)
    {
      outcomes[k] = { settled[k].iterations, settled[k].converged, 0, settled[k].seconds };
    }
    const std::vector<std::vector<char>> outsideBones = ProvenOutsideBones(next.settle.boneClearance);
    std::vector<MuscleStepMeasures> measures =
      ResolveAndMeasure(muscles, in.muscles, in.fixed, in.restOverlap, in.sharpEdges, in.restVolumes, in.parameters,
        outcomes, next.previous, std::vector<MuscleStepMeasures>(count), &outsideBones);
    // The frame's measures: the last step's, with the iterations and seconds of all its steps
    // and the largest step static shift.
    for (size_t k = 0; k < count; ++k)
    {
      const int iterations = frameMeasures[k].stepIterations + measures[k].stepIterations;
      const double seconds = frameMeasures[k].deformationSeconds + measures[k].deformationSeconds;
      const double stepShift = std::max(frameMeasures[k].stepStaticShift, measures[k].stepStaticShift);
      frameMeasures[k] = measures[k];
      frameMeasures[k].stepIterations = iterations;
      frameMeasures[k].deformationSeconds = seconds;
      frameMeasures[k].stepStaticShift = stepShift;
    }
    next.current = std::move(muscles);
    next.previous = std::move(measures);
    if (progress)
    {
      progress(static_cast<double>(j) / steps);
    }
  }
}

MotionFrameResult MotionDeformation::Advance(const MotionPose& worldPose, const std::function<void(double)>& progress)
{
  const auto start = Clock::now();
  const Internals& in = *this->In;
  const State& from = *this->Now;
  // The pose, checked against the rest pose and brought into the local frame; as many steps as
  // keep each bone point's move within the largest step (the first frame: the method's
  // NumberOfSteps when given).
  const MotionPose pose = this->ToLocalPose(worldPose);
  const int steps = this->FrameSteps(pose);
  auto next = std::make_shared<State>(from);
  next->pose = pose;
  ++next->frames;
  MotionFrameResult result;
  result.steps = steps;
  std::vector<MuscleStepMeasures> frameMeasures = from.previous;
  for (MuscleStepMeasures& s : frameMeasures)
  {
    s.stepIterations = 0;
    s.stepStaticShift = 0;
    s.staticallyMovedPoints = 0;
    s.deformationSeconds = 0;
    s.staticShift = Points::Zero(0, 3);
  }
  if (steps > 0)
  {
    this->SettleFrame(pose, steps, *next, frameMeasures, result.warnings, progress);
  }
  // Into the data's coordinates, one entry per muscle given.
  result.points.assign(in.muscleCount, Points(0, 3));
  result.measures.assign(in.muscleCount, MuscleStepMeasures{});
  for (size_t k = 0; k < in.muscles.size(); ++k)
  {
    result.points[in.active[k]] = next->current[k].points;
    in.frame.ToWorld(result.points[in.active[k]]);
    result.measures[in.active[k]] = frameMeasures[k];
    MeasuresToWorld(in.frame, result.measures[in.active[k]]);
  }
  result.seconds = SecondsSince(start);
  this->Now = std::move(next);
  ++this->Advanced;
  return result;
}
}
