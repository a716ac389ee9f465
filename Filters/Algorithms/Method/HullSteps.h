// SPDX-License-Identifier: BSD-3-Clause
// The interpolation method's hull-based pass (docs/DESIGN.md section 6, HullMode): each muscle's
// hull and the mean value coordinates of its points, deformed step by step with the paper's one
// pass and refitted or rebuilt between steps. The Method stage's own; InterpolatedDeformation.cxx
// builds on it.
#pragma once

#include "Common/Clock.h"
#include "Method/InterpolatedDeformation.h"
#include "Method/SettledSteps.h"

#include <functional>
#include <memory>
#include <set>
#include <string>
#include <vector>

namespace md
{
/// How the bones and every muscle's matched action lines move from the rest pose to the current
/// pose (their construction checks the pairs).
struct MethodMotions
{
  std::vector<PoseInterpolator> bones;
  std::vector<std::vector<PoseInterpolator>> lines; ///< per muscle
};

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
  RestMappingCache* kept, std::vector<double>& seconds, const std::function<void(double)>& report);

/// After a step's static resolution and volume: each hull brought to the muscle it now maps
/// (refitted, or the deformed hull with Rebuild) and the rest kept as relaxed detail.
void RefitHulls(HullPass& pass, const std::vector<TriangleMesh>& resolved,
  const std::vector<DeformationResult>& deformed, const std::vector<MuscleMotion>& muscles,
  const InterpolationParameters& parameters, std::vector<MuscleStepMeasures>& measures);

/// Step j of `steps` solved on the hulls (DeformHullStep), the bones' trees refitted to its
/// pose first: `next` gets the deformed muscles, `deformed` the pass's results; what to warn of
/// is added to `warnings` (each once: `warned`).
std::vector<StepOutcome> HullMethodStep(HullPass& pass, int j, int steps, const std::vector<MuscleMotion>& muscles,
  const MethodMotions& motions, const std::vector<TriangleMesh>& current, const std::vector<double>& restVolumes,
  const std::vector<Obstacle>& obstacles, const InterpolationParameters& parameters,
  std::vector<MuscleStepMeasures>& measures, std::vector<TriangleMesh>& next, std::vector<DeformationResult>& deformed,
  std::set<std::string>& warned, std::vector<std::string>& warnings, const std::function<void(double)>& progress);
}
