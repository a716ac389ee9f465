// SPDX-License-Identifier: BSD-3-Clause
// The parts of a step that the interpolation method (InterpolatedDeformation) and a motion
// (MotionDeformation) share: the settle from one pose to the next, in parts and halves where it
// must be (docs/DESIGN.md section 7), what to warn of, and the end of every step (the static
// resolution, the volume restore and the measures). Internal to the core.
#pragma once

#include "Geometry/LocalFrame.h"
#include "Geometry/MeshChecks.h"
#include "Intersections/StaticIntersections.h"
#include "Method/InterpolatedDeformation.h"
#include "Motion/BoneInterpolation.h"
#include "Settle/SurfaceSettle.h"

#include <functional>
#include <set>
#include <string>
#include <vector>

namespace md
{
/// How many times a settle that does not converge is halved (into 2, then 4 parts): the last
/// resort after SettleParts. The phantom at 50 degrees in 16 steps swung without end at one
/// step (10 flipped triangles); halved, every step settles and none turns over.
constexpr int kSettleHalvings = 2;

/// What the settles of a motion share, step to step: the motions of the bones (whose trees
/// `obstacles` are refitted to each pose settled to; `fixed` views them) and of the matched
/// lines from one pose to the next (fraction 0 to 1), the energies and what the muscles must hold.
struct SettleInput
{
  const std::vector<Obstacle>& obstacles;
  const std::vector<PoseInterpolator>& boneMotions;
  const std::vector<std::vector<PoseInterpolator>>& lineMotions;
  const std::vector<std::vector<MatchedLine>>& restLines; ///< StillLines
  const std::vector<const SurfaceEnergy*>& energies;
  const std::vector<double>& volumes;
  const std::vector<FixedObstacle>& fixed;
  const OverlapMasks& restOverlap;
  const SettleParameters& parameters;
};

/// Marks each attachment area's points (`muscles[m].attachments`) as lying in its bone in `masks`
/// (the rest pose's overlap, OverlapMasks order): fused with the bone, they are held out of it
/// by no contact and no static resolution, nor counted as penetrating it. A point of an area
/// lies on the bone's surface, and a contact would hold it the contact offset out of it, against
/// the area's own rows: on the LHDL psoas's insertion at 40 degrees of adduction, by 1.2 mm.
void FuseAttachments(OverlapMasks& masks, const std::vector<MuscleMotion>& muscles);

/// The muscles' matched lines from the rest pose to the pose at `fraction` of the motion.
std::vector<std::vector<MatchedLine>> LinesAt(const SettleInput& in, double fraction);

/// The bones' trees refitted to the pose at `fraction` of the motion.
void RefitBones(const SettleInput& in, double fraction);

/// Settles the muscles from where `motion` is (the pose at fraction `from` of the motion) to
/// the pose at `to`, in as many equal parts as SettleParts asks, each halved (kSettleHalvings
/// times at most) while it does not converge: the number of parts depends on how far the
/// muscles' minimum moves, continuously in the input. `muscles`' points are the answer.
std::vector<SettleReport> SettleStep(const SettleInput& in, double from, double to, std::vector<TriangleMesh>& muscles,
  SettleMotion& motion, const std::function<void(double)>& progress);

/// What to say after a settle to the pose at `to`: the lines that cross a bone they did not
/// cross at rest (`linesInBonesAtRest`), and a settle that did not converge. Each once:
/// `warned` holds what was said before.
std::vector<std::string> SettleWarnings(const SettleInput& in, double to, const std::vector<std::string>& names,
  const LineSamplesInside& linesInBonesAtRest, const std::vector<SettleReport>& settled, std::set<std::string>& warned);

/// How a step's deformation went for one muscle (the settle's or the hull-based pass's).
struct StepOutcome
{
  int iterations = 0;
  bool converged = true;
  std::int64_t pointsFrozen = 0;
  double seconds = 0;
};

/// The end of every step, on `next` (the muscles as the step's deformation left them, the
/// muscles' triangles): the static resolution (the rest pose's overlap `restOverlap` left
/// alone), the volumes given back (`restVolumes`, with PreserveVolume) and the measures against
/// the rest pose (`muscles`) and the last step's (`previous`). `measures` brings what the step
/// measured already (its hull seconds) and is returned complete. `outsideBones`: the settle's
/// proof of which points are outside which bone (ProvenOutsideBones), when `next` is
/// where a settle left the muscles. `sharpEdges`: the muscles' rest edges (MuscleSharpEdges),
/// found once for every step.
std::vector<MuscleStepMeasures> ResolveAndMeasure(std::vector<TriangleMesh>& next,
  const std::vector<MuscleMotion>& muscles, const std::vector<FixedObstacle>& fixed, const OverlapMasks& restOverlap,
  const std::vector<NewSharpEdges>& sharpEdges, const std::vector<double>& restVolumes,
  const InterpolationParameters& parameters, const std::vector<StepOutcome>& outcomes,
  const std::vector<MuscleStepMeasures>& previous, std::vector<MuscleStepMeasures> measures,
  const std::vector<std::vector<char>>* outsideBones = nullptr);

/// Each muscle's NewSharpEdges at rest, found in parallel.
std::vector<NewSharpEdges> MuscleSharpEdges(const std::vector<MuscleMotion>& muscles);

/// A step's measures computed in `frame`, their lengths in world units.
void MeasuresToWorld(const LocalFrame& frame, MuscleStepMeasures& measures);

/// The full-mesh energy of every muscle in the rest pose (`restLines[m]`, its matched lines
/// there: StillLines), or the one an earlier run left in `kept` where it still holds; those to build are
/// built in parallel. `seconds[m]` receives the time of each energy. A muscle whose energy cannot
/// be built throws, marked as its own (OfMuscle).
std::vector<std::shared_ptr<const SurfaceEnergy>> BuildEnergies(const std::vector<MuscleMotion>& muscles,
  const std::vector<std::vector<MatchedLine>>& restLines, const SettleParameters& parameters, RestMappingCache* kept,
  std::vector<double>& seconds);
}
