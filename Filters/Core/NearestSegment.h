// SPDX-License-Identifier: BSD-3-Clause
// The action-line segment nearest to a point, and how the segment's motion
// carries the point: the rotations of the Laplacian coordinates and the
// follow rows of the deformation (MuscleDeformer, SurfaceSettle).
#pragma once

#include "MuscleDeformer.h"

#include <algorithm>
#include <limits>

namespace md
{
/// The parameter in [0, 1] of the foot of p on the segment from a to b (0 on a segment of no length).
inline double SegmentFoot(const Eigen::Vector3d& p, const Eigen::Vector3d& a, const Eigen::Vector3d& b)
{
  const Eigen::Vector3d ab = b - a;
  const double length2 = ab.squaredNorm();
  return length2 > 0 ? std::clamp((p - a).dot(ab) / length2, 0.0, 1.0) : 0.0;
}

/// The action-line segment nearest to p (over all lines), as line and index
/// of its first point, with the parameter of p's foot on it in [0, 1].
/// Segments of zero length in either pose carry no direction and are skipped.
struct NearestSegment
{
  const MatchedLine* line = nullptr;
  Eigen::Index k = 0;
  double t = 0;

  NearestSegment(const Eigen::Vector3d& p, const std::vector<MatchedLine>& lines)
  {
    double nearest = std::numeric_limits<double>::max();
    for (const MatchedLine& candidate : lines)
    {
      for (Eigen::Index s = 0; s + 1 < candidate.rest.rows(); ++s)
      {
        const Eigen::Vector3d a = candidate.rest.row(s).transpose(), b = candidate.rest.row(s + 1).transpose();
        if ((b - a).squaredNorm() == 0 || (candidate.current.row(s + 1) - candidate.current.row(s)).squaredNorm() == 0)
        {
          continue;
        }
        const double foot = SegmentFoot(p, a, b);
        const double d = (a + foot * (b - a) - p).norm();
        if (d < nearest)
        {
          nearest = d;
          this->line = &candidate;
          this->k = s;
          this->t = foot;
        }
      }
    }
  }

  /// The rotation taking the segment's rest direction to its current one.
  Eigen::Matrix3d Rotation() const
  {
    if (!this->line)
    {
      return Eigen::Matrix3d::Identity();
    }
    return Eigen::Quaterniond::FromTwoVectors(
      (this->line->rest.row(this->k + 1) - this->line->rest.row(this->k)).transpose(),
      (this->line->current.row(this->k + 1) - this->line->current.row(this->k)).transpose())
      .toRotationMatrix();
  }

  /// Where the segment's motion takes p: rotated about its foot on the
  /// segment, which moves with the segment.
  Eigen::Vector3d Follow(const Eigen::Vector3d& p) const
  {
    if (!this->line)
    {
      return p;
    }
    const auto at = [&](const Points& pose) {
      return Eigen::Vector3d(((1 - this->t) * pose.row(this->k) + this->t * pose.row(this->k + 1)).transpose());
    };
    return at(this->line->current) + this->Rotation() * (p - at(this->line->rest));
  }
};
}
