// SPDX-License-Identifier: BSD-3-Clause
// The action-line segment nearest to a point, and how the segment's motion
// carries the point: the rotations of the Laplacian coordinates and the
// follow rows of the deformation (MuscleDeformer, SurfaceSettle). A segment is
// a piece of a line between two of its own points (LineSpan).
#pragma once

#include "Deformation/MuscleDeformer.h"
#include "Geometry/Polyline.h"

#include <algorithm>
#include <limits>
#include <utility>
#include <vector>

namespace md
{
/// A piece of a matched line from one of its own points to the next (MatchedLine::knots): a
/// segment, or the segments of a path that PathsOverBones kept over a bone.
struct LineSpan
{
  Eigen::Index first = 0;
  Eigen::Index last = 1;

  /// The point of `pose` (the line's rest or current points) at parameter t in [0, 1] of the
  /// piece: at that share of its rest length along it (on a segment, t along it).
  Eigen::Vector3d At(const Points& rest, const Points& pose, double t) const
  {
    Eigen::Index j = this->first;
    double u = t;
    if (this->last > this->first + 1)
    {
      double along = t * this->RestLength(rest);
      for (; j + 1 < this->last; ++j)
      {
        const double length = (rest.row(j + 1) - rest.row(j)).norm();
        if (along <= length)
        {
          break;
        }
        along -= length;
      }
      const double length = (rest.row(j + 1) - rest.row(j)).norm();
      u = length > 0 ? std::clamp(along / length, 0.0, 1.0) : 0.0;
    }
    return ((1 - u) * pose.row(j) + u * pose.row(j + 1)).transpose();
  }

  double RestLength(const Points& rest) const
  {
    double length = 0;
    for (Eigen::Index j = this->first; j < this->last; ++j)
    {
      length += (rest.row(j + 1) - rest.row(j)).norm();
    }
    return length;
  }

  /// The parameter (share of the rest length) of the point of the piece at rest nearest to p,
  /// and its distance from p.
  std::pair<double, double> Foot(const Points& rest, const Eigen::Vector3d& p) const
  {
    if (this->last == this->first + 1)
    {
      const Eigen::Vector3d a = rest.row(this->first).transpose(), b = rest.row(this->last).transpose();
      const double t = SegmentFoot(p, a, b);
      return { t, (a + t * (b - a) - p).norm() };
    }
    double nearest = std::numeric_limits<double>::max(), at = 0, before = 0;
    for (Eigen::Index j = this->first; j < this->last; ++j)
    {
      const Eigen::Vector3d a = rest.row(j).transpose(), b = rest.row(j + 1).transpose();
      const double u = SegmentFoot(p, a, b), length = (b - a).norm();
      const double d = (a + u * (b - a) - p).norm();
      if (d < nearest)
      {
        nearest = d;
        at = before + u * length;
      }
      before += length;
    }
    return { before > 0 ? at / before : 0.0, nearest };
  }
};

/// Calls visit(span) for every piece of `line` (LineSpan), in order.
template<typename Visit>
void ForEachSpan(const MatchedLine& line, Visit&& visit)
{
  if (line.knots.empty())
  {
    for (Eigen::Index k = 0; k + 1 < line.rest.rows(); ++k)
    {
      visit(LineSpan{ k, k + 1 });
    }
    return;
  }
  for (size_t j = 0; j + 1 < line.knots.size(); ++j)
  {
    visit(LineSpan{ line.knots[j], line.knots[j + 1] });
  }
}

/// The action-line piece nearest to p (over all lines; LineSpan: a segment, or a path between
/// two of its own points), with the parameter of p's foot on it in [0, 1]. Pieces whose ends
/// coincide in either pose carry no direction and are skipped. A piece turns the points near it
/// as its end-to-end chord turns, as the line's own segment would; its points between say where
/// its pull runs.
struct NearestSegment
{
  const MatchedLine* line = nullptr;
  LineSpan span;
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

  /// Calls visit(piece, distance of p from it) for every piece of `lines` that carries a
  /// direction in both poses, with p's foot on it.
  template<typename Visit>
  static void ForEachSegment(const Eigen::Vector3d& p, const std::vector<MatchedLine>& lines, Visit&& visit)
  {
    for (const MatchedLine& candidate : lines)
    {
      ForEachSpan(candidate, [&](const LineSpan& span) {
        if ((candidate.rest.row(span.last) - candidate.rest.row(span.first)).squaredNorm() == 0 ||
          (candidate.current.row(span.last) - candidate.current.row(span.first)).squaredNorm() == 0)
        {
          return;
        }
        NearestSegment segment;
        segment.line = &candidate;
        segment.span = span;
        const auto [t, distance] = span.Foot(candidate.rest, p);
        segment.t = t;
        visit(segment, distance);
      });
    }
  }

  /// The rotation taking the piece's rest direction (end to end) to its current one.
  Eigen::Matrix3d Rotation() const
  {
    if (!this->line)
    {
      return Eigen::Matrix3d::Identity();
    }
    const Points &rest = this->line->rest, &current = this->line->current;
    return Eigen::Quaterniond::FromTwoVectors((rest.row(this->span.last) - rest.row(this->span.first)).transpose(),
      (current.row(this->span.last) - current.row(this->span.first)).transpose())
      .toRotationMatrix();
  }

  /// Where the piece's motion takes p: rotated about its foot on the piece, which moves with the
  /// line's point at that place.
  Eigen::Vector3d Follow(const Eigen::Vector3d& p) const
  {
    if (!this->line)
    {
      return p;
    }
    const Points &rest = this->line->rest, &current = this->line->current;
    return this->span.At(rest, current, this->t) + this->Rotation() * (p - this->span.At(rest, rest, this->t));
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
