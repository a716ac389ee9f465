// SPDX-License-Identifier: BSD-3-Clause
// A muscle path kept out of the bones (docs/DESIGN.md, "Paths over the bones"): a taut string
// through the path's own points (origin, via points, insertion) that runs over a bone's surface
// where the straight segment would enter the bone.
//
// Each segment between two of the path's points is a string of pointsPerSegment free points. Its
// shape minimises the sum of squared chord lengths (a discrete geodesic at even spacing: where no
// bone is near, the straight segment) with every free point outside every bone by a clearance.
// The minimum is found by sequential quadratic programming: each bone is linearised at the point
// of its surface nearest each free point near it (a half-space), the quadratic problem over the
// points held on their half-space's plane is solved exactly (a small dense system), points the
// string pulls off their plane are let go, and points that came into a bone are held on the next
// round. Started from the last frame's answer, the string stays on the side of a bone it was on,
// and moves continuously with the bones and the path's points.
#pragma once

#include "Geometry/TriangleTree.h"

#include <vector>

namespace md
{
struct PathOverBonesParameters
{
  /// Free points of each segment between two of the path's own points: how finely the string
  /// follows a bone. Every pose of a path then has (n - 1) (pointsPerSegment + 1) + 1 points for
  /// n points of its own, wherever it wraps.
  int pointsPerSegment = 15;
  /// How far the string is kept off a bone's surface, as a share of the spacing of a segment's
  /// points (its straight length over pointsPerSegment + 1). A chord between two points held on a
  /// bone of radius R cuts in by about spacing^2 / (8 R): 1/8 of the spacing keeps the chords
  /// out of every bone whose curvature radius is at least the spacing.
  double clearanceShare = 0.125;
  /// Rounds of linearisation and solution per segment before giving up (the last answer is kept
  /// and Result::converged says so).
  int maximumIterations = 200;
};

struct PathOverBonesResult
{
  Points points;                 ///< the path: its own points with each segment's free points between
  double length = 0;             ///< the polyline's length
  double straightLength = 0;     ///< the length through the path's own points alone
  int iterations = 0;            ///< the most rounds a segment took
  bool converged = true;         ///< every segment settled within maximumIterations
  std::vector<int> pointsOnBone; ///< [bone]: free points held on its surface
  std::vector<int> boneOfPoint;  ///< [point]: the bone a free point is held on; -1 for none
};

/// `fixed` (at least two points) subdivided: each segment with `pointsPerSegment` evenly spaced
/// points between its ends. The layout of PathOverBones' result for a path that touches no bone.
Points SubdividedPath(const Points& fixed, int pointsPerSegment);

/// The path through `fixed` kept out of `bones` (closed surfaces, each a TriangleTree in the pose
/// of `fixed`). Where one of the path's own points lies inside a bone (an attachment on it), the
/// string may be in that bone from that point to where the straight segment first leaves it.
///
/// `start` (optional): the answer at the last frame, in SubdividedPath's layout for `fixed`'s
/// point count; the string starts from it (its free points that a bone moved into pushed out to
/// the nearest surface) and so stays on the side of each bone it was on. Without one (or with one
/// of another layout), the free points start on the straight segment, and those inside a bone
/// are lifted out on the side (of 16 around the segment) that lifts the deepest least.
///
/// Throws InputError for fewer than two points, non-finite points, or fewer than one point per
/// segment.
PathOverBonesResult PathOverBones(const Points& fixed, const std::vector<const TriangleTree*>& bones,
  const PathOverBonesParameters& parameters = {}, const Points* start = nullptr);
}
