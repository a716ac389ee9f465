// SPDX-License-Identifier: BSD-3-Clause
// Muscle paths over OpenSim's wrap objects, as OpenSim 4.x computes them: the wrap objects of a
// path tried in turn on every segment of its range, the one that lengthens the path least (or
// the first the straight path cuts through) kept, and several wrap objects iterated until the
// length settles (opensim-core's GeometryPath::applyWrapObjects, WrapCylinder::wrapLine and
// WrapSphere::wrapLine, WrapTorus::wrapLine and WrapEllipsoid::wrapLine, whose algorithms this
// follows; the code is ours).
#pragma once

#include "OpenSim/OpenSimModel.h"

#include <vector>

namespace md::osim
{
/// What wrapping one segment over one wrap object found (OpenSim's WrapAction).
enum class WrapAction
{
  NoWrap,       ///< the segment misses the object (or its active quadrant)
  InsideRadius, ///< an end of the segment is inside the object
  Wrapped,      ///< the segment wraps, but another segment may wrap with a smaller change
  Mandatory     ///< the straight segment cuts through the object: it must wrap here
};

/// A segment wrapped over a wrap object, in the object's frame.
struct WrapResult
{
  Eigen::Vector3d r1 = Eigen::Vector3d::Zero(); ///< where the path meets the surface
  Eigen::Vector3d r2 = Eigen::Vector3d::Zero(); ///< where it leaves it
  double length = 0.0;                          ///< along the surface from r1 to r2
  /// The path over the surface from r1 to r2: r1 turned about `axis` (through `centre`) by up to
  /// `turn` (radians, signed) while rising along it by up to `rise` (a helix on a cylinder, a
  /// great circle's arc on a sphere).
  Eigen::Vector3d axis = Eigen::Vector3d::UnitZ();
  Eigen::Vector3d centre = Eigen::Vector3d::Zero(); ///< a point on the axis
  double turn = 0.0, rise = 0.0;
  /// On an ellipsoid (centred at the origin) its radii, else zero: the turned point is then
  /// carried from `centre` along its direction onto the ellipsoid (a planar section's arc).
  Eigen::Vector3d radii = Eigen::Vector3d::Zero();
};

/// The segment p1-p2 (in the cylinder's frame: its axis z, centred at the origin) over a
/// cylinder of `radius` and `length` (only tangent points beyond both ends miss it), on the side
/// `quadrantSign` of axis `quadrantAxis` (sign 0: all round). The path over the surface is a
/// helix. `adjustTangents`: slide the tangent points along the axis until the lines from p1 and
/// p2 meet the helix at a tangent (within 0.1 degree), as OpenSim does for a path with several
/// wrap objects; without, the tangent points are OpenSim's first estimate, as it keeps them for a
/// path with one (where it computes lengths without drawing).
WrapAction WrapCylinderSegment(const Eigen::Vector3d& p1, const Eigen::Vector3d& p2, double radius, double length,
  int quadrantAxis, int quadrantSign, bool adjustTangents, WrapResult& result);

/// The segment p1-p2 (in the sphere's frame: centred at the origin) over a sphere of `radius`,
/// on the side `quadrantSign` of axis `quadrantAxis` (sign 0: all of it), as OpenSim computes it:
/// the tangent points in the plane through p1, p2 and the centre, the arc of the great circle
/// between them (the far way round where the quadrant asks). Where the segment runs through the
/// centre (the plane undefined) OpenSim reuses its last answer; here the plane through the
/// sphere's z axis (or x axis) is taken. OpenSim reports a far-way-round arc's length negative
/// (a sign slip); here it is the arc's length.
WrapAction WrapSphereSegment(const Eigen::Vector3d& p1, const Eigen::Vector3d& p2, double radius, int quadrantAxis,
  int quadrantSign, WrapResult& result);

/// The segment p1-p2 (in the torus's frame: its centre circle of radius `ringRadius` about z at
/// z = 0, its tube of radius `tubeRadius`) over the inside of the tube, as OpenSim computes it: a
/// cylinder of the tube's radius along the ring's tangent at the ring point nearest the segment,
/// wrapped over on the side facing the torus's centre. OpenSim finds that point by a
/// Levenberg-Marquardt search to 1e-4 from the segment's two ends; here it is found to rounding.
/// OpenSim reports every segment as wrapped, also one that misses; here one that misses does not
/// wrap.
WrapAction WrapTorusSegment(const Eigen::Vector3d& p1, const Eigen::Vector3d& p2, double ringRadius, double tubeRadius,
  int quadrantAxis, int quadrantSign, bool adjustTangents, WrapResult& result);

/// The segment p1-p2 (in the ellipsoid's frame: centred at the origin, its axes along x, y, z)
/// over an ellipsoid of `radii`, on the side `quadrantSign` of axis `quadrantAxis` (sign 0: all
/// of it), as OpenSim computes it: only a straight segment that cuts the ellipsoid wraps; the
/// wrap's plane holds p1, p2 and a point c1 of the ellipsoid found by `method` (and moved to the
/// quadrant's side); the tangent points are where the lines from p1 and p2 in that plane touch
/// the ellipsoid, on c1's side of the segment; the path between them is the plane's section,
/// the far way round where the quadrant asks. Two differences, both below OpenSim's own
/// accuracy: OpenSim finds the tangent points by a Levenberg-Marquardt search from c1 (to its
/// residual 1e-4); here they are exact (the ellipsoid's points on the polar plane of p1, or p2,
/// and in the wrap's plane). OpenSim's length is that of a polyline over the section, its points
/// about 1 mm apart (at most 500), shorter than the arc by up to micrometres on a muscle's
/// ellipsoid and stepping when its count changes; here it is the arc's, so that a moment arm by
/// difference of lengths does not step.
WrapAction WrapEllipsoidSegment(const Eigen::Vector3d& p1, const Eigen::Vector3d& p2, const Eigen::Vector3d& radii,
  int quadrantAxis, int quadrantSign, EllipsoidWrapMethod method, WrapResult& result);

/// The point of the surface path at `t` (0 at r1, 1 at r2).
Eigen::Vector3d SurfacePointAt(const WrapResult& wrap, double t);

/// Points on the surface path from r1 to r2 (both included), at most `spacing` apart.
Points SurfacePoints(const WrapResult& wrap, double spacing);

/// One point of a wrapped path (in ground): a path point, or where it meets or leaves a wrap
/// object.
struct WrappedPoint
{
  Eigen::Vector3d position = Eigen::Vector3d::Zero();
  int pathPoint = -1;         ///< index into Path::points; -1 for a wrap point
  int wrap = -1;              ///< for a wrap point: index into Path::wraps
  bool leaves = false;        ///< the second of a wrap's two points, after the surface
  double surfaceLength = 0.0; ///< on the second: the length over the surface from the first
  Points surface;             ///< on the second: the surface points from the first to it (ground)
};

/// The path through `points` (its active points in ground, in order, each with its index into
/// Path::points) wrapped over the path's wrap objects at the body poses `bodyPoses`, as OpenSim
/// does. `spacing`: the largest distance between drawn surface points (model units).
/// `openSimLength` (optional): the path's length as OpenSim reports it. Where several wrap objects
/// take more than one pass, OpenSim measures a wrap point's straight segments from where the
/// first pass put it (a cached place it does not renew), so that its length differs from the
/// returned path's own (straight between its points, over the surface between a wrap's two) by up
/// to millimetres; elsewhere the two are equal.
std::vector<WrappedPoint> WrapPath(const Model& model, const Path& path, const std::vector<Eigen::Vector3d>& points,
  const std::vector<int>& pathPoints, const std::vector<RigidTransform>& bodyPoses, double spacing,
  double* openSimLength = nullptr);
}
