// SPDX-License-Identifier: BSD-3-Clause
// How much the method's output moves when its input moves by rounding noise or
// when the hull's resolution changes (issue 13): the largest and the RMS
// distance between corresponding points of the output surfaces, per muscle, of
//   (a) the exact input against inputs moved by up to 1e-7 of each coordinate
//       (several seeds), with a scan's duplicate points kept equal and split;
//   (b) HullTargetNumberOfPoints 150, 200, 320, 400 against 250, and the
//       largest of all pairs among 200..400;
// for the one-pass method with the paper's step (N = 1, contact weight 0) and
// the interpolation method (Refit) at N = 1, 4, 8, on the phantom and, when
// present, the LHDL hip in four poses. Prints figures; asserts nothing.
//
//   BenchmarkStability [data folder] [case: all|phantom|flexion30|flexion60|adduction-40|adduction40]
//                      [seeds (3)] [methods: all|one-pass|filter|filter-surface|N (1, 4, 8)|settle|settle-N|settle-all]
#include "RealData.h"

#include "Geometry/LocalFrame.h"
#include "Geometry/MeanValueCoordinates.h"
#include "Hull/ProgressiveHull.h"
#include "Settle/SurfacePass.h"

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <string>
#include <vector>

namespace
{
struct Method
{
  std::string label;
  int steps;
  double contactWeight;
  bool settleOnSurface = false;
  /// MuscleDeformation's own computation (one pass, bones in the current pose, hull built and its
  /// mean value coordinates), on the hull or settled on the muscles' surfaces after it; not the
  /// interpolation method.
  enum class Filter
  {
    None,
    PassOnHull,
    PassOnSurface
  } filter = Filter::None;
};

/// Every step's points of every muscle (steps 1..N), or `failure` set.
struct Output
{
  std::vector<std::vector<md::Points>> points;
  std::string failure;
  double seconds = 0;
  int unsettledStep = 0; ///< with the settle: the first step whose settle did not converge, or 0
};

/// MuscleDeformation's computation at its defaults, in its local frame, as the filter runs it.
Output RunFilterPass(const MotionCase& c, const Method& method, int hullPoints)
{
  Output out;
  const auto start = std::chrono::steady_clock::now();
  try
  {
    std::vector<const md::Points*> parts;
    for (const md::MuscleMotion& m : c.muscles)
    {
      parts.push_back(&m.muscle.points);
    }
    const md::LocalFrame frame = md::LocalFrame::Around(parts);
    const size_t count = c.muscles.size();
    std::vector<md::TriangleMesh> surfaces(count), hulls(count);
    std::vector<md::WeightMatrix> weights(count);
    std::vector<md::MuscleToDeform> toDeform(count);
    md::HullParameters hull;
    hull.targetNumberOfPoints = hullPoints;
    for (size_t m = 0; m < count; ++m)
    {
      surfaces[m] = c.muscles[m].muscle;
      frame.ToLocal(surfaces[m].points);
      if (method.filter == Method::Filter::PassOnHull)
      {
        hulls[m] = md::BuildMuscleHull(surfaces[m], hull).result.hull;
        weights[m] = md::MeanValueCoordinates(hulls[m], surfaces[m].points);
      }
      toDeform[m] = { c.muscles[m].name, &surfaces[m], &hulls[m], c.muscles[m].lines, &weights[m] };
      for (md::MatchedLine& line : toDeform[m].lines)
      {
        frame.ToLocal(line.rest);
        frame.ToLocal(line.current);
      }
    }
    std::vector<std::string> names;
    std::vector<md::TriangleMesh> bones;
    for (const md::BoneMotion& b : c.bones)
    {
      names.push_back(b.name);
      bones.push_back({ b.current, b.rest.triangles });
      frame.ToLocal(bones.back().points);
    }
    const std::vector<md::Obstacle> obstacles = md::BuildObstacles(names, bones);
    std::vector<md::Points> points(count);
    if (method.filter == Method::Filter::PassOnHull)
    {
      md::DeformationParameters parameters;
      parameters.convergenceTolerance = frame.LengthToLocal(0.01); // the filter's default
      const std::vector<md::DeformationResult> passed = md::DeformMuscles(toDeform, obstacles, parameters);
      for (size_t m = 0; m < count; ++m)
      {
        points[m] = passed[m].points;
      }
    }
    else
    {
      std::vector<std::unique_ptr<md::SurfaceEnergy>> energies;
      std::vector<md::MuscleToSettle> toSettle;
      for (size_t m = 0; m < count; ++m)
      {
        const std::vector<md::MatchedLine> restLines = md::StillLines(toDeform[m].lines);
        energies.push_back(std::make_unique<md::SurfaceEnergy>(surfaces[m], restLines, md::SettleParameters{}));
        toSettle.push_back({ toDeform[m].name, &surfaces[m], toDeform[m].lines, energies.back().get() });
      }
      std::vector<md::FixedObstacle> fixed;
      for (const md::Obstacle& o : obstacles)
      {
        fixed.push_back({ o.name, o.tree.get() });
      }
      const std::vector<md::SurfacePassResult> settled = md::SettleInOnePass(toSettle, fixed, md::SettleParameters{});
      for (size_t m = 0; m < count; ++m)
      {
        points[m] = settled[m].points;
        if (!settled[m].report.converged && out.unsettledStep == 0)
        {
          out.unsettledStep = 1;
        }
      }
    }
    for (md::Points& p : points)
    {
      frame.ToWorld(p);
    }
    out.points.push_back(std::move(points));
  }
  catch (const std::exception& e)
  {
    out.failure = e.what();
  }
  out.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return out;
}

Output Run(const MotionCase& c, const Method& method, int hullPoints, md::RestMappingCache& cache)
{
  if (method.filter != Method::Filter::None)
  {
    return RunFilterPass(c, method, hullPoints);
  }
  md::InterpolationParameters parameters;
  parameters.numberOfSteps = method.steps;
  parameters.deformation.contactWeight = method.contactWeight;
  parameters.hull.targetNumberOfPoints = hullPoints;
  parameters.settleOnSurface = method.settleOnSurface;
  Output out;
  const auto start = std::chrono::steady_clock::now();
  try
  {
    md::InterpolationResult r = md::DeformByInterpolation(c.muscles, c.bones, parameters, {}, &cache);
    out.points.assign(r.points.begin() + 1, r.points.end());
    for (size_t j = 1; j < r.measures.size() && method.settleOnSurface && out.unsettledStep == 0; ++j)
    {
      for (const md::MuscleStepMeasures& measures : r.measures[j])
      {
        if (!measures.converged)
        {
          out.unsettledStep = static_cast<int>(j);
        }
      }
    }
  }
  catch (const std::exception& e)
  {
    out.failure = e.what();
  }
  out.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return out;
}

struct Distance
{
  double largest = 0;                 ///< over all muscles and points, at the last step
  double anyStep = 0;                 ///< the same over every step (a motion's frames)
  double rmsLow = 1e300, rmsHigh = 0; ///< the per-muscle RMS, min-max
  std::string worst;                  ///< the muscle of the largest
};

Distance Between(const MotionCase& c, const Output& a, const Output& b)
{
  Distance d;
  for (size_t j = 0; j < a.points.size() && j < b.points.size(); ++j)
  {
    for (size_t m = 0; m < c.muscles.size(); ++m)
    {
      d.anyStep = std::max(d.anyStep, (a.points[j][m] - b.points[j][m]).rowwise().norm().maxCoeff());
    }
  }
  for (size_t m = 0; m < c.muscles.size(); ++m)
  {
    const Eigen::VectorXd per = (a.points.back()[m] - b.points.back()[m]).rowwise().norm();
    const double rms = std::sqrt(per.squaredNorm() / static_cast<double>(per.size()));
    d.rmsLow = std::min(d.rmsLow, rms);
    d.rmsHigh = std::max(d.rmsHigh, rms);
    if (per.maxCoeff() >= d.largest)
    {
      d.largest = per.maxCoeff();
      d.worst = c.muscles[m].name;
    }
  }
  return d;
}

void Print(const std::string& method, const std::string& variation, const Output& run, const Distance* d)
{
  if (!run.failure.empty())
  {
    std::printf(
      "  %-28s %-26s FAILED (%.1f s): %s\n", method.c_str(), variation.c_str(), run.seconds, run.failure.c_str());
    return;
  }
  std::printf("  %-28s %-26s %9.4f %9.4f-%-9.4f %-18s %9.4f %5.1f", method.c_str(), variation.c_str(), d->largest,
    d->rmsLow, d->rmsHigh, d->worst.c_str(), d->anyStep, run.seconds);
  if (run.unsettledStep > 0)
  {
    std::printf("  (the settle did not converge at step %d)", run.unsettledStep);
  }
  std::printf("\n");
}

/// The spread of one kind of variation: the largest distance and the largest RMS over its runs.
struct Spread
{
  double largest = 0, rms = 0, anyStep = 0;
  int failed = 0, runs = 0;
  void Add(bool failure, const Distance& d)
  {
    ++runs;
    if (failure)
    {
      ++failed;
      return;
    }
    largest = std::max(largest, d.largest);
    rms = std::max(rms, d.rmsHigh);
    anyStep = std::max(anyStep, d.anyStep);
  }
  std::string Text() const
  {
    char text[200];
    std::snprintf(text, sizeof text,
      "largest %.4f mm, RMS up to %.4f mm (last step); largest at any step %.4f mm; %d of %d runs failed", largest, rms,
      anyStep, failed, runs);
    return text;
  }
};

void Study(const MotionCase& exact, const std::vector<Method>& methods, int seeds)
{
  std::printf("\n%s (%zu muscles, %zu bones)\n", exact.name.c_str(), exact.muscles.size(), exact.bones.size());
  std::printf("  %-28s %-26s %9s %19s %-18s %9s %5s\n", "method", "against the exact input", "largest",
    "RMS per muscle", "muscle of largest", "any step", "s");
  // Inputs with their own rest hulls, shared by every method.
  struct Input
  {
    std::string label;
    MotionCase input;
    int hullPoints;
    md::RestMappingCache cache;
  };
  std::vector<Input> inputs;
  inputs.push_back({ "exact, hull 250", exact, 250, {} });
  for (int seed = 1; seed <= seeds; ++seed)
  {
    inputs.push_back({ "1e-7, seed " + std::to_string(seed), Perturbed(exact, seed), 250, {} });
  }
  for (int seed = 1; seed <= seeds; ++seed)
  {
    inputs.push_back({ "1e-7 split dup., seed " + std::to_string(seed), Perturbed(exact, seed, true), 250, {} });
  }
  const std::vector<int> hullSizes{ 150, 200, 320, 400 };
  for (int size : hullSizes)
  {
    inputs.push_back({ "hull " + std::to_string(size), exact, size, {} });
  }
  for (const Method& method : methods)
  {
    std::vector<Output> runs;
    for (Input& in : inputs)
    {
      runs.push_back(Run(in.input, method, in.hullPoints, in.cache));
    }
    if (!runs[0].failure.empty())
    {
      Print(method.label, inputs[0].label, runs[0], nullptr);
      continue;
    }
    Distance none; // the exact run against itself
    none.rmsLow = 0;
    Print(method.label, inputs[0].label, runs[0], &none);
    Spread noise, split, hulls, hullPairs;
    for (size_t i = 1; i < inputs.size(); ++i)
    {
      const Distance d = runs[i].failure.empty() ? Between(exact, runs[0], runs[i]) : Distance{};
      Print(method.label, inputs[i].label, runs[i], &d);
      const std::string& label = inputs[i].label;
      (label.find("split") != std::string::npos     ? split
          : label.find("1e-7") != std::string::npos ? noise
                                                    : hulls)
        .Add(!runs[i].failure.empty(), d);
    }
    // Every pair among the hull sizes 200..400 (250 is the exact run).
    std::vector<const Output*> sized{ &runs[0] };
    for (size_t i = 0; i < hullSizes.size(); ++i)
    {
      if (hullSizes[i] >= 200)
      {
        sized.push_back(&runs[inputs.size() - hullSizes.size() + i]);
      }
    }
    for (size_t i = 0; i < sized.size(); ++i)
    {
      for (size_t j = i + 1; j < sized.size(); ++j)
      {
        const bool failed = !sized[i]->failure.empty() || !sized[j]->failure.empty();
        hullPairs.Add(failed, failed ? Distance{} : Between(exact, *sized[i], *sized[j]));
      }
    }
    std::printf("  %s: noise, duplicates kept: %s\n", method.label.c_str(), noise.Text().c_str());
    std::printf("  %s: noise, duplicates split: %s\n", method.label.c_str(), split.Text().c_str());
    std::printf("  %s: hull 150..400 against 250: %s\n", method.label.c_str(), hulls.Text().c_str());
    std::printf("  %s: every pair of hull 200, 250, 320, 400: %s\n", method.label.c_str(), hullPairs.Text().c_str());
  }
}
}

