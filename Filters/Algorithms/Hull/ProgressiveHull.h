// SPDX-License-Identifier: BSD-3-Clause
// Coarse outer hull of a closed surface by progressive-hull edge collapse
// (Sander et al. 2000, "Silhouette clipping"; Platis & Theoharis 2003).
#pragma once

#include "Common/MeshTypes.h"
#include "Geometry/SurfaceRepair.h"

#include <functional>
#include <string>

namespace md
{
struct HullParameters
{
  int targetNumberOfPoints = 250;
  /// A collapse may not create a triangle with an angle below this (degrees),
  /// unless the triangles it replaces already had a smaller one.
  double minimumAngleDegrees = 10.0;
  /// Largest turn of a triangle's normal in one collapse (degrees).
  double maximumNormalDeviationDegrees = 90.0;
  /// Largest angle between the normals of two neighbouring triangles after a
  /// collapse (degrees); above it the surface would fold onto itself.
  double maximumFoldAngleDegrees = 150.0;
  /// Asked every few hundred collapses; when it returns true the build throws Cancelled. May be
  /// called from worker threads.
  std::function<bool()> cancelled;

  /// True when `other` builds the same hull (everything but `cancelled` equal).
  bool SameHullAs(const HullParameters& other) const
  {
    return targetNumberOfPoints == other.targetNumberOfPoints && minimumAngleDegrees == other.minimumAngleDegrees &&
      maximumNormalDeviationDegrees == other.maximumNormalDeviationDegrees &&
      maximumFoldAngleDegrees == other.maximumFoldAngleDegrees;
  }
};

struct HullResult
{
  TriangleMesh hull;
  int collapses = 0;
  int rejectedCollapses = 0;          ///< collapses refused by a quality or intersection check
  int pointsBumpedIn = 0;             ///< points to enclose that had to be made hull points first
  std::int64_t pointsLeftOutside = 0; ///< points to enclose still outside at the end (0 expected)
  bool reachedTarget = false;
};

/// Collapses edges of `surface` (closed, manifold, outward-oriented, free of
/// self-intersections: see RepairClosedSurface) until `targetNumberOfPoints`
/// remain or no collapse is allowed. Each collapse places its point by the
/// least volume added, subject to lying outside the plane of every triangle
/// around the collapsed edge (with a small pull towards the edge's middle so
/// that flat regions have one answer): every hull encloses the previous one,
/// hence the surface. Collapses are taken in order of added volume and refused
/// when they would break manifoldness, make slivers, fold the surface or make
/// it intersect itself.
///
/// `enclose` (optional): points that must end inside the hull besides the
/// surface, such as RepairReport::pointsToEnclose. Each one the
/// surface leaves out first becomes a surface point (a small fan replaces the
/// nearest triangles facing it) and decimation keeps it inside from then on.
HullResult BuildProgressiveHull(
  const TriangleMesh& surface, const HullParameters& parameters, const Points* enclose = nullptr);
}

namespace md
{
/// A muscle's hull as the filters build it: the surface repaired where safe
/// (RepairClosedSurface), then decimated, enclosing the points the repair moved too.
struct MuscleHull
{
  TriangleMesh clean; ///< the repaired surface
  RepairReport report;
  HullResult result;
  /// Volumes of the hull and of the repaired surface, measured before the points go back to the
  /// muscle's coordinates (where a muscle far from the origin loses digits).
  double hullVolume = 0;
  double cleanVolume = 0;
};
/// Repairs `muscle` and builds its hull, in the muscle's LocalFrame (all results in its own
/// coordinates). Throws InputError when the muscle cannot be repaired,
/// or when the hull is not a closed, outward-oriented manifold or leaves a muscle point outside
/// (every point is checked): a hull is never handed on unchecked.
MuscleHull BuildMuscleHull(const TriangleMesh& muscle, const HullParameters& parameters);

/// Points of `muscle` (those its triangles use) outside `hull`; points within
/// 1e-9 of the muscle's size (plus `slack`, e.g. LocalFrame::Rounding) from the hull count as
/// inside. Every point is tested.
std::int64_t CountPointsOutsideHull(const TriangleMesh& hull, const TriangleMesh& muscle, double slack = 0);

/// Checks a hull the user gives (`hullName`) as the cage of `muscle` (`muscleName`): it must be a
/// closed, outward-oriented manifold and hold every point of the muscle (CountPointsOutsideHull,
/// with `slack`), for mean value coordinates extrapolate outside it. Throws InputError naming both.
void CheckGivenHull(const TriangleMesh& hull, const std::string& hullName, const TriangleMesh& muscle,
  const std::string& muscleName, double slack);
}
