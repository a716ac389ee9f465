// SPDX-License-Identifier: BSD-3-Clause
// Muscles through a whole motion (docs/DESIGN.md section 8): the frames of a motion are the
// interpolation method's steps. The first frame is reached from the rest pose in the method's
// steps; every later frame is deformed from the one before it, in as many steps as keep each
// bone point's move within InterpolationParameters::maximumStepDisplacement, with all of the
// method's parts (the settle on the muscles' surfaces with contact between the muscles and
// against the bones, the static resolution, the volume restore) and all muscles together.
//
// A frame is a small pose change, so it is cheap: the energies and their factorisations are
// the rest pose's (built once, kept in a RestMappingCache between runs), the bones' trees are
// refitted, not rebuilt, and each settle starts from the last frame's answer moved as the
// unconstrained minimum moved. Where the motion stands can be saved and resumed (a caller's
// frame cache: any frame is computed from the one before it, the same whichever order frames
// are asked for in).
#pragma once

#include "Method/InterpolatedDeformation.h"

#include <functional>
#include <memory>
#include <string>
#include <vector>

namespace md
{
/// One pose of a motion.
struct MotionPose
{
  std::vector<Points> bones;              ///< [bone]: the points of the bone's rest mesh in this pose
  std::vector<std::vector<Points>> lines; ///< [muscle][line]: the muscle's action lines, as many points as at rest
};

/// An action line of a pose (`line`) as the points of the muscle's rest line (`restLine`) go:
/// point for point when it has as many points (an OpenSim path's points are fixed on the bodies,
/// so the i-th is the same anatomical point in every pose); otherwise (a path that gained or
/// lost a point: an OpenSim conditional path point) the point at each rest point's normalised
/// arc length, the paper's matching (eq. 2) with the rest line's points kept. Every frame's line
/// then has the rest line's points. Throws InputError for fewer than two points or zero length.
Points AtRestParameters(const Points& restLine, const Points& line);

/// How smoothly points move over three frames: the largest second difference of a point's
/// position, |x_now - 2 x_old + x_older| (0 for points moving at a constant velocity). A muscle
/// that pops between frames has a second difference far above its bones' own.
double LargestSecondDifference(const Points& older, const Points& old, const Points& now);
/// The same of what drives the muscles: the largest over the bones' points and the action lines'.
/// A muscle's smoothness is measured against it (MotionSmoothness): where the input itself jumps
/// (an OpenSim conditional path point that comes or goes), the muscle may too.
double LargestSecondDifference(const MotionPose& older, const MotionPose& old, const MotionPose& now);

/// A frame of the motion, in the data's coordinates.
struct MotionFrameResult
{
  std::vector<Points> points;               ///< [muscle]; empty for a muscle that failed
  std::vector<MuscleStepMeasures> measures; ///< [muscle]: this frame's (iterations and seconds of its steps)
  int steps = 0;                            ///< steps from the last frame (0: nothing moved)
  double seconds = 0;
  std::vector<std::string> warnings; ///< new at this frame (each said once over the motion)
};

class MotionDeformation
{
public:
  struct Muscle
  {
    std::string name;
    TriangleMesh rest;                   ///< its surface in the rest pose
    std::vector<Points> restLines;       ///< its action lines in the rest pose
    std::vector<Attachment> attachments; ///< where it is attached (boneIndex: the bones' order)
    std::vector<Knots> restKnots;        ///< [line]: its own points (MatchedLine); none given: all
  };
  struct Bone
  {
    std::string name;
    TriangleMesh rest;
  };

  /// Prepares the motion from the rest pose: each muscle's energy (or the one `kept` holds from an
  /// earlier run), the bones' trees, the rest pose's overlap. A muscle that cannot be deformed
  /// (no surface or action line, no line sample inside it) is named in Failures() and the others
  /// go on without it. Throws InputError naming the bone for a bone it cannot use, and when no
  /// muscle can be deformed. Lengths in `parameters` are in data units.
  MotionDeformation(const std::vector<Muscle>& muscles, const std::vector<Bone>& bones,
    const InterpolationParameters& parameters, RestMappingCache* kept = nullptr);
  ~MotionDeformation();
  MotionDeformation(const MotionDeformation&) = delete;
  MotionDeformation& operator=(const MotionDeformation&) = delete;

  /// Per muscle: empty, or why it is left out of the motion.
  const std::vector<std::string>& Failures() const;
  /// What was said when the motion was prepared (a part of a muscle that no action line drives).
  const std::vector<std::string>& Warnings() const;
  /// Seconds spent preparing (the energies, the trees, the rest overlap).
  double PreparationSeconds() const;

  /// Deforms the muscles from the pose the motion is at (the last frame advanced to; the rest
  /// pose before the first) to `pose`. Throws InputError naming the bone, muscle or line when
  /// `pose` does not fit the rest pose (other counts of bones, lines or points; non-finite
  /// coordinates), and then the motion stays where it was. `progress` (optional) receives
  /// fractions in [0, 1]; it may throw (Cancelled), and the motion then stays where it was.
  MotionFrameResult Advance(const MotionPose& pose, const std::function<void(double)>& progress = {});
  /// Frames advanced to by this object (for callers that count their work).
  int FramesAdvanced() const { return this->Advanced; }

  /// Where the motion stands, to Resume from: the muscles, their last settle, the measures so
  /// far and the pose.
  struct State;
  std::shared_ptr<const State> Save() const;
  /// Back to a saved state (of this object); null: the rest pose, as before the first frame.
  void Resume(const std::shared_ptr<const State>& state);
  /// Memory a saved state holds, in bytes (for a caller that bounds its cache).
  static size_t StateBytes(const State& state);

private:
  struct Internals;
  /// `pose` checked against the rest pose and brought into the local frame (Advance's errors).
  MotionPose ToLocalPose(const MotionPose& pose) const;
  /// How many steps the frame to `pose` (local) is settled in: as many as keep each bone point's
  /// move within MaximumStepDisplacement (the first frame: NumberOfSteps when given); 0 where
  /// nothing moves.
  int FrameSteps(const MotionPose& pose) const;
  /// The muscles settled from where the motion stands to `pose` in `steps` steps, into `next`;
  /// `frameMeasures` gets the last step's measures with the iterations and seconds of all.
  void SettleFrame(const MotionPose& pose, int steps, State& next, std::vector<MuscleStepMeasures>& frameMeasures,
    std::vector<std::string>& warnings, const std::function<void(double)>& progress) const;
  std::unique_ptr<Internals> In;
  std::shared_ptr<const State> Now;  ///< where the motion stands
  std::shared_ptr<const State> Rest; ///< the rest pose
  int Advanced = 0;
};
}
