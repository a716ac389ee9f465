// SPDX-License-Identifier: BSD-3-Clause
// Forward kinematics of an OpenSim model: coordinates -> body poses -> muscle paths.
#pragma once

#include "OpenSim/OpenSimModel.h"

#include <string>
#include <vector>

namespace md::osim
{
/// Every coordinate at its default value, couplers applied.
std::vector<double> DefaultCoordinates(const Model& model);

/// Sets each coupled (dependent) coordinate from its independent one, in order.
void ApplyCouplers(const Model& model, std::vector<double>& coordinates);

/// The pose of every body in ground (body frame -> ground), indexed as Model::bodies.
std::vector<RigidTransform> BodyPoses(const Model& model, const std::vector<double>& coordinates);

/// A muscle path at one pose: its active points in ground, in order, with the points over the
/// wrap objects it wraps over between them.
struct PathGeometry
{
  Points points;
  /// Per point: its index into Path::points, or for a point over a wrap object -1 - the wrap's
  /// index into Path::wraps.
  std::vector<int> pointIndex;
  /// The path's length: straight between its points but over a wrap object's surface, where it
  /// is the surface path's own (OpenSim's).
  double length = 0.0;
};

/// The largest distance between the points drawn over a wrap object's surface (model units).
constexpr double kWrapPointSpacing = 0.002;

/// The active points of `path` in ground. Conditional points are active while their coordinate
/// is within their range (+-1e-5, as OpenSim); moving points evaluate their functions at their
/// coordinates clamped to the coordinates' ranges (as OpenSim).
///
/// With `conditionalFade` > 0 (radians), a conditional point of a rotational coordinate is never
/// dropped: beyond its range it fades, over that much of its coordinate, onto the straight segment
/// between the nearest points on either side that are not conditional (to where its own position
/// projects on it), and it lies there farther out. The path is then a continuous function of the
/// coordinates, where OpenSim's jumps as the point goes, and it is OpenSim's wherever the point
/// is active (docs/DESIGN.md, "Conditional path points"). Translational coordinates keep the jump.
///
/// `conditionsAt` (optional): the coordinates that decide which conditional points are active and
/// how far they have faded, in place of `coordinates`: the path at a nearby pose with the points
/// and weights of this one, as a moment arm holds them (OpenSim's, of the path as it is).
///
/// The path wraps over its wrap objects as OpenSim's does (OpenSimWrapping.h; cylinders so far).
PathGeometry PathAt(const Model& model, const Path& path, const std::vector<double>& coordinates,
  const std::vector<RigidTransform>& bodyPoses, double conditionalFade = 0.0,
  const std::vector<double>* conditionsAt = nullptr);

/// The points of `path` where `like`'s lie along `like`, by the share of the length before them:
/// `path`'s own points where the two have as many, as they do unless a wrap object's surface
/// points differ in number (a nearby pose that wraps over more or less of it, or not at all).
/// A pose's path is then a point array of the other pose's path.
Points PointsLike(const PathGeometry& path, const PathGeometry& like);

/// How far out of its range a conditional point is, along its coordinate (0 within it).
double BeyondRange(const PathPoint& point, double value);

/// Length of a polyline (sum of its segments).
double PolylineLength(const Points& points);

/// A closed triangle surface of a wrap object in its body's frame.
TriangleMesh WrapSurface(const WrapObject& wrap, int resolution = 24);
}
