// SPDX-License-Identifier: BSD-3-Clause
// The one deformation pass's own parts (docs/DESIGN.md section 4), shared by MuscleDeformer.cxx,
// DeformerContact.cxx (the bones' contact rows, moves that stop at obstacles) and
// DeformerFolds.cxx (folds of the full mesh undone): the state of one muscle through the pass.
// Not part of the stage's interface.
#pragma once

#include "Common/Clock.h"
#include "Deformation/MuscleDeformer.h"
#include "Deformation/VolumeConstrainedSolver.h"
#include "Geometry/TriangleTree.h"

#include <cstdint>
#include <limits>
#include <memory>
#include <vector>

namespace md
{
/// Unfold, let the volume settle, check again: at most this many times.
constexpr int maximumUnfoldings = 8;
/// A muscle whose span grows beyond this factor in the fine phase is being
/// torn apart (its volume is held): the phase stops there.
constexpr double maximumGrowth = 1.5;

/// The state of one muscle through the pass.
struct MuscleState
{
  const MuscleToDeform* input = nullptr;
  double size = 0;                       // span (box diagonal) of the muscle where the pass starts
  WeightMatrix ownWeights;               // when not given
  const WeightMatrix* weights = nullptr; // full mesh = weights * hull
  std::unique_ptr<VolumeConstrainedSolver> solver;
  Points targets;
  Points currentSamples;             // action-line samples in the current pose
  Points hull;                       // X
  Points points;                     // the full mesh as it moves (W X where nothing held it)
  Points start;                      // where the pass starts
  const Points* reference = nullptr; // the shape folds are judged against (MuscleToDeform::reference)
  double hullVolume = 0, restVolume = 0;
  std::vector<char> frozen;           // inside a bone before a step: stays
  std::vector<char> stopped;          // held at an obstacle in the last move
  std::vector<char> touched;          // held at an obstacle in any move: left out of the volume gradient, which
                                      // would otherwise swing as points come off the obstacle and back
  std::unique_ptr<TriangleTree> tree; // of `points`, for the other muscles
  // Of the full mesh's points, when the unfolding first needs them: their
  // neighbours and the triangles they are corners of.
  std::vector<std::vector<std::int64_t>> neighbours;
  std::vector<std::vector<Eigen::Index>> trianglesOf;
  double orientation = 1; // +1 when the triangles face outwards
  bool converged = false;
  bool fineDone = false;
  bool fellBack = false; // the fine phase tore the muscle apart: it keeps its coarse result
  Points fineStartPoints, fineStartHull;
  int unfoldings = 0;
  bool flipsCheckedClean = false;
  bool unfoldingBlocked = false;                          // the last unfolding left folds (pinned at a bone): no more
  double fineStep = 1;                                    // step length of the fine phase
  double lastChange = std::numeric_limits<double>::max(); // largest hull change of the last fine step
  Clock::duration time{};
  DeformationResult result;
};

/// Coarse phase: the hull alone, its own volume held, no obstacles.
void RunCoarsePhase(MuscleState& s, const DeformationParameters& parameters);

/// Contact rows (DeformationParameters::contactWeight): each point of the full
/// mesh (W X + detail) inside a bone it may not overlap gets a row pulling it
/// to that bone's nearest surface point, and the coarse phase runs again from
/// where it stopped; rounds until no new point comes in. A point keeps its row
/// and target once it has one, so that the rounds do not swing it in and out.
void PushOffBones(MuscleState& s, const std::vector<Obstacle>& bones, const DeformationParameters& parameters);

/// How many times its starting span the muscle spans now: beyond
/// maximumGrowth it is being torn apart.
double Growth(const MuscleState& s);

/// Moves every point of `s` from `points` to `candidate`, except where an
/// obstacle holds it.
void MoveWithObstacles(MuscleState& s, const Points& candidate, const std::vector<Obstacle>& bones,
  const std::vector<const MuscleState*>& others);

/// Points of `members` (not frozen) inside a bone go to its nearest surface
/// point, just outside.
void SlideOnBones(MuscleState& s, const std::vector<Obstacle>& bones, const std::vector<Eigen::Index>& members);

/// Points of `members` inside a bone, deeper than they were at `before` (or
/// not inside it then), go back to `before` and are pinned. Returns how many.
std::int64_t PinDeeperInBones(MuscleState& s, const std::vector<Obstacle>& bones,
  const std::vector<Eigen::Index>& members, const Points& before, std::vector<char>& pinned);

/// Undoes folds of the full mesh (triangles the mapping turned over, where
/// the hull deformed too unevenly for its mean value coordinates): the points
/// around the flipped triangles take back the shape their neighbourhood has
/// in the reference shape (as-rigid-as-possible: local rotations, one small
/// sparse solve with the region's border fixed), the region growing until
/// nothing is flipped. With `onBones` (bones push the muscle) the reshaping
/// keeps to the bones: a point it carries into a bone slides on the bone's
/// surface, and a point already inside one that it would carry deeper stays
/// where it was, held as part of the region's border. Returns whether any
/// point moved.
bool UnfoldFlippedTriangles(
  MuscleState& s, const std::vector<Obstacle>& bones, bool dynamicIntersections, bool onBones);
}
