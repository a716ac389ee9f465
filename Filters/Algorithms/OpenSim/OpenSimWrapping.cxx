// SPDX-License-Identifier: BSD-3-Clause
#include "OpenSim/OpenSimWrapping.h"
#include "OpenSim/WrapGeometry.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <optional>

namespace md::osim
{
namespace
{
using Vector = Eigen::Vector3d;

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
/// The length of the cylinder OpenSim puts along a torus's ring (model units).
constexpr double kTorusCylinderLength = 10000.0;
/// OpenSim's segment length on a wrap surface when it places tangent points (metres).
constexpr double kTangencySegment = 0.002;
/// How far a line to a tangent point may be from tangent to the helix, and how many times a
/// tangent point is slid to make it so (OpenSim's).
constexpr double kTangencyThreshold = 0.1 * M_PI / 180.0;
constexpr int kTangencyIterations = 100;
/// The change of a path's length (metres) at which OpenSim stops iterating its wrap objects, and
/// how many times it goes over them at most.
constexpr double kSettledLength = 0.0005;
constexpr int kWrapIterations = 8;

int Sign(double a)
{
  return a >= 0.0 ? 1 : -1;
}

/// The point of the line through `linePoint` along `line` (any length) nearest to `p`.
Vector ClosestOnLine(const Vector& p, const Vector& linePoint, const Vector& line)
{
  double magnitude = 0;
  const Vector toPoint = NormalizeOrZero(p - linePoint, &magnitude);
  const Vector direction = NormalizeOrZero(line);
  return linePoint + toPoint.dot(direction) * magnitude * direction;
}

double DistanceSquaredToLine(const Vector& p, const Vector& linePoint, const Vector& line)
{
  const Vector toLine = linePoint - p;
  const Vector n = line.normalized();
  return (toLine - toLine.dot(n) * n).squaredNorm();
}

/// The points of the lines p1-p2 and p3-p4 nearest each other (`near1`, `near2`) and their
/// parameters along them (`s`, `t`: 0 at p1 / p3, 1 at p2 / p4); false (parameters NaN) for
/// parallel lines.
bool NearestOnLines(const Vector& p1, const Vector& p2, const Vector& p3, const Vector& p4, Vector& near1, double& s,
  Vector& near2, double& t)
{
  double length1 = 0, length2 = 0;
  const Vector d1 = NormalizeOrZero(p2 - p1, &length1);
  const Vector d2 = NormalizeOrZero(p4 - p3, &length2);
  const Vector cross = d1.cross(d2);
  const double denominator = cross.squaredNorm();
  if (std::abs(denominator) <= 2e-13)
  {
    s = t = kNaN;
    return false;
  }
  Eigen::Matrix3d m;
  m.row(0) = (p3 - p1).transpose();
  m.row(1) = d1.transpose();
  m.row(2) = cross.transpose();
  t = m.determinant() / denominator;
  near2 = p3 + t * d2;
  m.row(1) = d2.transpose();
  s = m.determinant() / denominator;
  near1 = p1 + s * d1;
  s /= length1;
  t /= length2;
  return true;
}

/// Where the segment a-b meets the plane n . x + d = 0 (within OpenSim's 1e-5 of its ends).
bool SegmentMeetsPlane(const Vector& a, const Vector& b, const Vector& n, double d, Vector& where)
{
  constexpr double kLineEpsilon = 1e-5;
  const Vector along = b - a;
  const double dot = along.dot(n);
  if (std::abs(dot) < kLineEpsilon)
  {
    return false;
  }
  const double t = (-d - n.dot(a)) / dot;
  if (t < -kLineEpsilon || t > 1.0 + kLineEpsilon)
  {
    return false;
  }
  where = a + t * along;
  return true;
}

const Vector kAxisPoint(0.0, 0.0, -1.0);
const Vector kAxis(0.0, 0.0, 1.0);

/// Of the tangent points r1a, r1b of one end and r2a, r2b of the other, the pair whose directions
/// from their centres (c1, c2: on a cylinder's axis, or a sphere's centre) are nearest each other.
void NearestPair(const Vector& r1a, const Vector& r1b, const Vector& r2a, const Vector& r2b, const Vector& c1,
  const Vector& c2, WrapResult& result)
{
  const Vector r1am = NormalizeOrZero(r1a - c1), r1bm = NormalizeOrZero(r1b - c1), r2am = NormalizeOrZero(r2a - c2),
               r2bm = NormalizeOrZero(r2b - c2);
  const double dot1 = r1am.dot(r2am), dot2 = r1am.dot(r2bm), dot3 = r1bm.dot(r2am), dot4 = r1bm.dot(r2bm);
  const bool firstA = (dot1 > dot2 && dot1 > dot3 && dot1 > dot4) || (dot2 > dot3 && dot2 > dot4);
  const bool secondA = (dot1 > dot2 && dot1 > dot3 && dot1 > dot4) || (!firstA && dot3 > dot4);
  result.r1 = firstA ? r1a : r1b;
  result.r2 = secondA ? r2a : r2b;
}

/// Slides tangent point `r` along the axis so that the line from `p` to it meets the surface at
/// the angle the helix leaves it (towards `onHelix`, the helix's next point); false when it
/// already does to within kTangencyThreshold.
bool AdjustTangentPoint(const Vector& p, Vector& r, const Vector& onHelix)
{
  const double alpha = std::acos(NormalizeOrZero(r - p).dot(kAxis));
  const double omega = std::acos(NormalizeOrZero(onHelix - r).dot(kAxis));
  if (!(std::abs(alpha - omega) > kTangencyThreshold))
  {
    return false;
  }
  const Vector pOnAxis = ClosestOnLine(p, r, kAxis), helixOnAxis = ClosestOnLine(onHelix, r, kAxis);
  Vector near1, near2;
  double s = 0, t = 0;
  if (!NearestOnLines(p, onHelix, pOnAxis, helixOnAxis, near1, s, near2, t))
  {
    return false;
  }
  r += 1.5 * (near2 - r);
  return true;
}

/// The point at `t` (0 at r1, 1 at r2) of the helix from r1 turning by `turn` about z and rising
/// by `rise`.
Vector OnHelix(const Vector& r1, double turn, double rise, double t)
{
  const double c = std::cos(t * turn), s = std::sin(t * turn);
  return Vector(c * r1.x() - s * r1.y(), s * r1.x() + c * r1.y(), r1.z() + t * rise);
}

/// The helix over the cylinder from r1 to r2 (the long way round when `longWrap`) and its length,
/// the tangent points slid to tangency first when `adjust`.
void SpiralPath(const Vector& p1, const Vector& p2, double radius, bool longWrap, bool adjust, WrapResult& result)
{
  const double sense = longWrap ? -1.0 : 1.0;
  double theta = 0, axial = 0;
  const auto at = [&](double t) -> Vector {
    return OnHelix(result.r1, sense * theta, axial, t);
  };
  for (int iterations = 0;; ++iterations)
  {
    const Vector r1a = ClosestOnLine(result.r1, kAxisPoint, kAxis), r2a = ClosestOnLine(result.r2, kAxisPoint, kAxis);
    axial = (r2a - r1a).dot(kAxis);
    const Vector u = result.r1 - r1a, v = result.r2 - r2a;
    theta = std::atan2(u.cross(v).dot(kAxis), u.dot(v));
    if (longWrap)
    {
      theta = 2.0 * M_PI - theta;
    }
    result.length = std::hypot(radius * theta, axial);
    // OpenSim checks tangency at the helix's second point of segments kTangencySegment long.
    const int segments = std::max(1, static_cast<int>(result.length / kTangencySegment));
    if (!adjust || segments < 2 || iterations >= kTangencyIterations)
    {
      break;
    }
    const double t = 1.0 / segments;
    const bool moved1 = AdjustTangentPoint(p1, result.r1, at(t));
    const bool moved2 = AdjustTangentPoint(p2, result.r2, at(1.0 - t));
    if (!moved1 && !moved2)
    {
      break;
    }
  }
  result.axis = kAxis;
  result.turn = sense * theta;
  result.rise = axial;
}
}

Vector SurfacePointAt(const WrapResult& wrap, double t)
{
  if (wrap.radii.isZero())
  {
    return wrap.centre + Eigen::AngleAxisd(t * wrap.turn, wrap.axis) * (wrap.r1 - wrap.centre) +
      t * wrap.rise * wrap.axis;
  }
  // Along the turned direction from the centre to the ellipsoid (the quadratic's positive root);
  // r1 - centre is normal to the axis, so the turn is cos and sin.
  const Vector from = wrap.r1 - wrap.centre;
  const Vector turned = std::cos(t * wrap.turn) * from + std::sin(t * wrap.turn) * wrap.axis.cross(from);
  return wrap.centre + CrossEllipsoid(wrap.centre, turned, wrap.radii).larger * turned;
}

Points SurfacePoints(const WrapResult& wrap, double spacing)
{
  const int drawn = std::max(1, static_cast<int>(std::ceil(wrap.length / spacing)));
  Points surface(drawn + 1, 3);
  for (int i = 0; i <= drawn; ++i)
  {
    surface.row(i) = SurfacePointAt(wrap, static_cast<double>(i) / drawn).transpose();
  }
  surface.row(drawn) = wrap.r2.transpose(); // exactly where the path leaves the surface
  return surface;
}

WrapAction WrapSphereSegment(
  const Vector& p1, const Vector& p2, double radius, int quadrantAxis, int quadrantSign, WrapResult& result)
{
  result = WrapResult();
  if (p1.norm() < radius || p2.norm() < radius)
  {
    return WrapAction::InsideRadius;
  }
  // Where the segment's line meets the sphere: both crossings within the segment, in order.
  const Vector ri = p1 - p2, mp = -p2;
  const double a = ri.dot(ri), b = -2.0 * mp.dot(ri), c = mp.dot(mp) - radius * radius;
  const double disc = b * b - 4.0 * a * c;
  if (disc < 0.0)
  {
    return WrapAction::NoWrap;
  }
  const double l1 = (-b + std::sqrt(disc)) / (2.0 * a), l2 = (-b - std::sqrt(disc)) / (2.0 * a);
  if (!(0.0 < l1 && l1 < 1.0) || !(0.0 < l2 && l2 < 1.0) || l1 < l2)
  {
    return WrapAction::NoWrap;
  }
  WrapAction action = WrapAction::Wrapped;
  const Vector along = NormalizeOrZero(p1 - p2);
  Vector planeNormal = along.cross(NormalizeOrZero(p2));
  if (planeNormal.norm() < 1e-5)
  {
    // Through the centre: any plane holds the line (OpenSim reuses its last answer).
    planeNormal = along.cross(std::abs(along.z()) < 0.9 ? Vector::UnitZ() : Vector::UnitX());
  }
  const Vector n = NormalizeOrZero(planeNormal);
  // Each end's two tangent points, in the plane through the ends and the centre.
  const auto tangents = [&](const Vector& p, Vector& ta, Vector& tb) {
    const Vector y = NormalizeOrZero(-p), z = n.cross(y);
    const double half = std::asin(radius / p.norm()), reach = p.norm() * std::cos(half);
    ta = p + (std::cos(half) * y - std::sin(half) * z) * reach;
    tb = p + (std::cos(half) * y + std::sin(half) * z) * reach;
  };
  Vector r1a, r1b, r2a, r2b;
  tangents(p1, r1a, r1b);
  tangents(p2, r2a, r2b);
  const Vector r1am = NormalizeOrZero(r1a), r1bm = NormalizeOrZero(r1b), r2am = NormalizeOrZero(r2a),
               r2bm = NormalizeOrZero(r2b);
  NearestPair(r1a, r1b, r2a, r2b, Vector::Zero(), Vector::Zero(), result);
  bool farSide = false;
  if (quadrantSign != 0)
  {
    const int axis = quadrantAxis;
    const auto onSide = [&](const Vector& x) {
      return Sign(x[axis]) == quadrantSign;
    };
    if (onSide(p1) || onSide(p2))
    {
      // The line's point nearest the centre: the wrap is mandatory where it is inside the sphere
      // (and, as OpenSim has it, its distance from p1 in model units is between 0 and 1),
      // possible where the ends are on opposite sides and it is on the other.
      const double fromP1 = (-p1).dot(-along);
      const Vector nearest = p1 - fromP1 * along;
      if (nearest.squaredNorm() < radius * radius && fromP1 > 0.0 && fromP1 < 1.0)
      {
        action = WrapAction::Mandatory;
      }
      else if (Sign(p1[axis]) != Sign(p2[axis]) && !onSide(nearest))
      {
        action = WrapAction::Wrapped;
      }
      else
      {
        return WrapAction::NoWrap;
      }
    }
    if (!onSide(p1) || !onSide(p2))
    {
      // The tangent points facing the centre from the ends, or the other pair where the path
      // would leave the wrapping side; the far way round where it runs against its radii.
      const Vector toCentre = NormalizeOrZero(-p1 - p2);
      const bool a1 = r1am.dot(toCentre) > r1bm.dot(toCentre), a2 = r2am.dot(toCentre) > r2bm.dot(toCentre);
      result.r1 = a1 ? r1a : r1b;
      result.r2 = a2 ? r2a : r2b;
      const Vector side = Vector::Unit(axis) * quadrantSign;
      if (NormalizeOrZero((result.r1 - p1) + (result.r2 - p2)).dot(side) < 0.0)
      {
        result.r1 = a1 ? r1b : r1a;
        result.r2 = a2 ? r2b : r2a;
      }
      farSide = (result.r1 + result.r2).dot((result.r1 - p1) + (result.r2 - p2)) < 0.0;
    }
  }
  const Vector r1n = NormalizeOrZero(result.r1), r2n = NormalizeOrZero(result.r2);
  double angle = std::acos(std::clamp(r1n.dot(r2n), -1.0, 1.0));
  if (farSide)
  {
    angle = -(2.0 * M_PI - angle);
  }
  result.axis = NormalizeOrZero(r1n.cross(r2n));
  result.turn = angle;
  result.rise = 0.0;
  result.length = radius * std::abs(angle);
  return action;
}

WrapAction WrapCylinderSegment(const Vector& p1, const Vector& p2, double radius, double length, int quadrantAxis,
  int quadrantSign, bool adjustTangents, WrapResult& result)
{
  const double rSquared = radius * radius;
  const bool constrained = quadrantSign != 0;
  const int axis = quadrantAxis;
  WrapAction action = WrapAction::Wrapped;
  result = WrapResult();
  if (DistanceSquaredToLine(p1, kAxisPoint, kAxis) < rSquared ||
    DistanceSquaredToLine(p2, kAxisPoint, kAxis) < rSquared)
  {
    return WrapAction::InsideRadius;
  }
  // Where the straight segment comes nearest the axis (between the cylinder's ends).
  Vector near12 = Vector::Constant(kNaN), near00 = Vector::Constant(kNaN);
  double t12 = kNaN, t00 = kNaN;
  NearestOnLines(p1, p2, Vector(0, 0, -0.5 * length), Vector(0, 0, 0.5 * length), near12, t12, near00, t00);
  const bool cuts = (near12 - near00).squaredNorm() < rSquared && t12 > 0.0 && t12 < 1.0;
  if (!constrained)
  {
    if (!cuts)
    {
      return WrapAction::NoWrap;
    }
    action = WrapAction::Mandatory;
  }
  // Each end's two tangent points: where the planes through it tangent to the cylinder touch.
  const Vector p11 = ClosestOnLine(p1, kAxisPoint, kAxis), p22 = ClosestOnLine(p2, kAxisPoint, kAxis);
  const auto tangents = [&](const Vector& p, const Vector& onAxis, double& distance, Vector& a, Vector& b) {
    const Vector out = NormalizeOrZero(p - onAxis, &distance);
    const double sinTheta = radius / distance;
    const double along = radius * sinTheta;
    const Vector foot = onAxis + along * out;
    const double across = std::sqrt(rSquared - along * along);
    const Vector side = kAxis.cross(out);
    a = foot + across * side;
    b = foot - across * side;
  };
  double p11Distance = 0, p22Distance = 0;
  Vector r1a, r1b, r2a, r2b;
  tangents(p1, p11, p11Distance, r1a, r1b);
  tangents(p2, p22, p22Distance, r2a, r2b);
  bool farSide = false, longWrap = false;
  if (constrained)
  {
    const auto onSide = [&](const Vector& x) {
      return Sign(x[axis]) == quadrantSign;
    };
    if (onSide(p1) || onSide(p2))
    {
      // An end on the wrapping side: the wrap is mandatory where the segment cuts the cylinder,
      // possible where the ends are on opposite sides and the segment passes on the other.
      if (cuts)
      {
        action = WrapAction::Mandatory;
      }
      else if (Sign(p1[axis]) != Sign(p2[axis]) && !onSide(near12))
      {
        action = WrapAction::Wrapped;
      }
      else
      {
        return WrapAction::NoWrap;
      }
    }
    const Vector r1am = r1a - p11, r1bm = r1b - p11, r2am = r2a - p22, r2bm = r2b - p22;
    const double alpha = std::acos(r1am.dot(r2bm) / (r1am.norm() * r2bm.norm()));
    const double beta = std::acos(r1bm.dot(r2am) / (r1bm.norm() * r2am.norm()));
    // The tangent points on the wrapping side; r1 and r2 together decide when r1's both are or
    // neither is. The wrap goes round the far side where the other pair's angle is the larger.
    const auto pick = [&](bool aThenB) {
      result.r1 = aThenB ? r1a : r1b;
      result.r2 = aThenB ? r2b : r2a;
      farSide = aThenB ? alpha > beta : !(alpha > beta);
    };
    if (onSide(r1a) && onSide(r1b))
    {
      pick(!onSide(r2a));
    }
    else if (onSide(r1a) != onSide(r1b))
    {
      pick(onSide(r1a));
    }
    else if (onSide(r2a))
    {
      pick(false);
    }
    else if (onSide(r2b))
    {
      pick(true);
    }
    else // no tangent point on the wrapping side
    {
      pick(alpha > beta);
      farSide = true;
    }
    // The long way round (more than half the cylinder) when the path runs against its radii.
    const Vector musclesWay = (result.r1 - p1) + (result.r2 - p2);
    const Vector radial = (result.r1 - p11) + (result.r2 - p22);
    longWrap = radial.dot(musclesWay) < 0.0;
  }
  else
  {
    NearestPair(r1a, r1b, r2a, r2b, p11, p22, result);
  }
  // The apex: where the plane through p1, p2 and the axis point between them leaves the
  // cylinder on the wrapping side. The tangent points slide along the axis onto the plane
  // through p1, p2 and the apex.
  const Vector between = p1 + p11Distance / (p11Distance + p22Distance) * (p2 - p1);
  const Vector axisPoint = ClosestOnLine(between, kAxisPoint, kAxis);
  Vector normal = NormalizeOrZero(NormalizeOrZero(p1 - axisPoint).cross(NormalizeOrZero(p2 - axisPoint)));
  const Vector apex1 = axisPoint + radius * NormalizeOrZero(kAxis.cross(normal));
  const Vector apex2 = axisPoint + radius * NormalizeOrZero(normal.cross(kAxis));
  const bool nearer1 = (between - apex1).squaredNorm() < (between - apex2).squaredNorm();
  const Vector apex = nearer1 != farSide ? apex1 : apex2;
  normal = NormalizeOrZero(NormalizeOrZero(p1 - apex).cross(NormalizeOrZero(p2 - apex)));
  const double d = -p1.dot(normal);
  Vector r1p, r2p;
  // (As OpenSim: the axis point p22 taken as the line's direction from p11.)
  if (SegmentMeetsPlane(result.r1 - 10.0 * kAxis, result.r1 + 10.0 * kAxis, normal, d, r1p) &&
    (ClosestOnLine(r1p, p11, p22) - p22).squaredNorm() < (p11 - p22).squaredNorm())
  {
    result.r1 = r1p;
  }
  if (SegmentMeetsPlane(result.r2 - 10.0 * kAxis, result.r2 + 10.0 * kAxis, normal, d, r2p) &&
    (ClosestOnLine(r2p, p11, p22) - p11).squaredNorm() < (p22 - p11).squaredNorm())
  {
    result.r2 = r2p;
  }
  const double half = 0.5 * length;
  if ((result.r1.z() < -half || result.r1.z() > half) && (result.r2.z() < -half || result.r2.z() > half))
  {
    return WrapAction::NoWrap;
  }
  SpiralPath(p1, p2, radius, longWrap, adjustTangents, result);
  return action;
}

namespace
{
/// The length along the line from `from` towards `to` at which OpenSim's residual for the point
/// nearest a ring of `radius` (about z, at z = 0) vanishes, from 0, by Newton's method on it.
/// (OpenSim's residual is the derivative of the squared distance to a ring of twice the radius.)
double RingResidualRoot(const Vector& from, const Vector& to, double radius)
{
  const Vector n = NormalizeOrZero(to - from);
  const double c2 = 2.0 * from.dot(n), c3 = from.x() * n.x() + from.y() * n.y(), c4 = n.x() * n.x() + n.y() * n.y();
  const double c5 = from.x() * from.x() + from.y() * from.y();
  const auto residual = [&](double u) {
    return c2 + 2.0 * u - 2.0 * radius * (2.0 * c4 * u + 2.0 * c3) / std::sqrt(u * u * c4 + 2.0 * c3 * u + c5);
  };
  double u = 0.0;
  const double scale = std::max({ radius, from.norm(), 1e-12 });
  for (int iteration = 0; iteration < 100; ++iteration)
  {
    const double h = 1e-7 * scale, f = residual(u);
    const double slope = (residual(u + h) - residual(u - h)) / (2.0 * h);
    if (!std::isfinite(f) || !std::isfinite(slope) || slope == 0.0)
    {
      break;
    }
    const double step = std::clamp(-f / slope, -scale, scale);
    u += step;
    if (std::abs(step) <= 1e-14 * scale)
    {
      break;
    }
  }
  return u;
}
}

WrapAction WrapTorusSegment(const Vector& p1, const Vector& p2, double ringRadius, double tubeRadius, int quadrantAxis,
  int quadrantSign, bool adjustTangents, WrapResult& result)
{
  result = WrapResult();
  // The point of the line nearest the ring from each end; the nearer (or the one on the
  // quadrant's side), and the ring point beside it.
  const auto nearRing = [&](const Vector& from, const Vector& to) {
    return Vector(from + RingResidualRoot(from, to, ringRadius) * NormalizeOrZero(to - from));
  };
  const auto ringDistance = [&](const Vector& a) {
    return std::sqrt(std::max(0.0, a.squaredNorm() + ringRadius * ringRadius - 2.0 * ringRadius * a.head<2>().norm()));
  };
  const Vector a1 = nearRing(p1, p2), a2 = nearRing(p2, p1);
  bool first = ringDistance(a1) < ringDistance(a2);
  if (quadrantSign != 0)
  {
    const bool on1 = Sign(a1[quadrantAxis]) == quadrantSign, on2 = Sign(a2[quadrantAxis]) == quadrantSign;
    if (!on1 && !on2)
    {
      return WrapAction::NoWrap;
    }
    first = on1 && on2 ? first : on1;
  }
  const Vector chosen = first ? a1 : a2;
  if (chosen.head<2>().norm() == 0.0)
  {
    return WrapAction::NoWrap;
  }
  const Vector ringPoint(
    chosen.x() * ringRadius / chosen.head<2>().norm(), chosen.y() * ringRadius / chosen.head<2>().norm(), 0.0);
  // The cylinder's frame: x towards the torus's centre, y down the torus's axis, z along the ring.
  Eigen::Matrix3d toCylinder;
  const Vector x = NormalizeOrZero(-ringPoint), y(0.0, 0.0, -1.0);
  toCylinder.row(0) = x.transpose();
  toCylinder.row(1) = y.transpose();
  toCylinder.row(2) = x.cross(y).transpose();
  const auto into = [&](const Vector& p) {
    return Vector(toCylinder * (p - ringPoint));
  };
  const auto back = [&](const Vector& p) {
    return Vector(toCylinder.transpose() * p + ringPoint);
  };
  WrapResult onCylinder;
  const WrapAction action =
    WrapCylinderSegment(into(p1), into(p2), tubeRadius, kTorusCylinderLength, 0, 1, adjustTangents, onCylinder);
  if (action != WrapAction::Wrapped && action != WrapAction::Mandatory)
  {
    return action;
  }
  result = onCylinder;
  result.r1 = back(onCylinder.r1);
  result.r2 = back(onCylinder.r2);
  result.axis = toCylinder.transpose() * onCylinder.axis;
  // The surface path turns about the cylinder's axis through the ring point, not the origin:
  // SurfacePoints draws about the origin, so the points are drawn in the cylinder's frame.
  result.centre = ringPoint;
  return action;
}

namespace
{
/// Removes wrap `w`'s two points from `path`, if there.
void RemoveWrapPoints(std::vector<WrappedPoint>& path, int w)
{
  for (size_t j = 0; j < path.size(); ++j)
  {
    if (path[j].wrap == w)
    {
      path.erase(path.begin() + static_cast<std::ptrdiff_t>(j), path.begin() + static_cast<std::ptrdiff_t>(j) + 2);
      return;
    }
  }
}

/// The index in `path` of path point `pathPoint`, or -1.
int Find(const std::vector<WrappedPoint>& path, int pathPoint)
{
  for (size_t j = 0; j < path.size(); ++j)
  {
    if (path[j].wrap < 0 && path[j].pathPoint == pathPoint)
    {
      return static_cast<int>(j);
    }
  }
  return -1;
}

/// Whether path point `k` is in `path` (is active).
bool Active(const std::vector<WrappedPoint>& path, int k)
{
  return Find(path, k) >= 0;
}

/// Where OpenSim takes a path's points to be when it measures lengths. A wrap point's place in
/// ground is cached (in the state) the first time a length is measured with it, and the cache is
/// not renewed when a later iteration over several wrap objects moves the point: its straight
/// segments are measured from where the point was then, its surface length is the latest. Kept
/// here so that lengths equal OpenSim's (docs/DESIGN.md, "Wrap objects").
class MeasuredPlaces
{
public:
  explicit MeasuredPlaces(size_t wraps)
    : Cached(wraps)
  {
  }

