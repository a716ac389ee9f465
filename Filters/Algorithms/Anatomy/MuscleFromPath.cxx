// SPDX-License-Identifier: BSD-3-Clause
#include "Anatomy/MuscleFromPath.h"

#include "Geometry/MeshChecks.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

namespace md
{
namespace
{
/// The belly's share of the path: at least this much, so that a muscle whose tendon slack length
/// nearly spans its path still has room for its volume; at most this much, so that each end
/// keeps a tendon to taper into.
constexpr double kLeastBellyShare = 1.0 / 3.0;
constexpr double kMostBellyShare = 0.9;
/// The share of the belly, at each of its ends, over which the radius rises from the tendon's.
constexpr double kTaperShare = 0.25;
/// Points a ring has at least, and rings at least.
constexpr int kLeastRingPoints = 8;
constexpr int kLeastRings = 3;
/// Points averaged along the path for one point of the smoothed centre line, and how far either
/// way they reach, in local radii: far enough that the centre line turns at a corner no tighter
/// than the tube's radius, so that the surface does not fold on the corner's inner side.
constexpr int kSmoothingSamples = 33;
constexpr double kSmoothingRadii = 2.0;
/// The surface's volume is scaled to the estimate within this share.
constexpr double kVolumeTolerance = 1e-9;
constexpr int kVolumeRounds = 50;
/// Against the bones: how far a point stops short of a bone and how near the centre it may be
/// drawn, as shares of the local radius, and how far the other points may widen to keep the volume.
constexpr double kBoneClearanceShare = 0.02;
constexpr double kLeastRadiusShare = 0.1;
constexpr double kMostRadiusScale = 3.0;

/// A polyline parametrised by arc length.
class ArcPolyline
{
public:
  explicit ArcPolyline(const Points& points)
  {
    this->at.push_back(0.0);
    for (Eigen::Index i = 0; i < points.rows(); ++i)
    {
      this->points.emplace_back(points.row(i).transpose());
      if (i > 0)
      {
        this->at.push_back(this->at.back() + (this->points[i] - this->points[i - 1]).norm());
      }
    }
  }

  double Length() const { return this->at.back(); }

  Eigen::Vector3d At(double s) const
  {
    s = std::clamp(s, 0.0, this->Length());
    const size_t k = static_cast<size_t>(std::upper_bound(this->at.begin(), this->at.end(), s) - this->at.begin());
    if (k >= this->at.size())
    {
      return this->points.back();
    }
    const size_t first = k == 0 ? 0 : k - 1;
    const double span = this->at[k] - this->at[first];
    const double f = span > 0 ? (s - this->at[first]) / span : 0.0;
    return (1 - f) * this->points[first] + f * this->points[k];
  }

