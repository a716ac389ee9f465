// SPDX-License-Identifier: BSD-3-Clause
// The one-pass deformation (MuscleDeformation) solved on the muscles' own surfaces
// (docs/DESIGN.md section 7): every muscle settled in one step from the rest pose to the minimum
// of its full-mesh energy for the current pose, as the first step of a motion is, so that the
// answer depends continuously on the input and not at all on a hull.
#pragma once

#include "Common/MuscleFailures.h"
#include "Deformation/MuscleDeformer.h"
#include "Settle/SurfaceSettle.h"

#include <functional>
#include <string>
#include <vector>

namespace md
{
/// One muscle of a pass on its surface: its rest pose, its matched lines (rest -> current) and its
/// full-mesh energy (SurfaceEnergy of that rest pose and the lines' rest points).
struct MuscleToSettle
{
  std::string name; ///< for messages
  const TriangleMesh* muscle = nullptr;
  std::vector<MatchedLine> lines;
  const SurfaceEnergy* energy = nullptr;
};

struct SurfacePassResult
{
  Points points; ///< every point of the muscle (its unwelded twins placed with CarryToUnwelded)
  SettleReport report;
  double volumeChangePercent = 0;
  std::int64_t flippedTriangles = 0;
  std::vector<std::string> warnings;
};

/// Settles `muscles` together in one step from the rest pose to the current pose of their lines:
/// each is held outside every one of `obstacles` (in the current pose; their rest pose is not
/// known, so overlap a scan has with them at rest is pushed out too, as IntersectionResolve
/// would) and outside the other muscles, except where it overlaps them at rest, and keeps its
/// rest volume. A one-pass cannot know which way the bones went: where the motion takes a bone
/// through a muscle, the muscle goes out of it the nearest way, and a large motion (LHDL flexion
/// 60 degrees, adduction -40) can still end on either side of a bone under rounding noise; the
/// interpolation method (DeformByInterpolation) follows the bones step by step instead.
/// `progress` as SettleMuscles'.
std::vector<SurfacePassResult> SettleInOnePass(const std::vector<MuscleToSettle>& muscles,
  const std::vector<FixedObstacle>& obstacles, const SettleParameters& parameters,
  const std::function<void(double)>& progress = {});

/// SettleInOnePass of the muscles whose `failures` entry is empty, as DeformMusclesThatCan: a
/// muscle whose settle fails on its own account gets the message in `failures` and the others
/// are settled again without it. The results of failed muscles are empty.
std::vector<SurfacePassResult> SettleInOnePassThatCan(const std::vector<MuscleToSettle>& muscles,
  const std::vector<FixedObstacle>& obstacles, const SettleParameters& parameters, std::vector<std::string>& failures,
  const std::function<void(double)>& progress = {});
}
