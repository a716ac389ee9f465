// SPDX-License-Identifier: BSD-3-Clause
// A path over an OpenSim WrapEllipsoid (declared in OpenSimWrapping.h): opensim-core's
// WrapEllipsoid::wrapLine, whose algorithm this follows (the wrap's plane, the sampled section),
// with the tangent points in closed form. The code is ours.
#include "OpenSim/OpenSimWrapping.h"
#include "OpenSim/WrapGeometry.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

namespace md::osim
{
namespace
{
using Vector = Eigen::Vector3d;

/// OpenSim's constants: the fan's blend between the axial and the fan estimates of c1, the
/// fan's samples, how near its ends an axial estimate fades out, and "equal within rounding".
constexpr double kMuBlendMin = 0.7073;
constexpr double kMuBlendMax = 0.9;
constexpr int kFanSamples = 300;
constexpr double kAxialEndBlend = 0.3;
constexpr double kRoundoff = 2e-13;
/// OpenSim's segment length over the ellipsoid (model units, meant as metres) and its most
/// segments.
constexpr double kSurfaceSegment = 0.001;
constexpr int kMostSegments = 499;

/// The point of the ellipse (x/a)^2 + (y/b)^2 = 1 nearest (u, v): Eberly's Newton iteration on
/// the Lagrange multiplier (Graphics Gems IV), with its special cases on the axes, as OpenSim.
Eigen::Vector2d NearestOnEllipse(double a, double b, double u, double v)
{
  const double a2 = a * a, b2 = b * b;
  const bool onYAxis = std::abs(u) <= kRoundoff, onXAxis = std::abs(v) <= kRoundoff;
  if (onYAxis && onXAxis)
  {
    return a < b ? Eigen::Vector2d(u < 0.0 ? -a : a, v) : Eigen::Vector2d(u, v < 0.0 ? -b : b);
  }
  if (onYAxis)
  {
    if (a >= b || std::abs(v) >= b - a2 / b)
    {
      return { u, v >= 0 ? b : -b };
    }
    const double y = b2 * v / (b2 - a2);
    return { a * std::sqrt(std::abs(1 - (y / b) * (y / b))), y };
  }
  if (onXAxis)
  {
    if (b >= a || std::abs(u) >= a - b2 / a)
    {
      return { u >= 0 ? a : -a, v };
    }
    const double x = a2 * u / (a2 - b2);
    return { x, b * std::sqrt(std::abs(1 - (x / a) * (x / a))) };
  }
  const double a2u2 = a2 * u * u, b2v2 = b2 * v * v;
  double t = (u / a) * (u / a) + (v / b) * (v / b) < 1.0 ? 0.0 : std::max(a, b) * std::hypot(u, v);
  double p = 0, q = 0;
  for (int i = 0; i < 64; ++i)
  {
    p = t + a2;
    q = t + b2;
    const double f = p * p * q * q - a2u2 * q * q - b2v2 * p * p;
    if (std::abs(f) < 1e-9)
    {
      break;
    }
    t -= f / (2.0 * (p * q * (p + q) - a2u2 * q - b2v2 * p));
  }
  return { a2 * u / p, b2 * v / q };
}

/// The point of the ellipsoid of radii `a` nearest `x`, as OpenSim finds it: in the coordinate
/// plane through x normal to axis `planeAxis` (the plane's ellipse), or where x is on coordinate
/// planes in the one whose ellipse is narrowest, else by Eberly's Newton iteration.
Vector NearestOnEllipsoid(const Vector& a, const Vector& x, int planeAxis = -1)
{
  if (planeAxis < 0)
  {
    double narrowest = std::numeric_limits<double>::infinity();
    for (int i = 0; i < 3; ++i)
    {
      const double width = a.sum() - a[i];
      if (std::abs(x[i]) <= kRoundoff && width < narrowest)
      {
        planeAxis = i;
        narrowest = width;
      }
    }
  }
  if (planeAxis >= 0)
  {
    const int j = (planeAxis + 1) % 3, k = (planeAxis + 2) % 3;
    const Eigen::Vector2d near = NearestOnEllipse(a[j], a[k], x[j], x[k]);
    Vector result = x;
    result[j] = near[0];
    result[k] = near[1];
    return result;
  }
  const Vector a2 = a.cwiseAbs2();
  const Vector a2x2 = a2.cwiseProduct(x.cwiseAbs2());
  double t = x.cwiseQuotient(a).squaredNorm() < 1.0 ? 0.0 : a.maxCoeff() * x.norm();
  Vector pqr;
  for (int i = 0; i < 64; ++i)
  {
    pqr = Vector::Constant(t) + a2;
    const double p = pqr[0], q = pqr[1], r = pqr[2];
    const double f =
      p * p * q * q * r * r - a2x2[0] * q * q * r * r - a2x2[1] * p * p * r * r - a2x2[2] * p * p * q * q;
    if (std::abs(f) < 1e-9)
    {
      break;
    }
    const double slope = 2.0 *
      (p * q * r * (q * r + p * r + p * q) - a2x2[0] * q * r * (q + r) - a2x2[1] * p * r * (p + r) -
        a2x2[2] * p * q * (p + q));
    t -= f / slope;
  }
  pqr = Vector::Constant(t) + a2;
  return a2.cwiseProduct(x).cwiseQuotient(pqr);
}

/// c1, the ellipsoid's point the wrap's plane passes through, for the segment whose line meets
/// the ellipsoid at r1 and r2 (OpenSim's three methods). `fanWeight` gets how much of the fan
/// estimate it holds (-1 where none was computed), `alongness` how nearly the segment runs along
/// a coordinate axis (the cosine).
Vector WrapPlanePoint(const Vector& p1, const Vector& p2, const Vector& r1, const Vector& r2, const Vector& a,
  EllipsoidWrapMethod method, double& fanWeight, double& alongness)
{
  fanWeight = -1.0;
  const Vector r1r2 = r2 - r1;
  // Axial: where the segment crosses the coordinate plane normal to the axis most nearly along
  // it, and the ellipse of that plane's point nearest there.
  Vector mu = NormalizeOrZero(p1 - p2).cwiseAbs();
  int best = 0;
  for (int i = 1; i < 3; ++i)
  {
    best = mu[i] > mu[best] ? i : best;
  }
  alongness = mu[best];
  if (method == EllipsoidWrapMethod::Midpoint)
  {
    return NearestOnEllipsoid(a, r1 + 0.5 * r1r2);
  }
  const double t = -r1[best] / r1r2[best];
  const Vector axial = NearestOnEllipsoid(a, r1 + t * r1r2, best);
  if (method == EllipsoidWrapMethod::Axial)
  {
    return axial;
  }
  if (mu[best] > kMuBlendMin)
  {
    // A crossing near (or beyond) the ends of r1-r2 fades the axial estimate out.
    const double s = t < 0.0 || t > 1.0 ? 0.0
      : t < kAxialEndBlend              ? t / kAxialEndBlend
      : t > 1.0 - kAxialEndBlend        ? (1.0 - t) / kAxialEndBlend
                                        : 1.0;
    mu[best] = kMuBlendMin + s * (mu[best] - kMuBlendMin);
  }
  alongness = mu[best];
  Vector c1 = mu[best] > kMuBlendMin ? axial : Vector::Zero();
  if (mu[best] < kMuBlendMax)
  {
    // The fan: the directions from the segment's points to their nearest ellipsoid points,
    // averaged.
    Vector sum = Vector::Zero();
    for (int i = 1; i < kFanSamples - 1; ++i)
    {
      const Vector on = r1 + (static_cast<double>(i) / kFanSamples) * r1r2;
      sum += NormalizeOrZero(NearestOnEllipsoid(a, on) - on);
    }
    const Vector fan = NearestOnEllipsoid(a, r1 + 0.5 * r1r2 + NormalizeOrZero(sum));
    if (mu[best] <= kMuBlendMin)
    {
      c1 = fan;
      fanWeight = 1.0;
    }
    else
    {
      const double share = (mu[best] - kMuBlendMin) / (kMuBlendMax - kMuBlendMin);
      c1 = NearestOnEllipsoid(a, share * c1 + (1.0 - share) * fan);
      fanWeight = 1.0 - share;
    }
  }
  return c1;
}

/// The point where the line from `p` in the plane n . x + d = 0 touches the ellipsoid of radii
/// `a`: of the two, the one on the side of the line p-q where `side` is (the nearer to `side`
/// where that is on the line). The touching points are the ellipsoid's points on p's polar plane
/// (x . p / a^2 = 1).
Vector TangentPoint(const Vector& p, const Vector& q, const Vector& side, const Vector& n, double d, const Vector& a)
{
  const Vector polar = p.cwiseQuotient(a.cwiseAbs2());
  const Vector along = n.cross(polar);
  // A point of both planes (the least-norm one) and the line's meeting with the ellipsoid.
  Eigen::Matrix2d m;
  m << n.dot(n), n.dot(polar), n.dot(polar), polar.dot(polar);
  const Eigen::Vector2d ab = m.ldlt().solve(Eigen::Vector2d(-d, 1.0));
  const Vector x0 = ab[0] * n + ab[1] * polar;
  const EllipsoidCrossings on = CrossEllipsoid(x0, along, a);
  const Vector t1 = x0 + on.larger * along, t2 = x0 + on.smaller * along;
  const auto sideOf = [&](const Vector& x) {
    return (x - p).cross(q - p).dot(n);
  };
  const double wanted = sideOf(side);
  if (wanted == 0.0)
  {
    return (t1 - side).squaredNorm() <= (t2 - side).squaredNorm() ? t1 : t2;
  }
  return (sideOf(t1) > 0.0) == (wanted > 0.0) ? t1 : t2;
}

/// The length of the surface path from r1 to r2: polylines of 128, 256 and 512 equal turns,
/// extrapolated (Romberg: their error is a series in even powers of the turn).
double ArcLength(const WrapResult& wrap)
{
  constexpr int kLevels = 3, kFinest = 512;
  std::array<double, kLevels> polyline{};
  std::array<Vector, kLevels> last{ wrap.r1, wrap.r1, wrap.r1 };
  for (int i = 1; i <= kFinest; ++i)
  {
    const Vector next = i == kFinest ? wrap.r2 : SurfacePointAt(wrap, static_cast<double>(i) / kFinest);
    for (int level = 0; level < kLevels; ++level)
    {
      // Level 0 takes every 4th point, level 1 every 2nd, level 2 all.
      if (i % (1 << (kLevels - 1 - level)) == 0)
      {
        polyline[level] += (next - last[level]).norm();
        last[level] = next;
      }
    }
  }
  const double once0 = (4.0 * polyline[1] - polyline[0]) / 3.0, once1 = (4.0 * polyline[2] - polyline[1]) / 3.0;
  return (16.0 * once1 - once0) / 15.0;
}
}

WrapAction WrapEllipsoidSegment(const Vector& point1, const Vector& point2, const Vector& radii, int quadrantAxis,
  int quadrantSign, EllipsoidWrapMethod method, WrapResult& result)
{
  result = WrapResult();
  // OpenSim works at a scale where the radii are about 1 (its thresholds are for that scale).
  const double factor = 3.0 / radii.sum();
  const Vector p1 = factor * point1, p2 = factor * point2, a = factor * radii;
  const double p1e = p1.cwiseQuotient(a).squaredNorm() - 1.0, p2e = p2.cwiseQuotient(a).squaredNorm() - 1.0;
  if (p1e < -1e-4 || p2e < -1e-4)
  {
    return WrapAction::InsideRadius;
  }
  if (std::abs(NormalizeOrZero(p1).dot(NormalizeOrZero(p2)) - 1.0) < 1e-4)
  {
    return WrapAction::NoWrap; // p1 and p2 in one direction from the centre
  }
  // Only a segment that cuts the ellipsoid wraps: where its line meets it, both within it.
  const Vector p1p2 = p1 - p2;
  const EllipsoidCrossings cut = CrossEllipsoid(p2, p1p2, a);
  const double l1 = cut.larger, l2 = cut.smaller;
  if (!cut.meets || !(0.0 < l1 && l1 < 1.0) || !(0.0 < l2 && l2 < 1.0))
  {
    return WrapAction::NoWrap;
  }
  double fanWeight = -1.0, alongness = 0.0;
  Vector c1 = WrapPlanePoint(p1, p2, p2 + l1 * p1p2, p2 + l2 * p1p2, a, method, fanWeight, alongness);
  if (quadrantSign != 0 && (c1[quadrantAxis] >= 0.0 ? 1 : -1) != quadrantSign)
  {
    // c1 mirrored to the quadrant's side, and drawn back towards the plane between the sides by
    // as much as the fan made it.
    c1[quadrantAxis] = -c1[quadrantAxis];
    if (fanWeight < 0.0)
    {
      fanWeight = 1.0 - (alongness - kMuBlendMin) / (kMuBlendMax - kMuBlendMin);
    }
    fanWeight = std::min(fanWeight, 1.0);
    if (fanWeight > 0.0)
    {
      c1[quadrantAxis] -= fanWeight * c1[quadrantAxis];
      c1 = NearestOnEllipsoid(a, c1);
    }
  }
  // The wrap's plane, through p1, p2 and c1.
  const Vector n = NormalizeOrZero(p1p2.cross(p1 - c1));
  if (n.isZero())
  {
    return WrapAction::NoWrap;
  }
  const double d = -n.dot(c1);
  result.r1 = std::abs(p1e) < 1e-4 ? p1 : TangentPoint(p1, p2, c1, n, d, a);
  result.r2 = std::abs(p2e) < 1e-4 ? p2 : TangentPoint(p2, p1, c1, n, d, a);
  if (!result.r1.allFinite() || !result.r2.allFinite())
  {
    result = WrapResult();
    return WrapAction::NoWrap; // an end's polar plane parallel to the wrap's (degenerate)
  }
  // The section is drawn about the plane's point on the coordinate axis most nearly normal to it.
  int normalAxis = 0;
  for (int i = 1; i < 3; ++i)
  {
    normalAxis = std::abs(n[i]) > std::abs(n[normalAxis]) ? i : normalAxis;
  }
  result.centre = Vector::Unit(normalAxis) * (-d / n[normalAxis]);
  const Vector ar1 = NormalizeOrZero(result.r1 - result.centre), ar2 = NormalizeOrZero(result.r2 - result.centre);
  const double angle = std::acos(std::clamp(ar1.dot(ar2), -1.0, 1.0));
  result.axis = NormalizeOrZero(ar1.cross(ar2));
  result.radii = a;
  result.rise = 0.0;
  result.turn = angle;
  // OpenSim draws the section in segments of about kSurfaceSegment (counted by the chord in model
  // units); where a quadrant is set and the near way round leaves along the first or the last
  // segment back towards p1 or p2, it takes the far way round.
  const int segments =
    std::min(kMostSegments, static_cast<int>((result.r2 - result.r1).norm() / factor / kSurfaceSegment));
  if (quadrantSign != 0 && segments >= 2 &&
    (NormalizeOrZero(p1 - result.r1).dot(NormalizeOrZero(SurfacePointAt(result, 1.0 / segments) - result.r1)) > 0.0 ||
      NormalizeOrZero(p2 - result.r2).dot(NormalizeOrZero(SurfacePointAt(result, 1.0 - 1.0 / segments) - result.r2)) >
        0.0))
  {
    result.turn = -(2.0 * M_PI - angle);
  }
  result.length = ArcLength(result);
  result.r1 /= factor;
  result.r2 /= factor;
  result.centre /= factor;
  result.radii = radii;
  result.length /= factor;
  return WrapAction::Mandatory;
}
}