int main(int argc, char* argv[])
{
  const std::string folder = argc > 1 ? argv[1] : "";
  const std::string which = argc > 2 ? argv[2] : "all";
  const int seeds = argc > 3 ? std::max(1, std::atoi(argv[3])) : 3;
  const std::string methodsArg = argc > 4 ? argv[4] : "all";
  std::vector<Method> methods;
  if (methodsArg == "all" || methodsArg == "one-pass")
  {
    methods.push_back({ "one pass, paper's step", 1, 0.0 });
  }
  for (int n : { 1, 4, 8 })
  {
    if (methodsArg == "all" || methodsArg == std::to_string(n))
    {
      methods.push_back({ "interpolation N = " + std::to_string(n), n, md::StepDeformationDefaults().contactWeight });
    }
  }
  if (methodsArg == "all" || methodsArg == "filter") // MuscleDeformation itself
  {
    methods.push_back({ "MuscleDeformation, hull (paper)", 1, 0.0, false, Method::Filter::PassOnHull });
  }
  if (methodsArg == "all" || methodsArg == "filter" || methodsArg == "filter-surface")
  {
    methods.push_back({ "MuscleDeformation, muscle surface", 1, 0.0, true, Method::Filter::PassOnSurface });
  }
  // Each step solved on the muscles' surfaces (DeformationMesh Muscle surface, the default):
  // "settle" is N = 4, "settle-all" N = 1, 4 and 8, "settle-8" N = 8 alone (and so on).
  for (int n : { 1, 4, 8 })
  {
    if (methodsArg == "settle-all" || (methodsArg == "settle" && n == 4) || methodsArg == "settle-" + std::to_string(n))
    {
      methods.push_back({ "interpolation N = " + std::to_string(n) + ", settled on the full mesh", n,
        md::StepDeformationDefaults().contactWeight, true });
    }
  }
  if (methods.empty())
  {
    std::fprintf(stderr,
      "unknown methods '%s': all, one-pass, filter, filter-surface, 1, 4, 8, settle, settle-1, settle-4, settle-8 or "
      "settle-all\n",
      methodsArg.c_str());
    return 2;
  }
  std::printf("Distances (mm) between corresponding points of the last step's muscles (any step: the largest at\n"
              "any of the steps 1..N), per variation against the exact input with hull 250; Release build. 1e-7:\n"
              "every coordinate moved by up to 1e-7 of itself and rounded to float; split dup.: the same, with a\n"
              "scan's duplicate points moved apart.\n");
  if (which == "all" || which == "phantom")
  {
    Study(PhantomMotion(30), methods, seeds);
  }
  const std::map<std::string, std::pair<std::string, int>> poses{ { "flexion30", { "hip_flexion", 20 } },
    { "flexion60", { "hip_flexion", 35 } }, { "adduction-40", { "hip_adduction", 0 } },
    { "adduction40", { "hip_adduction", 40 } } };
  for (const auto& pose : poses)
  {
    if (which != "all" && which != pose.first)
    {
      continue;
    }
    MotionCase lhdl;
    if (!LhdlMotion(pose.second.first, pose.second.second, lhdl, folder))
    {
      std::printf("\nLHDL data not found: skipped (pass the data folder or set MUSCLEDEFORMATION_DATA_DIR)\n");
      return 0;
    }
    lhdl.name += " (" + pose.first + ")";
    Study(lhdl, methods, seeds);
  }
  return 0;
}
