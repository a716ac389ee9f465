// SPDX-License-Identifier: BSD-3-Clause
// Polylines: their length, the foot of a point on a segment, and points at equal arc lengths
// along them.
#pragma once

#include "Common/MeshTypes.h"

#include <algorithm>
#include <vector>

namespace md
{
/// The length of a polyline (its points in order, one a row).
template<class Derived>
double PolylineLength(const Eigen::MatrixBase<Derived>& points)
{
  double length = 0.0;
  for (Eigen::Index i = 1; i < points.rows(); ++i)
  {
    length += (points.row(i) - points.row(i - 1)).norm();
  }
  return length;
}

/// The parameter in [0, 1] of the foot of p on the segment from a to b (0 on a segment of no length).
inline double SegmentFoot(const Eigen::Vector3d& p, const Eigen::Vector3d& a, const Eigen::Vector3d& b)
{
  const Eigen::Vector3d ab = b - a;
  const double length2 = ab.squaredNorm();
  return length2 > 0 ? std::clamp((p - a).dot(ab) / length2, 0.0, 1.0) : 0.0;
}

/// `count` (>= 2) points at equal arc lengths along `curve`, its ends included.
inline Points ResampleByArcLength(const std::vector<Eigen::Vector3d>& curve, Eigen::Index count)
{
  std::vector<double> at(curve.size(), 0.0);
  for (size_t i = 1; i < curve.size(); ++i)
  {
    at[i] = at[i - 1] + (curve[i] - curve[i - 1]).norm();
  }
  Points points(count, 3);
  size_t k = 1;
  for (Eigen::Index i = 0; i < count; ++i)
  {
    const double target = at.back() * static_cast<double>(i) / static_cast<double>(count - 1);
    while (k + 1 < curve.size() && at[k] < target)
    {
      ++k;
    }
    const double span = at[k] - at[k - 1];
    const double f = span > 0 ? std::clamp((target - at[k - 1]) / span, 0.0, 1.0) : 0.0;
    points.row(i) = ((1 - f) * curve[k - 1] + f * curve[k]).transpose();
  }
  return points;
}
}
