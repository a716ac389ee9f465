// SPDX-License-Identifier: BSD-3-Clause
// The deformation's answer on the muscle itself (docs/DESIGN.md section 7):
// the energy of the Kellnhofer & Kohout deformation (rotated Laplacian
// coordinates, action-line rows, volume) with contact, posed on every point
// of the full mesh and converged there. Through a motion each step's settle
// starts from the last step's answer (SettleMotion), not from the hull-based
// pass, so the answer does not depend on the hull's size or on the order of
// its collapses. Contact is a constraint, not a penalty: a point may not go
// inside a bone or another muscle, each linearised as a half-space at its
// nearest surface point, and the constrained minimum is found by an active set
// on the constraints' multipliers with the energy's matrix factorised once per
// muscle (for a whole motion). The interpolation method's default
// (InterpolationParameters::settleOnSurface).
#pragma once

#include "Geometry/RigidMotion.h"
#include "Intersections/StaticIntersections.h"
#include "Settle/SurfaceEnergy.h"

#include <array>
#include <functional>
#include <memory>
#include <vector>

namespace md
{
struct SettleReport
{
  int iterations = 0;
  bool converged = false;
  std::int64_t pointsInContact = 0; ///< held by a contact at the minimum
  double seconds = 0;
};

/// A motion's settles, from step to step (SettleMuscles' `motion`): where the last settle
/// ended. The next step's settle starts from those points moved by the change of the
/// unconstrained minimum between the two poses: a start that depends continuously on the input
/// and not at all on the hull, so that the minimum found does too (docs/DESIGN.md section 7).
struct SettleMotion
{
  std::vector<Points> points; ///< every muscle's points where the last settle ended
  std::vector<Points> free;   ///< the minimum of that pose without contact and volume
  /// Per muscle, its action-line samples' depths in the bones at rest
  /// (SurfaceEnergy::SampleDepthsInBones): a sample is let go only deeper than that.
  std::vector<std::vector<double>> restDepths;
  /// Whether each settle starts with the contacts that held the muscles where the last one ended
  /// (`held`) active, rather than with none: a motion's frames are small pose changes, whose
  /// contacts persist, so the active set is found in fewer iterations, and the contacts are
  /// carried along the motion rather than found anew at every frame (MotionDeformation).
  bool carryContacts = false;
  /// The contacts that held the muscles where the last settle ended (with carryContacts), each
  /// as (muscle, point, obstacle, triangle), the obstacles the bones first and then the muscles.
  std::vector<std::array<Eigen::Index, 4>> held;
  /// The bones' points in the rest pose (StartMotion's `restBones`), shared by every step's
  /// SettleMotion: what `bonePlacements` place.
  std::shared_ptr<const std::vector<Points>> boneReference;
  /// Per bone, the rigid placement of its rest points that fits it where the last settle ended
  /// (with the largest distance of its points from the placed rest points).
  std::vector<RigidFit> bonePlacements;
  /// Per muscle, for each point and bone (point * bones + bone): how much farther than the
  /// contact offset the last settle's contact search proves the point from the bone where it
  /// ended (its clearance less the last move; 0 where it proves nothing). The static resolution
  /// after it need not test the points it proves (ProvenOutsideBones), and the next settle's first
  /// contact search starts from it,
  /// less how far the point has moved since relative to the bone's placement (BoneClearancesNow):
  /// a point near a bone mostly moves with it, so most points need not be searched again at the
  /// first iteration. Empty after a settle that diverged.
  std::vector<std::vector<double>> boneClearance;
};

/// Per muscle, for each point and bone (point * bones + bone): 1 where `boneClearance`
/// (SettleMotion's) proves the point outside the bone and farther than the contact offset, what
/// the static resolution after that settle need not test (ResolveStaticIntersections'
/// `outsideFixed`).
std::vector<std::vector<char>> ProvenOutsideBones(const std::vector<std::vector<double>>& boneClearance);

/// Each bone's rest points (`reference`, SettleMotion::boneReference) placed rigidly where
/// `bones`' trees are now (FitRigidTransform); empty without a reference.
std::vector<RigidFit> PlaceBones(
  const std::shared_ptr<const std::vector<Points>>& reference, const std::vector<FixedObstacle>& bones);

/// The clearances `motion` carries (SettleMotion::boneClearance) made good for the points
/// `muscles` hold and the bones where `placements` (PlaceBones') put them now: each less how far its
/// point has moved relative to the bone, in the bone's rest frame as the two placements put
/// it, and less both placements' largest residuals (a bone not quite rigid). The distance from
/// a point to a surface changes by at most the point's move relative to it, so a point that
/// was outside a bone, and farther than the offset, by a clearance is still outside by what is
/// left. Laid out as ContactSearch's clearance, point * (bones + muscles) + obstacle (the
/// muscles' entries 0). Empty where `motion` carries none (no settle before,
/// one that diverged, no bones).
std::vector<std::vector<double>> BoneClearancesNow(
  const SettleMotion& motion, const std::vector<TriangleMesh>& muscles, const std::vector<RigidFit>& placements);

/// The start of a motion: `muscles` in the rest pose (their action lines `restLines`, StillLines,
/// the bones `restBones` in the rest pose).
SettleMotion StartMotion(const std::vector<TriangleMesh>& muscles, const std::vector<const SurfaceEnergy*>& energies,
  const std::vector<std::vector<MatchedLine>>& restLines, const std::vector<FixedObstacle>& restBones);

/// Every muscle's unconstrained minimum (no contact, no volume) of its full-mesh energy for the
/// pose `lines[m]` describe, `bones` in that pose; in parallel.
std::vector<Points> FreeMinima(const std::vector<const SurfaceEnergy*>& energies,
  const std::vector<std::vector<MatchedLine>>& lines, const std::vector<FixedObstacle>& bones);

/// How far the muscles' unconstrained minimum moves from where `motion` is to the pose whose
/// minima are `freeMinima` (FreeMinima's): the largest point move, relative to its muscle's size
/// (0 without a motion to start from).
double LargestStartMove(
  const SettleMotion& motion, const std::vector<const SurfaceEnergy*>& energies, const std::vector<Points>& freeMinima);

/// How many equal parts a motion's step whose minimum moves by `startMove` (LargestStartMove's)
/// is settled in: the fewest in which no muscle's minimum moves by more than
/// SettleParameters::largestStartMove of its size, or, where each part `carriesContacts` to the
/// next (SettleMotion::carryContacts), largestCarriedMove (at most 64).
int SettleParts(double startMove, const SettleParameters& parameters, bool carriesContacts);

/// Settles every muscle of `muscles` (their points in, the settled points out) to the minimum
/// of its full-mesh energy for the pose `lines[m]` describes, holding `volumes[m]`, none of its
/// points inside a bone (`bones`, in that pose) or another muscle: the muscles are settled
/// together, and where two are in contact each gives way as its own stiffness says. Overlap
/// the rest pose has (`restOverlap`, OverlapMasks order) is left alone. The starting points
/// decide only which side of an obstacle a point is on. `energies[m]` belong to the muscles'
/// rest poses; the settle runs on their welded surfaces and writes the other points back with
/// CarryToUnwelded. A point inside an obstacle at the start goes out the nearest way; one that
/// goes in during the settle goes back out the way it came in. A settle that does not converge
/// within SettleParameters::maximumIterations keeps its last iterate, with `converged` false;
/// one that diverges (a third iteration that moves a point by half its muscle's size) stops
/// and leaves every muscle at its starting points, also with `converged` false.
/// With `motion` (a step of a motion, StartMotion at the first), the muscles' points in are
/// not read: the settle starts where `motion` says, and `motion` is moved on to where it ends.
/// `progress` (optional) receives the share of SettleParameters::maximumIterations done after
/// each iteration; it may throw (Cancelled) to stop the settle. `freeMinima`: FreeMinima of
/// `lines` and `bones` when the caller has them already (SettleParts'); empty: found here.
std::vector<SettleReport> SettleMuscles(std::vector<TriangleMesh>& muscles,
  const std::vector<const SurfaceEnergy*>& energies, const std::vector<std::vector<MatchedLine>>& lines,
  const std::vector<double>& volumes, const std::vector<FixedObstacle>& bones, const OverlapMasks* restOverlap,
  const SettleParameters& parameters, SettleMotion* motion = nullptr, const std::function<void(double)>& progress = {},
  std::vector<Points> freeMinima = {});
}