  Vector operator()(const WrappedPoint& p)
  {
    if (p.wrap < 0)
    {
      return p.position;
    }
    std::optional<Vector>& cached = this->Cached[static_cast<size_t>(p.wrap)][p.leaves ? 1 : 0];
    if (!cached)
    {
      cached = p.position;
    }
    return *cached;
  }

  /// The path's length as OpenSim measures it.
  double Length(const std::vector<WrappedPoint>& path)
  {
    double length = 0.0;
    for (size_t i = 1; i < path.size(); ++i)
    {
      const WrappedPoint& a = path[i - 1];
      const WrappedPoint& b = path[i];
      length += a.wrap >= 0 && a.wrap == b.wrap ? b.surfaceLength : ((*this)(b) - (*this)(a)).norm();
    }
    return length;
  }

private:
  std::vector<std::array<std::optional<Vector>, 2>> Cached; ///< [wrap][meets, leaves]
};

/// Wraps the path over wrap `w` (its best segment, if any): OpenSim's step for one wrap object.
/// False when the wrap's range holds no active point (OpenSim then stops wrapping the path).
bool ApplyWrap(const Model& model, const Path& path, int w, const std::vector<RigidTransform>& bodyPoses, bool single,
  double spacing, std::vector<WrappedPoint>& points, MeasuredPlaces& measured, WrapAction& last)
{
  last = WrapAction::NoWrap;
  RemoveWrapPoints(points, w);
  const PathWrap& wrap = path.wraps[static_cast<size_t>(w)];
  const WrapObject& object = model.wrapObjects[static_cast<size_t>(wrap.wrapObject)];
  if (!object.active)
  {
    return true;
  }
  const int count = static_cast<int>(path.points.size());
  const int first = wrap.rangeStart < 1 ? 0 : wrap.rangeStart - 1;
  const int lastPoint = wrap.rangeEnd < 1 ? count - 1 : wrap.rangeEnd - 1;
  int forward = first, backward = lastPoint;
  while (forward <= lastPoint && !Active(points, forward))
  {
    ++forward;
  }
  while (backward >= first && !Active(points, backward))
  {
    --backward;
  }
  if (forward > lastPoint || backward < first)
  {
    return false;
  }
  const int start = Find(points, forward), end = Find(points, backward);
  const RigidTransform toGround = Compose(bodyPoses[static_cast<size_t>(object.body)], object.placement);
  const RigidTransform fromGround = Inverse(toGround);
  // The segment whose wrap lengthens the path least, or the first the object cuts through.
  WrapResult best;
  int bestEnd = -1;
  double leastChange = std::numeric_limits<double>::infinity();
  for (int a = start; a < end; ++a)
  {
    const WrappedPoint& pa = points[static_cast<size_t>(a)];
    const WrappedPoint& pb = points[static_cast<size_t>(a) + 1];
    if (pa.wrap >= 0 && pa.wrap == pb.wrap)
    {
      continue; // over the surface of one wrap object already
    }
    WrapResult result;
    const Vector p1 = fromGround.Apply(pa.position), p2 = fromGround.Apply(pb.position);
    switch (object.shape)
    {
      case WrapShape::Cylinder:
        last = WrapCylinderSegment(p1, p2, object.dimensions[0], object.dimensions[1], object.quadrantAxis,
          object.quadrantSign, !single, result);
        break;
      case WrapShape::Sphere:
        last = WrapSphereSegment(p1, p2, object.dimensions[0], object.quadrantAxis, object.quadrantSign, result);
        break;
      case WrapShape::Torus:
        last = WrapTorusSegment(p1, p2, object.dimensions[0], object.dimensions[1], object.quadrantAxis,
          object.quadrantSign, !single, result);
        break;
      case WrapShape::Ellipsoid:
        last = WrapEllipsoidSegment(p1, p2, Vector(object.dimensions[0], object.dimensions[1], object.dimensions[2]),
          object.quadrantAxis, object.quadrantSign, wrap.method, result);
        break;
    }
    if (last == WrapAction::Mandatory)
    {
      best = std::move(result);
      bestEnd = a + 1;
      break;
    }
    if (last == WrapAction::Wrapped)
    {
      const Vector a1 = measured(pa), a2 = measured(pb);
      const double change = (a1 - toGround.Apply(result.r1)).norm() + result.length +
        (toGround.Apply(result.r2) - a2).norm() - (a2 - a1).norm();
      if (change < leastChange)
      {
        leastChange = change;
        best = std::move(result);
        bestEnd = a + 1;
      }
    }
  }
  if (bestEnd >= 0)
  {
    WrappedPoint meets, leaves;
    meets.position = toGround.Apply(best.r1);
    meets.wrap = w;
    leaves.position = toGround.Apply(best.r2);
    leaves.wrap = w;
    leaves.leaves = true;
    leaves.surfaceLength = best.length;
    leaves.surface = toGround.Apply(SurfacePoints(best, spacing));
    points.insert(points.begin() + bestEnd, { meets, leaves });
  }
  return true;
}
}

std::vector<WrappedPoint> WrapPath(const Model& model, const Path& path, const std::vector<Eigen::Vector3d>& points,
  const std::vector<int>& pathPoints, const std::vector<RigidTransform>& bodyPoses, double spacing,
  double* openSimLength)
{
  MeasuredPlaces measured(path.wraps.size());
  std::vector<WrappedPoint> wrapped(points.size());
  for (size_t i = 0; i < points.size(); ++i)
  {
    wrapped[i].position = points[i];
    wrapped[i].pathPoint = pathPoints[i];
  }
  const int count = static_cast<int>(path.wraps.size());
  const auto done = [&]() {
    if (openSimLength)
    {
      *openSimLength = measured.Length(wrapped);
    }
    return wrapped;
  };
  if (count == 0)
  {
    return done();
  }
  std::vector<int> order(static_cast<size_t>(count));
  for (int i = 0; i < count; ++i)
  {
    order[static_cast<size_t>(i)] = i;
  }
  std::vector<WrapAction> results(static_cast<size_t>(count), WrapAction::NoWrap);
  // One wrap object is wrapped once; several in turn, each from the others' last answer, until
  // the length settles.
  const int iterations = count < 2 ? 1 : kWrapIterations;
  double lastLength = std::numeric_limits<double>::infinity();
  for (int k = 0; k < iterations; ++k)
  {
    for (int i = 0; i < count; ++i)
    {
      if (!ApplyWrap(model, path, order[static_cast<size_t>(i)], bodyPoses, count == 1, spacing, wrapped, measured,
            results[static_cast<size_t>(i)]))
      {
        return done();
      }
    }
    const double length = measured.Length(wrapped);
    if (std::abs(length - lastLength) < kSettledLength)
    {
      break;
    }
    lastLength = length;
    // As OpenSim: where the first object missed and the second found a point inside it, the two
    // are tried the other way round.
    if (k == 0 && count > 1 && results[0] == WrapAction::NoWrap && results[1] == WrapAction::InsideRadius)
    {
      std::swap(order[0], order[1]);
      RemoveWrapPoints(wrapped, 0);
    }
  }
  return done();
}
}
