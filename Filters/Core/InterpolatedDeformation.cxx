// SPDX-License-Identifier: BSD-3-Clause
#include "InterpolatedDeformation.h"

#include "MeshChecks.h"
#include "MuscleFailures.h"
#include "VolumeConstrainedSolver.h"

#include <Eigen/Cholesky>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <exception>
#include <memory>
#include <numeric>
#include <set>

namespace md
{
namespace
{
using Clock = std::chrono::steady_clock;

double SecondsSince(Clock::time_point start)
{
  return std::chrono::duration<double>(Clock::now() - start).count();
}

/// The hulls of the muscles with their points at `points[m]` (the muscles'
/// triangles), built in parallel, the largest muscle first so that the cores
/// finish together; with `wanted`, only those of the muscles it marks (the others are left
/// empty). A hull that cannot be built is left empty and its muscle
/// gets the message in `errors`; `seconds` receives each build's time.
std::vector<TriangleMesh> BuildHulls(const std::vector<MuscleMotion>& muscles, const std::vector<const Points*>& points,
  const HullParameters& parameters, std::vector<std::string>& errors, std::vector<double>& seconds,
  const std::vector<char>* wanted = nullptr)
{
  const size_t count = muscles.size();
  std::vector<size_t> order;
  for (size_t m = 0; m < count; ++m)
  {
    if (!wanted || (*wanted)[m])
    {
      order.push_back(m);
    }
  }
  std::stable_sort(order.begin(), order.end(),
    [&](size_t a, size_t b) { return muscles[a].muscle.triangles.rows() > muscles[b].muscle.triangles.rows(); });
  std::vector<TriangleMesh> hulls(count);
  errors.assign(count, std::string());
  seconds.assign(count, 0.0);
  std::vector<std::exception_ptr> failed(count); // no exception may leave a parallel region
#pragma omp parallel for schedule(dynamic, 1)
  for (int k = 0; k < static_cast<int>(order.size()); ++k)
  {
    const size_t m = order[k];
    const auto start = Clock::now();
    try
    {
      hulls[m] = BuildMuscleHull(TriangleMesh{ *points[m], muscles[m].muscle.triangles }, parameters).result.hull;
    }
    catch (const InputError& e)
    {
      errors[m] = "muscle '" + muscles[m].name + "': " + e.what();
    }
    catch (...)
    {
      failed[m] = std::current_exception(); // Cancelled, or out of memory: thrown again below
    }
    seconds[m] = SecondsSince(start);
  }
  for (const std::exception_ptr& failure : failed)
  {
    if (failure)
    {
      std::rethrow_exception(failure);
    }
  }
  return hulls;
}

/// Smooths the per-point detail (a few halfway steps to the mean of the
/// neighbours): the sharp rims of earlier steps' bone prints fade, as in
/// elastic tissue once the bone has moved on; where the bone still is, the
/// next static resolution makes the print again, a short way.
void RelaxDetail(const Triangles& triangles, int iterations, Points& detail)
{
  const Eigen::Index n = detail.rows();
  const std::vector<std::vector<std::int64_t>> neighbours = PointNeighbours(triangles, n);
  for (int k = 0; k < iterations; ++k)
  {
    Points relaxed = detail;
    for (Eigen::Index i = 0; i < n; ++i)
    {
      if (neighbours[i].empty())
      {
        continue;
      }
      Eigen::RowVector3d sum = Eigen::RowVector3d::Zero();
      for (std::int64_t j : neighbours[i])
      {
        sum += detail.row(j);
      }
      relaxed.row(i) = 0.5 * detail.row(i) + (0.5 / static_cast<double>(neighbours[i].size())) * sum;
    }
    detail = std::move(relaxed);
  }
}

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

struct HullRefitter::Factorisation
{
  Eigen::LDLT<Eigen::MatrixXd> ldlt;
};

HullRefitter::HullRefitter(const WeightMatrix& weights, const TriangleMesh& restHull, double regularisation)
  : Weights(weights)
{
  Eigen::MatrixXd normal = Eigen::MatrixXd::Zero(weights.cols(), weights.cols());
  normal.selfadjointView<Eigen::Lower>().rankUpdate(weights.transpose());
  normal = normal.selfadjointView<Eigen::Lower>();
  const Eigen::MatrixXd laplacian = Eigen::MatrixXd(CotangentLaplacian(restHull));
  const Eigen::MatrixXd shape = laplacian.transpose() * laplacian;
  // Both terms pull towards the guess: the Laplacian one keeps the shape, the
  // identity one holds the hull points the mesh hardly depends on (small
  // columns of W), which the fit alone would send far away.
  const double scale = regularisation * normal.trace();
  this->Regulariser = (scale / std::max(shape.trace(), 1e-300)) * shape;
  this->Regulariser.diagonal().array() += scale / static_cast<double>(normal.rows());
  auto solver = std::make_shared<Factorisation>();
  solver->ldlt.compute(normal + this->Regulariser);
  this->Solver = solver;
}

Points HullRefitter::Fit(const Points& mesh, const Points& guess) const
{
  const Eigen::MatrixXd right = this->Weights.transpose() * mesh + this->Regulariser * guess;
  return this->Solver->ldlt.solve(right);
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
/// The hull-based pass through a motion (the paper's deformation, HullMode): each muscle's hull,
/// the mean value coordinates of its points in it, and the per-point detail the hull does not carry.
struct HullPass
{
  std::vector<TriangleMesh> hulls;
  std::vector<const WeightMatrix*> weights;
  std::vector<WeightMatrix> rebuiltWeights;
  std::vector<std::unique_ptr<HullRefitter>> refitters; ///< HullMode::Refit's
  std::vector<Points> details;
  std::vector<std::vector<std::vector<char>>> boneOverlap; ///< [muscle][bone][point]: rest-pose overlap
  DeformationParameters step;
};

/// The rest-pose hulls (the muscles in parallel) and mappings (each in parallel inside), or those
/// an earlier run left in `kept` where they still hold; their time is added to `seconds[m]`.
HullPass PrepareHullPass(const std::vector<MuscleMotion>& muscles, const InterpolationParameters& parameters,
  RestMappingCache* kept, std::vector<double>& seconds, const std::function<void(double)>& report)
{
  const size_t count = muscles.size();
  RestMappingCache scratch;
  RestMappingCache& rest = kept ? *kept : scratch;
  rest.muscles.resize(count);
  std::vector<const Points*> restPointers(count);
  std::vector<char> build(count, 0);
  for (size_t m = 0; m < count; ++m)
  {
    const RestMappingCache::Entry& entry = rest.muscles[m];
    restPointers[m] = &muscles[m].muscle.points;
    build[m] = entry.weights.size() == 0 || !SameMesh(entry.surface, muscles[m].muscle) ||
      !entry.hull.SameHullAs(parameters.hull);
  }
  std::vector<std::string> errors;
  std::vector<TriangleMesh> built = BuildHulls(muscles, restPointers, parameters.hull, errors, seconds, &build);
  auto forgetHull = [](RestMappingCache::Entry& entry) { // the energy, if any, stays
    entry.surface = {};
    entry.hull = {};
    entry.restHull = {};
    entry.weights = {};
  };
  for (size_t m = 0; m < count; ++m)
  {
    RestMappingCache::Entry& entry = rest.muscles[m];
    if (build[m])
    {
      forgetHull(entry);
    }
    if (build[m] && errors[m].empty())
    {
      const auto mappingStart = Clock::now();
      entry.surface = muscles[m].muscle;
      entry.hull = parameters.hull;
      entry.hull.cancelled = nullptr;
      entry.restHull = std::move(built[m]);
      try
      {
        entry.weights = MeanValueCoordinates(entry.restHull, muscles[m].muscle.points);
      }
      catch (const InputError& e)
      {
        errors[m] = "muscle '" + muscles[m].name + "': " + e.what();
        forgetHull(entry);
        continue;
      }
      ++rest.hullBuildCount;
      seconds[m] += SecondsSince(mappingStart);
    }
    report(0.15 * (m + 1) / count);
  }
  for (size_t m = 0; m < count; ++m)
  {
    if (!errors[m].empty())
    {
      throw OfMuscle(InputError(errors[m]), m);
    }
  }
  // Rebuild replaces hulls and weights; Refit moves only the hull's points.
  HullPass pass;
  pass.hulls.resize(count);
  pass.weights.resize(count);
  pass.rebuiltWeights.resize(count);
  pass.refitters.resize(count);
  pass.details.resize(count);
  for (size_t m = 0; m < count; ++m)
  {
    const auto mappingStart = Clock::now();
    pass.hulls[m] = rest.muscles[m].restHull;
    pass.weights[m] = &rest.muscles[m].weights;
    pass.details[m] = muscles[m].muscle.points - *pass.weights[m] * pass.hulls[m].points;
    if (parameters.hullMode == HullMode::Refit)
    {
      pass.refitters[m] =
        std::make_unique<HullRefitter>(*pass.weights[m], pass.hulls[m], parameters.refitRegularisation);
    }
    seconds[m] += SecondsSince(mappingStart);
    report(0.15 + 0.05 * (m + 1) / count);
  }
  pass.step = parameters.deformation;
  pass.step.measureSamplesInside = false; // not part of the method's measures
  return pass;
}

/// Step j of the hull-based pass: with HullMode::Rebuild a new hull and mapping of each muscle as
/// it is now (the paper), then the muscles deformed together from `current`.
std::vector<DeformationResult> DeformHullStep(HullPass& pass, int j, int steps,
  const std::vector<MuscleMotion>& muscles, const std::vector<std::vector<PoseInterpolator>>& lineMotions,
  const std::vector<TriangleMesh>& current, const std::vector<double>& restVolumes,
  const std::vector<Obstacle>& obstacles, const InterpolationParameters& parameters,
  std::vector<MuscleStepMeasures>& measures, std::vector<std::string>& warnings,
  const std::function<void(double)>& progress)
{
  const size_t count = muscles.size();
  if (parameters.hullMode == HullMode::Rebuild && j > 1)
  {
    std::vector<const Points*> currentPointers(count);
    for (size_t m = 0; m < count; ++m)
    {
      currentPointers[m] = &current[m].points;
    }
    std::vector<std::string> failures;
    std::vector<double> seconds;
    std::vector<TriangleMesh> rebuilt = BuildHulls(muscles, currentPointers, parameters.hull, failures, seconds);
    for (size_t m = 0; m < count; ++m)
    {
      const auto mappingStart = Clock::now();
      if (failures[m].empty() && !CheckEdges(rebuilt[m].triangles).IsClosedOrientedManifold())
      {
        failures[m] = "the rebuilt hull is not a closed manifold surface";
      }
      if (failures[m].empty())
      {
        pass.hulls[m] = std::move(rebuilt[m]);
        pass.rebuiltWeights[m] = MeanValueCoordinates(pass.hulls[m], current[m].points);
        pass.weights[m] = &pass.rebuiltWeights[m];
        pass.details[m] = current[m].points - *pass.weights[m] * pass.hulls[m].points;
      }
      else
      {
        warnings.push_back("step " + std::to_string(j) + ": the hull of muscle '" + muscles[m].name +
          "' could not be rebuilt (" + failures[m] + "); the previous step's hull is kept");
      }
      measures[m].hullSeconds = seconds[m] + SecondsSince(mappingStart);
    }
  }
  std::vector<MuscleToDeform> toDeform(count);
  for (size_t m = 0; m < count; ++m)
  {
    MuscleToDeform& d = toDeform[m];
    d.name = muscles[m].name;
    d.muscle = &current[m];
    d.hull = &pass.hulls[m];
    d.weights = pass.weights[m];
    d.detail = &pass.details[m];
    d.targetVolume = restVolumes[m];
    d.reference = &muscles[m].muscle.points; // folds an earlier step left are undone too
    d.boneOverlap = &pass.boneOverlap[m];
    for (const PoseInterpolator& line : lineMotions[m])
    {
      d.lines.push_back({ line.AtStep(j - 1, steps), line.AtStep(j, steps) });
    }
  }
  return DeformMuscles(toDeform, obstacles, pass.step, progress);
}

/// After a step's static resolution and volume: each hull brought to the muscle it now maps
/// (refitted, or the deformed hull with Rebuild) and the rest kept as relaxed detail.
void RefitHulls(HullPass& pass, const std::vector<TriangleMesh>& resolved,
  const std::vector<DeformationResult>& deformed, const std::vector<MuscleMotion>& muscles,
  const InterpolationParameters& parameters, std::vector<MuscleStepMeasures>& measures)
{
  for (size_t m = 0; m < resolved.size(); ++m)
  {
    const auto hullStart = Clock::now();
    pass.hulls[m].points = parameters.hullMode == HullMode::Refit
      ? pass.refitters[m]->Fit(resolved[m].points, deformed[m].hullPoints)
      : deformed[m].hullPoints;
    pass.details[m] = resolved[m].points - *pass.weights[m] * pass.hulls[m].points;
    RelaxDetail(muscles[m].muscle.triangles, parameters.detailRelaxation, pass.details[m]);
    measures[m].hullSeconds += SecondsSince(hullStart);
  }
}

/// The full-mesh energy of every muscle in the rest pose (SurfaceEnergy), or the one an earlier
/// run left in `kept` where it still holds; those to build are built in parallel. `restLines[m]`
/// receives each muscle's matched lines at step 0 and `seconds[m]` the time of its energy.
std::vector<std::shared_ptr<const SurfaceEnergy>> BuildEnergies(const std::vector<MuscleMotion>& muscles,
  const std::vector<std::vector<PoseInterpolator>>& lineMotions, int steps, const SettleParameters& parameters,
  RestMappingCache* kept, std::vector<std::vector<Points>>& restLines, std::vector<double>& seconds,
  const std::function<void(double)>& report)
{
  const size_t count = muscles.size();
  RestMappingCache scratch;
  RestMappingCache& rest = kept ? *kept : scratch;
  rest.muscles.resize(count);
  std::vector<std::shared_ptr<const SurfaceEnergy>> energies(count);
  std::vector<std::exception_ptr> failed(count); // no exception may leave a parallel region
  for (size_t m = 0; m < count; ++m)
  {
    for (const PoseInterpolator& line : lineMotions[m])
    {
      restLines[m].push_back(line.AtStep(0, steps));
    }
    const KeptSurfaceEnergy& entry = rest.muscles[m].surfaceEnergy;
    if (entry.Holds(muscles[m].muscle, restLines[m], parameters))
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
      energies[m] = std::make_shared<const SurfaceEnergy>(muscles[m].muscle, restLines[m], parameters);
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
      entry.Keep(energies[m], muscles[m].muscle, restLines[m], parameters);
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
  report(0.2);
  return energies;
}

/// How many times a settle that does not converge is halved (into 2, then 4 parts): the last
/// resort after SettleParts. The phantom at 50 degrees in 16 steps swung without end at one
/// step (10 flipped triangles); halved, every step settles and none turns over.
constexpr int kSettleHalvings = 2;

/// What the settles of a motion share, step to step: the motions of the bones (whose trees
/// `obstacles` are refitted to each pose settled to; `fixed` views them) and of the matched
/// lines, the energies and what the muscles must hold.
struct SettleInput
{
  const std::vector<Obstacle>& obstacles;
  const std::vector<PoseInterpolator>& boneMotions;
  const std::vector<std::vector<PoseInterpolator>>& lineMotions;
  const std::vector<std::vector<Points>>& restLines;
  const std::vector<const SurfaceEnergy*>& energies;
  const std::vector<double>& volumes;
  const std::vector<FixedObstacle>& fixed;
  const OverlapMasks& restOverlap;
  const SettleParameters& parameters;
};

/// The muscles' matched lines from the rest pose to the pose at `fraction` of the motion.
std::vector<std::vector<MatchedLine>> LinesAt(const SettleInput& in, double fraction)
{
  std::vector<std::vector<MatchedLine>> lines(in.lineMotions.size());
  for (size_t m = 0; m < lines.size(); ++m)
  {
    for (size_t l = 0; l < in.lineMotions[m].size(); ++l)
    {
      lines[m].push_back({ in.restLines[m][l], in.lineMotions[m][l].AtFraction(fraction) });
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
  for (size_t m = 0; m < reports.size(); ++m)
  {
    halves[m].iterations += reports[m].iterations; // the attempt that did not converge
    halves[m].seconds += reports[m].seconds;
  }
  return halves;
}

/// Settles the muscles from where `motion` is (the pose at fraction `from` of the motion) to
/// the pose at `to`, in as many equal parts as SettleParts asks (each by SettleToPose): the
/// number of parts depends on how far the muscles' minimum moves, continuously in the input,
/// where SettleToPose's halving depends on whether a settle converged. A step of one part is
/// settled as it was before either, to the bit.
std::vector<SettleReport> SettleStep(const SettleInput& in, double from, double to, std::vector<TriangleMesh>& muscles,
  SettleMotion& motion, const std::function<void(double)>& progress)
{
  RefitBones(in, to);
  std::vector<Points> freeMinima = FreeMinima(in.energies, LinesAt(in, to), in.fixed);
  const int parts = SettleParts(motion, in.energies, freeMinima, in.parameters);
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
  InterpolationResult result;
  const int steps = ResolveNumberOfSteps(bones, parameters);
  result.numberOfSteps = steps;
  std::vector<Points> restPoints;
  for (const MuscleMotion& m : muscles)
  {
    restPoints.push_back(m.muscle.points);
  }
  result.points.assign(1, restPoints);
  result.measures.assign(1, std::vector<MuscleStepMeasures>(count));
  result.stepSeconds.assign(1, 0.0);
  result.restHullSeconds.assign(count, 0.0);

  if (LargestMotion(muscles, bones) == 0)
  {
    // Nothing moves: every step is the rest pose, exactly.
    result.zeroMotion = true;
    result.warnings.push_back("the motion has zero length (the current pose equals the rest pose): "
                              "the muscles are returned as they are");
    for (int j = 1; j <= steps; ++j)
    {
      result.points.push_back(restPoints);
      result.measures.push_back(result.measures[0]);
      result.stepSeconds.push_back(0.0);
    }
    result.totalSeconds = SecondsSince(start);
    report(1.0);
    return result;
  }

  // Interpolators of the bones and of every matched action line (their
  // construction checks the pairs).
  std::vector<PoseInterpolator> boneMotions;
  std::vector<std::string> boneNames;
  for (const BoneMotion& b : bones)
  {
    boneMotions.emplace_back(b.rest.points, b.current, parameters.interpolationMode);
    boneNames.push_back(b.name);
  }
  std::vector<std::vector<PoseInterpolator>> lineMotions(count);
  for (size_t m = 0; m < count; ++m)
  {
    for (const MatchedLine& line : muscles[m].lines)
    {
      try
      {
        lineMotions[m].emplace_back(line.rest, line.current, parameters.interpolationMode);
      }
      catch (Error& e)
      {
        throw OfMuscle(InputError(std::string("an action line of muscle '") + muscles[m].name + "': " + e.what()), m);
      }
    }
  }

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
  const std::vector<Obstacle> obstacles = BuildObstacles(boneNames, [&] {
    std::vector<TriangleMesh> meshes;
    for (const BoneMotion& b : bones)
    {
      meshes.push_back(b.rest);
    }
    return meshes;
  }());
  std::vector<FixedObstacle> fixed;
  for (const Obstacle& o : obstacles)
  {
    fixed.push_back({ o.name, o.tree.get() });
  }
  std::vector<TriangleMesh> current(count);
  for (size_t m = 0; m < count; ++m)
  {
    current[m] = muscles[m].muscle;
  }
  const OverlapMasks restOverlap = FindOverlaps(current, fixed);

  // The full-mesh energies (rest pose only), kept for every step; each step's settle goes on
  // from the last one's answer (from the rest pose at the first), so the answer depends
  // continuously on the input and not at all on a hull (docs/DESIGN.md section 7).
  std::vector<std::shared_ptr<const SurfaceEnergy>> energies;
  std::vector<const SurfaceEnergy*> energyPointers;
  std::vector<std::vector<Points>> restLines(count); // the matched lines at step 0
  SettleMotion settleMotion;
  LineSamplesInside linesInBonesAtRest; // the scans' own overlap
  std::vector<std::string> names;
  for (const MuscleMotion& m : muscles)
  {
    names.push_back(m.name);
  }
  if (settle)
  {
    energies =
      BuildEnergies(muscles, lineMotions, steps, parameters.settle, kept, restLines, result.restHullSeconds, report);
    for (size_t m = 0; m < count; ++m)
    {
      energyPointers.push_back(energies[m].get());
      if (energies[m]->PointsNoLineDrives() > 0)
      {
        result.warnings.push_back(PartApartWarning(
          muscles[m].name, energies[m]->PointsNoLineDrives(), energies[m]->PointsUsed(), "its surface"));
      }
    }
    settleMotion = StartMotion(current, energyPointers, restLines, fixed);
    std::vector<std::vector<MatchedLine>> still;
    for (const std::vector<Points>& lines : restLines)
    {
      still.push_back(StillLines(lines));
    }
    linesInBonesAtRest = LineSamplesInBones(still, fixed, parameters.settle.samplesPerSegment);
  }
  else
  {
    // Contact rows leave the rest pose's overlap with each bone alone.
    hullPass.boneOverlap.resize(count);
    for (size_t m = 0; m < count; ++m)
    {
      hullPass.boneOverlap[m].assign(
        restOverlap[m].begin(), restOverlap[m].begin() + static_cast<std::ptrdiff_t>(bones.size()));
    }
  }
  double stepStart = 0.2;
  const double stepShare = 0.8 / steps;
  std::vector<MuscleStepMeasures> previous(count);
  std::set<std::string> warned;
  for (int j = 1; j <= steps; ++j)
  {
    const auto stepClock = Clock::now();
    if (!settle) // the settle refits them to each pose it settles to
    {
#pragma omp parallel for schedule(dynamic, 1)
      for (int b = 0; b < static_cast<int>(bones.size()); ++b)
      {
        obstacles[b].tree->Refit(boneMotions[b].AtStep(j, steps));
      }
    }

    std::vector<MuscleStepMeasures> measures(count);
    std::vector<TriangleMesh> next(count);
    std::vector<DeformationResult> deformed(count); // the hull-based pass's
    std::vector<SettleReport> settled(count);
    if (settle)
    {
      for (size_t m = 0; m < count; ++m)
      {
        next[m].triangles = muscles[m].muscle.triangles; // the points come from settleMotion
        next[m].points = current[m].points;
      }
      const SettleInput in{ obstacles, boneMotions, lineMotions, restLines, energyPointers, restVolumes, fixed,
        restOverlap, parameters.settle };
      const double to = static_cast<double>(j) / steps; // AtStep(j, steps)'s fraction
      settled = SettleStep(in, static_cast<double>(j - 1) / steps, to, next, settleMotion,
        [&](double fraction) { report(stepStart + 0.9 * stepShare * fraction); });
      const std::vector<std::vector<MatchedLine>> wholeMotion = LinesAt(in, to); // rest pose -> this step
      std::vector<std::string> said =
        LinesThroughBones(names, wholeMotion, fixed, &linesInBonesAtRest, parameters.settle.samplesPerSegment);
      if (std::any_of(settled.begin(), settled.end(), [](const SettleReport& r) { return !r.converged; }))
      {
        said.push_back("the muscles did not settle within " + std::to_string(parameters.settle.maximumIterations) +
          " iterations, not even with the step split into " + std::to_string(1 << kSettleHalvings) +
          " (the last iterate is kept, with Converged 0): another NumberOfSteps may settle them");
      }
      for (const std::string& warning : said)
      {
        if (warned.insert(warning).second) // said once, at the first step that has it
        {
          result.warnings.push_back("step " + std::to_string(j) + ": " + warning);
        }
      }
    }
    else
    {
      deformed = DeformHullStep(hullPass, j, steps, muscles, lineMotions, current, restVolumes, obstacles, parameters,
        measures, result.warnings, [&](double fraction) { report(stepStart + 0.9 * stepShare * fraction); });
      for (size_t m = 0; m < count; ++m)
      {
        next[m] = { deformed[m].points, muscles[m].muscle.triangles };
        for (const std::string& warning : deformed[m].warnings)
        {
          if (warned.insert(warning).second) // said once, at the first step that has it
          {
            result.warnings.push_back("step " + std::to_string(j) + ": " + warning);
          }
        }
      }
    }
    StaticResolveResult resolved = ResolveStaticIntersections(next, fixed, &restOverlap, parameters.staticResolve);
    // The volume is given back over the whole surface, except at the overlap
    // the rest pose has (which stays where it is); a point against an obstacle
    // cannot move outwards through it anyway.
    std::vector<std::vector<char>> held(count);
    for (size_t m = 0; m < count; ++m)
    {
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
    if (!settle)
    {
      RefitHulls(hullPass, next, deformed, muscles, parameters, measures);
    }
    const std::vector<Penetration> penetration = MeasureNewPenetration(next, fixed, &restOverlap);

    std::vector<Points> stepPoints(count);
    for (size_t m = 0; m < count; ++m)
    {
      MuscleStepMeasures& s = measures[m];
      const TriangleMesh& rest = muscles[m].muscle;
      s.volumeChangePercent =
        100.0 * (EnclosedVolume(next[m].points, rest.triangles) - restVolumes[m]) / restVolumes[m];
      s.newPenetrationCount = penetration[m].count;
      s.maxNewPenetrationDepth = penetration[m].maxDepth;
      s.newBonePenetrationCount = penetration[m].fixedCount;
      s.maxNewBonePenetrationDepth = penetration[m].fixedMaxDepth;
      s.stepStaticShift = resolved.reports[m].maxShift;
      s.maxStaticShift = std::max(previous[m].maxStaticShift, s.stepStaticShift);
      s.staticallyMovedPoints = resolved.reports[m].penetratingPoints;
      s.sharpEdgeCount = CountNewSharpEdges(rest.points, next[m].points, rest.triangles);
      s.flippedTriangleCount = CountFlippedTriangles(rest.points, next[m].points, rest.triangles);
      s.stepIterations = settle ? settled[m].iterations : deformed[m].iterations;
      s.iterations = previous[m].iterations + s.stepIterations;
      s.converged = previous[m].converged && (settle ? settled[m].converged : deformed[m].converged);
      s.pointsFrozenInObstacles = deformed[m].verticesFrozen;
      s.deformationSeconds = settle ? settled[m].seconds : deformed[m].seconds;
      s.staticShift = std::move(resolved.shift[m]);
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
    RestMappingCache subCache;
    subCache.hullBuildCount = cache.hullBuildCount;
    subCache.energyBuildCount = cache.energyBuildCount;
    for (size_t m : active)
    {
      subset.push_back(muscles[m]);
      subCache.muscles.push_back(std::move(cache.muscles[m]));
    }
    auto keep = [&] {
      for (size_t k = 0; k < active.size(); ++k)
      {
        cache.muscles[active[k]] = std::move(subCache.muscles[k]);
      }
      cache.hullBuildCount = subCache.hullBuildCount;
      cache.energyBuildCount = subCache.energyBuildCount;
    };
    InterpolationResult some;
    try
    {
      some = DeformEveryMuscle(subset, bones, parameters, forward, &subCache);
    }
    catch (...)
    {
      keep();
      throw;
    }
    keep();
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
      MuscleStepMeasures& s = result.measures[j][m];
      s.maxNewPenetrationDepth = frame.LengthToWorld(s.maxNewPenetrationDepth);
      s.maxNewBonePenetrationDepth = frame.LengthToWorld(s.maxNewBonePenetrationDepth);
      s.stepStaticShift = frame.LengthToWorld(s.stepStaticShift);
      s.maxStaticShift = frame.LengthToWorld(s.maxStaticShift);
      frame.VectorsToWorld(s.staticShift);
    }
  }
}
}
