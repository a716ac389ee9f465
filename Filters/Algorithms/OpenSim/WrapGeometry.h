// SPDX-License-Identifier: BSD-3-Clause
// Small geometry shared by the wrap objects' code (OpenSimWrapping.cxx, OpenSimWrapEllipsoid.cxx).
#pragma once

#include <Eigen/Core>

#include <algorithm>
#include <cmath>
#include <limits>

namespace md::osim
{
/// v / |v|, or zero where |v| is below machine epsilon; `magnitude` gets |v|.
inline Eigen::Vector3d NormalizeOrZero(const Eigen::Vector3d& v, double* magnitude = nullptr)
{
  const double m = v.norm();
  if (magnitude)
  {
    *magnitude = m;
  }
  return m >= std::numeric_limits<double>::epsilon() ? Eigen::Vector3d(v / m) : Eigen::Vector3d::Zero();
}

/// Where the line point + s direction meets the ellipsoid of `radii` centred at the origin: the
/// roots s of |(point + s direction) / radii|^2 = 1, the larger first. Where the line passes the
/// ellipsoid by (`meets` false) both are the parameter of its nearest approach in the
/// ellipsoid's scaled space.
struct EllipsoidCrossings
{
  double larger = 0.0, smaller = 0.0;
  bool meets = false;
};

inline EllipsoidCrossings CrossEllipsoid(
  const Eigen::Vector3d& point, const Eigen::Vector3d& direction, const Eigen::Vector3d& radii)
{
  const Eigen::Vector3d f1 = direction.cwiseQuotient(radii), f2 = point.cwiseQuotient(radii);
  const double a = f1.squaredNorm(), b = 2.0 * f1.dot(f2), c = f2.squaredNorm() - 1.0;
  const double disc = b * b - 4.0 * a * c;
  const double root = std::sqrt(std::max(0.0, disc));
  return { (-b + root) / (2.0 * a), (-b - root) / (2.0 * a), disc >= 0.0 };
}
}
