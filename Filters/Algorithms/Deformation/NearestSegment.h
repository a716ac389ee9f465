// SPDX-License-Identifier: BSD-3-Clause
// The action-line segment nearest to a point, and how the segment's motion
// carries the point: the rotations of the Laplacian coordinates and the
// follow rows of the deformation (MuscleDeformer, SurfaceSettle).
#pragma once

#include "Deformation/MuscleDeformer.h"

#include <algorithm>
#include <limits>
#include <utility>
#include <vector>

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

  NearestSegment() = default;
  NearestSegment(const Eigen::Vector3d& p, const std::vector<MatchedLine>& lines)
  {
    double nearest = std::numeric_limits<double>::max();
    ForEachSegment(p, lines, [&](const NearestSegment& segment, double d) {
      if (d < nearest)
      {
        nearest = d;
        *this = segment;
      }
    });
  }

  /// Calls visit(segment, distance of p from it) for every segment of `lines` that carries a
  /// direction in both poses (segments of zero length are skipped), with p's foot on it.
  template<typename Visit>
  static void ForEachSegment(const Eigen::Vector3d& p, const std::vector<MatchedLine>& lines, Visit&& visit)
  {
    for (const MatchedLine& candidate : lines)
    {
      for (Eigen::Index s = 0; s + 1 < candidate.rest.rows(); ++s)
      {
        const Eigen::Vector3d a = candidate.rest.row(s).transpose(), b = candidate.rest.row(s + 1).transpose();
        if ((b - a).squaredNorm() == 0 || (candidate.current.row(s + 1) - candidate.current.row(s)).squaredNorm() == 0)
        {
          continue;
        }
        NearestSegment segment;
        segment.line = &candidate;
        segment.k = s;
        segment.t = SegmentFoot(p, a, b);
        visit(segment, (a + segment.t * (b - a) - p).norm());
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

/// How the action-line segments near p carry it, blended so that it varies continuously with p
/// and with the lines: each segment whose distance from p exceeds the nearest one's by less than
/// `width` weighs (1 - (excess / width)^2)^2, and the rotation (the weighted mean of the
/// segments' quaternions) and where the motion takes p are the weighted means. The nearest
/// segment alone jumps where two segments are equally near (between two bundles' lines, at a
/// via point), and a 1e-7 change of the input then decides which one carries a point. `width` 0:
/// the nearest segment (segments exactly as near weigh alike).
struct BlendedSegments
{
  Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();
  Eigen::Vector3d follow = Eigen::Vector3d::Zero();

  BlendedSegments(const Eigen::Vector3d& p, const std::vector<MatchedLine>& lines, double width)
  {
    std::vector<std::pair<NearestSegment, double>> segments;
    double nearest = std::numeric_limits<double>::max();
    NearestSegment::ForEachSegment(p, lines, [&](const NearestSegment& segment, double d) {
      segments.emplace_back(segment, d);
      nearest = std::min(nearest, d);
    });
    if (segments.empty())
    {
      this->follow = p;
      return;
    }
    Eigen::Vector4d sum = Eigen::Vector4d::Zero();
    Eigen::Vector4d reference = Eigen::Vector4d::Zero();
    double total = 0;
    for (const auto& [segment, d] : segments)
    {
      const double excess = d - nearest;
      const double u = width > 0 ? excess / width : (excess > 0 ? 1.0 : 0.0);
      if (u >= 1)
      {
        continue;
      }
      const double w = (1 - u * u) * (1 - u * u);
      Eigen::Vector4d q = Eigen::Quaterniond(segment.Rotation()).coeffs();
      if (total == 0)
      {
        reference = q;
      }
      if (q.dot(reference) < 0) // q and -q are the same rotation: average the near ones
      {
        q = -q;
      }
      sum += w * q;
      this->follow += w * segment.Follow(p);
      total += w;
    }
    this->follow /= total;
    this->rotation = Eigen::Quaterniond(Eigen::Vector4d(sum.normalized())).toRotationMatrix();
  }
};
}