  /// The mean of the polyline over [s - h, s + h], h no more than reaches either end (so that the
  /// ends stay the path's own).
  Eigen::Vector3d SmoothedAt(double s, double h) const
  {
    h = std::min({ h, s, this->Length() - s });
    if (h <= 0)
    {
      return this->At(s);
    }
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    for (int k = 0; k < kSmoothingSamples; ++k)
    {
      sum += this->At(s - h + 2 * h * k / (kSmoothingSamples - 1));
    }
    return sum / kSmoothingSamples;
  }

private:
  std::vector<Eigen::Vector3d> points;
  std::vector<double> at;
};

double SmoothStep(double x)
{
  x = std::clamp(x, 0.0, 1.0);
  return x * x * (3 - 2 * x);
}

/// The radius at arc length s as a share of the belly's: the tendon's outside [start, end], rising
/// smoothly (zero slope at both ends of the rise) over each end's taper.
double RadiusShare(double s, double start, double end, double tendonRatio)
{
  const double taper = kTaperShare * (end - start);
  const double rise = SmoothStep((s - start) / taper) * SmoothStep((end - s) / taper);
  return tendonRatio + (1 - tendonRatio) * rise;
}

/// A unit vector perpendicular to `t`.
Eigen::Vector3d AnyPerpendicular(const Eigen::Vector3d& t)
{
  const Eigen::Vector3d axis = std::abs(t.x()) < 0.9 ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitY();
  return t.cross(axis).normalized();
}

void CheckInput(const Points& path, const MuscleProperties& muscle, const MuscleFromPathParameters& parameters)
{
  if (path.rows() < 2)
  {
    throw InputError("the path has " + std::to_string(path.rows()) + " points: it needs at least 2");
  }
  if (!AllFinite(path))
  {
    throw InputError("the path has a coordinate that is not a finite number");
  }
  if (!(parameters.numberOfPoints >= kLeastRings * kLeastRingPoints + 2))
  {
    throw InputError("the surface needs at least " + std::to_string(kLeastRings * kLeastRingPoints + 2) +
      " points (asked: " + std::to_string(parameters.numberOfPoints) + ")");
  }
  if (!(parameters.tendonRadiusRatio > 0 && parameters.tendonRadiusRatio <= 1))
  {
    throw InputError("the tendon's radius ratio must lie in (0, 1]");
  }
  if (!(std::isfinite(muscle.tendonSlackLength) && muscle.tendonSlackLength >= 0))
  {
    throw InputError("the muscle's tendon slack length is unknown or negative");
  }
}
}

double EstimatedMuscleVolume(const MuscleProperties& muscle, double specificTension)
{
  if (!(std::isfinite(muscle.maxIsometricForce) && muscle.maxIsometricForce > 0))
  {
    throw InputError("the muscle's max isometric force is unknown or not positive");
  }
  if (!(std::isfinite(muscle.optimalFiberLength) && muscle.optimalFiberLength > 0))
  {
    throw InputError("the muscle's optimal fibre length is unknown or not positive");
  }
  if (!(std::isfinite(specificTension) && specificTension > 0))
  {
    throw InputError("the specific tension must be a positive number");
  }
  return muscle.maxIsometricForce / specificTension * muscle.optimalFiberLength;
}

MuscleFromPathResult MuscleFromPath(const Points& path, const MuscleProperties& muscle,
  const MuscleFromPathParameters& parameters, const std::vector<const TriangleTree*>& bones)
{
  CheckInput(path, muscle, parameters);
  MuscleFromPathResult result;
  result.estimatedVolume = EstimatedMuscleVolume(muscle, parameters.specificTension);
  const ArcPolyline line(path);
  const double length = line.Length();
  if (!(length > kDegenerateShare * std::max(1.0, path.cwiseAbs().maxCoeff())))
  {
    throw InputError("the path has no length");
  }

  // The belly: the path less its tendon, the tendon shared equally by both ends.
  const double share = (length - muscle.tendonSlackLength) / length;
  const double belly = std::clamp(share, kLeastBellyShare, kMostBellyShare);
  result.bellyLimited = belly != share;
  if (result.bellyLimited)
  {
    std::ostringstream note;
    note << "the path (" << length << ") less the tendon slack length (" << muscle.tendonSlackLength << ") leaves "
         << std::max(0.0, share) * 100 << " % of it to the belly: the belly takes " << belly * 100 << " %";
    result.notes.push_back(note.str());
  }
  result.bellyStart = 0.5 * (1 - belly) * length;
  result.bellyEnd = result.bellyStart + belly * length;
  const double ratio = parameters.tendonRadiusRatio;
  const auto shareAt = [&](double s) {
    return RadiusShare(s, result.bellyStart, result.bellyEnd, ratio);
  };

  // The belly's radius for a straight tube of this profile: volume = pi r^2 * integral of share^2.
  constexpr int kIntegrationSteps = 4096;
  double integral = 0;
  for (int k = 0; k < kIntegrationSteps; ++k)
  {
    const double share = shareAt(length * (k + 0.5) / kIntegrationSteps);
    integral += share * share * length / kIntegrationSteps;
  }
  const double radius = std::sqrt(result.estimatedVolume / (M_PI * integral));

  // Rings of equal spacing, their points about as far apart round the belly as along the path.
  const int inner = parameters.numberOfPoints - 2;
  const int ringPoints = std::clamp(static_cast<int>(std::lround(std::sqrt(inner * 2 * M_PI * radius / length))),
    kLeastRingPoints, inner / kLeastRings);
  const int rings = inner / ringPoints;

  // Each ring's centre on the path smoothed over the local radius, and a frame carried along it.
  std::vector<Eigen::Vector3d> centres(static_cast<size_t>(rings)), normals(centres.size()), binormals(centres.size());
  std::vector<double> shares(centres.size());
  const double spacing = length / (rings - 1);
  for (int k = 0; k < rings; ++k)
  {
    const double s = spacing * k;
    shares[k] = shareAt(s);
    centres[k] = line.SmoothedAt(s, kSmoothingRadii * radius * shares[k]);
  }
  Eigen::Vector3d previousTangent = (line.At(spacing) - line.At(0)).normalized(), normal;
  for (int k = 0; k < rings; ++k)
  {
    const double s = spacing * k, h = 0.5 * spacing;
    const Eigen::Vector3d ahead =
      line.SmoothedAt(std::min(length, s + h), kSmoothingRadii * radius * shareAt(std::min(length, s + h)));
    const Eigen::Vector3d behind =
      line.SmoothedAt(std::max(0.0, s - h), kSmoothingRadii * radius * shareAt(std::max(0.0, s - h)));
    Eigen::Vector3d tangent = ahead - behind;
    tangent = tangent.norm() > kDegenerateShare * length ? tangent.normalized() : previousTangent;
    normal = k == 0 ? AnyPerpendicular(tangent) : Eigen::Vector3d(normal - normal.dot(tangent) * tangent);
    normal = normal.norm() > 1e-6 ? normal.normalized() : AnyPerpendicular(tangent);
    normals[k] = normal;
    binormals[k] = tangent.cross(normal);
    previousTangent = tangent;
  }

  // The triangles: quads between neighbouring rings, a fan at each end.
  const Eigen::Index first = static_cast<Eigen::Index>(rings) * ringPoints, last = first + 1;
  const auto id = [&](int ring, int j) {
    return static_cast<std::int64_t>(ring) * ringPoints + (j % ringPoints);
  };
  Triangles triangles(2 * (rings - 1) * ringPoints + 2 * ringPoints, 3);
  Eigen::Index t = 0;
  for (int k = 0; k + 1 < rings; ++k)
  {
    for (int j = 0; j < ringPoints; ++j)
    {
      triangles.row(t++) << id(k, j), id(k, j + 1), id(k + 1, j + 1);
      triangles.row(t++) << id(k, j), id(k + 1, j + 1), id(k + 1, j);
    }
  }
  for (int j = 0; j < ringPoints; ++j)
  {
    triangles.row(t++) << first, id(0, j + 1), id(0, j);
    triangles.row(t++) << last, id(rings - 1, j), id(rings - 1, j + 1);
  }

  // Each point's direction from its ring's centre, and how far it may go before a bone.
  std::vector<Eigen::Vector3d> directions(static_cast<size_t>(first));
  std::vector<double> reach(directions.size(), std::numeric_limits<double>::infinity());
  for (int k = 0; k < rings; ++k)
  {
    const double local = radius * shares[k];
    for (int j = 0; j < ringPoints; ++j)
    {
      const double angle = 2 * M_PI * j / ringPoints;
      const auto i = static_cast<size_t>(id(k, j));
      directions[i] = std::cos(angle) * normals[k] + std::sin(angle) * binormals[k];
      const double farthest = kMostRadiusScale * local;
      for (const TriangleTree* bone : bones)
      {
        if (const auto hit = bone->FirstEntry(centres[k], centres[k] + farthest * directions[i]))
        {
          reach[i] =
            std::min(reach[i], std::max(hit->t * farthest - kBoneClearanceShare * local, kLeastRadiusShare * local));
        }
      }
    }
  }

  // The points at a scale of the radii (each within its reach); the scale that gives the volume.
  Points points(last + 1, 3);
  points.row(first) = line.At(0).transpose();
  points.row(last) = line.At(length).transpose();
  const auto place = [&](double scale) {
    for (int k = 0; k < rings; ++k)
    {
      for (int j = 0; j < ringPoints; ++j)
      {
        const auto i = static_cast<size_t>(id(k, j));
        points.row(id(k, j)) =
          (centres[k] + std::min(scale * radius * shares[k], reach[i]) * directions[i]).transpose();
      }
    }
    return SignedVolume(points, triangles);
  };
  double scale = 1, volume = place(scale);
  if (volume < 0)
  {
    triangles.col(1).swap(triangles.col(2));
    volume = -volume;
  }
  const auto off = [&] {
    return std::abs(volume / result.estimatedVolume - 1) > kVolumeTolerance;
  };
  for (int round = 0; round < kVolumeRounds && off(); ++round)
  {
    scale = std::min(kMostRadiusScale, scale * std::sqrt(result.estimatedVolume / volume));
    volume = place(scale);
  }
  // Where bones hold points, the volume grows slower than the scale squared: halve the bracket
  // (the volume rises with the scale), unless even the largest scale falls short.
  double low = 0, high = kMostRadiusScale;
  for (int round = 0; round < kVolumeRounds && off() && !(scale == kMostRadiusScale && volume < result.estimatedVolume);
       ++round)
  {
    (volume < result.estimatedVolume ? low : high) = scale;
    scale = 0.5 * (low + high);
    volume = place(scale);
  }
  if (volume < result.estimatedVolume * (1 - 1e-6))
  {
    std::ostringstream note;
    note << "the bones leave room for " << 100 * volume / result.estimatedVolume
         << " % of the estimated volume at three times the radii";
    result.notes.push_back(note.str());
  }
  for (size_t i = 0; i < reach.size(); ++i)
  {
    const int ring = static_cast<int>(i) / ringPoints;
    result.pointsHeldByBones += reach[i] < scale * radius * shares[static_cast<size_t>(ring)];
  }
  result.surface = { points, triangles };
  result.volume = volume;
  result.volumeKept = volume / result.estimatedVolume;
  result.bellyRadius = scale * radius;
  result.tendonRadius = scale * radius * ratio;
  return result;
}
}
