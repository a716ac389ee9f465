// SPDX-License-Identifier: BSD-3-Clause
#include "Method/HullSteps.h"

#include "Common/MuscleFailures.h"
#include "Deformation/VolumeConstrainedSolver.h"
#include "Geometry/MeshChecks.h"

#include <Eigen/Cholesky>

#include <algorithm>
#include <cmath>
#include <exception>
#include <numeric>

namespace md
{
namespace
{
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
    for (size_t l = 0; l < lineMotions[m].size(); ++l)
    {
      const PoseInterpolator& line = lineMotions[m][l];
      d.lines.push_back({ line.AtStep(j - 1, steps), line.AtStep(j, steps), muscles[m].lines[l].knots });
    }
  }
  return DeformMuscles(toDeform, obstacles, pass.step, progress);
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

std::vector<StepOutcome> HullMethodStep(HullPass& pass, int j, int steps, const std::vector<MuscleMotion>& muscles,
  const MethodMotions& motions, const std::vector<TriangleMesh>& current, const std::vector<double>& restVolumes,
  const std::vector<Obstacle>& obstacles, const InterpolationParameters& parameters,
  std::vector<MuscleStepMeasures>& measures, std::vector<TriangleMesh>& next, std::vector<DeformationResult>& deformed,
  std::set<std::string>& warned, std::vector<std::string>& warnings, const std::function<void(double)>& progress)
{
  const size_t count = muscles.size();
#pragma omp parallel for schedule(dynamic, 1)
  for (int b = 0; b < static_cast<int>(obstacles.size()); ++b)
  {
    obstacles[b].tree->Refit(motions.bones[b].AtStep(j, steps));
  }
  deformed = DeformHullStep(
    pass, j, steps, muscles, motions.lines, current, restVolumes, obstacles, parameters, measures, warnings, progress);
  std::vector<StepOutcome> outcomes(count);
  for (size_t m = 0; m < count; ++m)
  {
    next[m] = { deformed[m].points, muscles[m].muscle.triangles };
    for (const std::string& warning : deformed[m].warnings)
    {
      if (warned.insert(warning).second) // said once, at the first step that has it
      {
        warnings.push_back("step " + std::to_string(j) + ": " + warning);
      }
    }
    outcomes[m] = { deformed[m].iterations, deformed[m].converged, deformed[m].verticesFrozen, deformed[m].seconds };
  }
  return outcomes;
}
}
