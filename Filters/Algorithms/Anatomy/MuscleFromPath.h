// SPDX-License-Identifier: BSD-3-Clause
// A muscle surface made from a musculoskeletal model's muscle: a closed tube around its path in
// the rest pose, whose belly holds the muscle's volume (PCSA x optimal fibre length).
#pragma once

#include "Common/MeshTypes.h"
#include "Common/MuscleProperties.h"
#include "Geometry/TriangleTree.h"

#include <string>
#include <vector>

namespace md
{
struct MuscleFromPathParameters
{
  /// The force a unit of physiological cross-section bears at full activation, in N per square
  /// of the path's length unit: 0.6 N/mm^2 (60 N/cm^2, the value Rajagopal et al. 2016 used to
  /// derive their model's forces from muscle volumes). PCSA = max isometric force / tension.
  double specificTension = 0.6;
  /// Points of the surface (rings around the path, each of the same number of points, and one
  /// point at each end).
  int numberOfPoints = 600;
  /// A tendon's radius as a share of the belly's: the surface keeps this radius along the
  /// tendons and at its ends, which are the muscle's attachments.
  double tendonRadiusRatio = 0.25;
  /// MusclesFromPaths: share the space between the muscles, so that they do not overlap; off,
  /// each is made as MuscleFromPath makes it alone.
  bool keepMusclesApart = true;
};

struct MuscleFromPathResult
{
  TriangleMesh surface;       ///< closed, manifold, outward
  double estimatedVolume = 0; ///< PCSA x optimal fibre length
  double volume = 0;          ///< the surface's, within 1e-6 of the estimate
  double bellyStart = 0;      ///< arc length along the path where the belly begins to widen
  double bellyEnd = 0;        ///< where it has narrowed to the tendon again
  bool bellyLimited = false;  ///< the belly's share of the path set by a limit, not the tendon
  double bellyRadius = 0;     ///< the belly's largest radius
  double tendonRadius = 0;    ///< the radius along the tendons
  /// Surface points whose radius a bone, or another muscle, held short, and the volume the
  /// surface holds as a share of the estimate (1 unless they left no room for it).
  int pointsHeldByBones = 0;
  int pointsHeldByMuscles = 0;
  double volumeKept = 1;
  std::vector<std::string> notes; ///< assumptions the input forced (a belly share clamped)
};

/// The volume of a muscle from its properties: max isometric force / `specificTension` x optimal
/// fibre length (the tension in N per square of the length's unit). Throws InputError for a
/// property unknown, not finite or not positive.
double EstimatedMuscleVolume(const MuscleProperties& muscle, double specificTension);

/// A closed tube around `path` (its points in order, the rest pose). The belly spans the part of
/// the path that is not tendon: the path's length less the tendon slack length, the tendon split
/// equally between both ends, and no less than a third (no more than nine tenths) of the path.
/// Its radius rises from the tendon's to the belly's over the belly's first and last quarter
/// (a smooth step, so the surface has no kink) and is constant between; the tube follows the
/// path smoothed over the local radius, so that a via point's corner does not fold the surface,
/// and its two ends are flat caps centred on the path's first and last points. Its radii are
/// scaled until the surface's volume is the estimate (EstimatedMuscleVolume) to 1e-6.
///
/// `bones` (outward surfaces, closed or not): each surface point stops short of the first bone
/// its ray from the tube's centre enters (by 2 % of the local radius, and never nearer the centre
/// than a tenth of it, nor so near that the path near it would leave the surface), and the others
/// widen, to three times their radius at most, to keep the
/// volume. A ray that starts inside a bone passes the triangles it leaves through, so a path
/// that runs in a bone (an attachment) keeps its tube there, and an open mesh is a one-sided
/// obstacle, met from its outer side only. Where the bones leave too little room, the volume
/// falls short and a note says by how much.
/// Throws InputError naming the problem: a path of fewer than two points, not finite or of no
/// length, a muscle property missing or out of range, parameters out of range.
MuscleFromPathResult MuscleFromPath(const Points& path, const MuscleProperties& muscle,
  const MuscleFromPathParameters& parameters, const std::vector<const TriangleTree*>& bones = {});

/// Every muscle of a model at once, as MuscleFromPath, each also kept out of the others: the
/// space is shared as a Voronoi diagram of the tubes' centre lines (a point belongs to the muscle
/// whose smoothed path is nearest), each point stops 2 % of its local radius short of its tube's
/// cell, and the rest widens to keep the volume. The cells do not overlap, so neither do the
/// surfaces' points, however each widens; each path keeps its own cell, so only paths that cross
/// make their muscles meet (unless `parameters.keepMusclesApart` is off). `failures[m]` gets
/// muscle m's InputError (its result left empty); the others go on.
std::vector<MuscleFromPathResult> MusclesFromPaths(const std::vector<Points>& paths,
  const std::vector<MuscleProperties>& muscles, const MuscleFromPathParameters& parameters,
  const std::vector<const TriangleTree*>& bones, std::vector<std::string>& failures);
}
