// SPDX-License-Identifier: BSD-3-Clause
#include "Anatomy/MuscleFromPath.h"

#include "Geometry/MeshChecks.h"
#include "Geometry/Polyline.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
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
/// Against the bones and the other muscles: how far a point stops short of one and how near the
/// centre it may be drawn, as shares of the local radius, and how far the other points may widen
/// to keep the volume.
constexpr double kClearanceShare = 0.02;
constexpr double kLeastRadiusShare = 0.1;
constexpr double kMostRadiusScale = 3.0;
/// A held point stays this many times as far from its ring's centre as the path near the ring.
constexpr double kPathMargin = 1.5;
/// A ray is followed out of its tube's cell in steps of the local radius over this, then the step
/// halved this many times (to a 1/2048 of the radius).
constexpr double kCellSteps = 8;
constexpr int kCellHalvings = 8;

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

namespace
{
/// A muscle's tube before its radii are scaled to its volume: rings round the smoothed path,
/// each point's direction from its ring's centre and how far it may go (its reach).
struct Tube
{
  MuscleFromPathResult result; ///< the estimate, the belly, the notes so far
  double radius = 0;           ///< the belly's radius before scaling
  int rings = 0, ringPoints = 0;
  std::vector<Eigen::Vector3d> centres, normals, binormals;
  std::vector<double> shares; ///< each ring's radius as a share of `radius`
  /// How near its ring's centre a point may be drawn: a tenth of the local radius, and far enough
  /// that the ring's chords pass outside the path near the ring (which the smoothing moved off the
  /// centre), so that the path stays in.
  std::vector<double> floors;
  std::vector<Eigen::Vector3d> directions;
  std::vector<double> reach; ///< per point; infinity where nothing is in the way
  std::vector<char> heldByBone, heldByMuscle;
  Triangles triangles;
  Eigen::Vector3d start, end; ///< the path's first and last points: the caps' centres
  Eigen::Vector3d low, high;  ///< a box round every point the tube can reach

  Eigen::Index Id(int ring, int j) const
  {
    return static_cast<Eigen::Index>(ring) * this->ringPoints + (j % this->ringPoints);
  }
  /// The local radius (before scaling) of ring k.
  double Local(size_t k) const { return this->radius * this->shares[k]; }
};

Tube MakeTube(const Points& path, const MuscleProperties& muscle, const MuscleFromPathParameters& parameters)
{
  CheckInput(path, muscle, parameters);
  Tube tube;
  MuscleFromPathResult& result = tube.result;
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
    const double at = shareAt(length * (k + 0.5) / kIntegrationSteps);
    integral += at * at * length / kIntegrationSteps;
  }
  tube.radius = std::sqrt(result.estimatedVolume / (M_PI * integral));
  const double radius = tube.radius;

  // Rings of equal spacing, their points about as far apart round the belly as along the path.
  const int inner = parameters.numberOfPoints - 2;
  tube.ringPoints = std::clamp(static_cast<int>(std::lround(std::sqrt(inner * 2 * M_PI * radius / length))),
    kLeastRingPoints, inner / kLeastRings);
  tube.rings = inner / tube.ringPoints;
  const int rings = tube.rings, ringPoints = tube.ringPoints;

  // Each ring's centre on the path smoothed over the local radius, and a frame carried along it.
  const auto count = static_cast<size_t>(rings);
  tube.centres.resize(count);
  tube.normals.resize(count);
  tube.binormals.resize(count);
  tube.shares.resize(count);
  const double spacing = length / (rings - 1);
  for (size_t k = 0; k < count; ++k)
  {
    const double s = spacing * static_cast<double>(k);
    tube.shares[k] = shareAt(s);
    tube.centres[k] = line.SmoothedAt(s, kSmoothingRadii * radius * tube.shares[k]);
  }
  Eigen::Vector3d previousTangent = (line.At(spacing) - line.At(0)).normalized(), normal;
  for (size_t k = 0; k < count; ++k)
  {
    const double s = spacing * static_cast<double>(k), h = 0.5 * spacing;
    const double ahead = std::min(length, s + h), behind = std::max(0.0, s - h);
    Eigen::Vector3d tangent = line.SmoothedAt(ahead, kSmoothingRadii * radius * shareAt(ahead)) -
      line.SmoothedAt(behind, kSmoothingRadii * radius * shareAt(behind));
    tangent = tangent.norm() > kDegenerateShare * length ? tangent.normalized() : previousTangent;
    normal = k == 0 ? AnyPerpendicular(tangent) : Eigen::Vector3d(normal - normal.dot(tangent) * tangent);
    normal = normal.norm() > 1e-6 ? normal.normalized() : AnyPerpendicular(tangent);
    tube.normals[k] = normal;
    tube.binormals[k] = tangent.cross(normal);
    previousTangent = tangent;
  }

  // The triangles: quads between neighbouring rings, a fan at each end.
  const Eigen::Index first = static_cast<Eigen::Index>(rings) * ringPoints, last = first + 1;
  tube.triangles.resize(2 * (rings - 1) * ringPoints + 2 * ringPoints, 3);
  Eigen::Index t = 0;
  for (int k = 0; k + 1 < rings; ++k)
  {
    for (int j = 0; j < ringPoints; ++j)
    {
      tube.triangles.row(t++) << tube.Id(k, j), tube.Id(k, j + 1), tube.Id(k + 1, j + 1);
      tube.triangles.row(t++) << tube.Id(k, j), tube.Id(k + 1, j + 1), tube.Id(k + 1, j);
    }
  }
  for (int j = 0; j < ringPoints; ++j)
  {
    tube.triangles.row(t++) << first, tube.Id(0, j + 1), tube.Id(0, j);
    tube.triangles.row(t++) << last, tube.Id(rings - 1, j), tube.Id(rings - 1, j + 1);
  }
  tube.start = line.At(0);
  tube.end = line.At(length);
  tube.floors.resize(count);
  for (size_t k = 0; k < count; ++k)
  {
    const Eigen::Vector3d tangent = tube.normals[k].cross(tube.binormals[k]);
    double offset = 0;
    for (int sample = -kSmoothingSamples / 2; sample <= kSmoothingSamples / 2; ++sample)
    {
      const Eigen::Vector3d v =
        line.At(spacing * (static_cast<double>(k) + 2.0 * static_cast<double>(sample) / kSmoothingSamples)) -
        tube.centres[k];
      offset = std::max(offset, (v - v.dot(tangent) * tangent).norm());
    }
    // A chord between two of the ring's points lies cos(pi / ringPoints) as far out as they do,
    // and between two rings that turn at a corner the surface passes inside both: half as much
    // again.
    tube.floors[k] = std::max(kLeastRadiusShare * tube.Local(k),
      (kPathMargin * offset + kClearanceShare * tube.Local(k)) / std::cos(M_PI / ringPoints));
  }

  // Each point's direction; nothing in its way yet.
  tube.directions.resize(static_cast<size_t>(first));
  for (int k = 0; k < rings; ++k)
  {
    for (int j = 0; j < ringPoints; ++j)
    {
      const double angle = 2 * M_PI * j / ringPoints;
      tube.directions[static_cast<size_t>(tube.Id(k, j))] = std::cos(angle) * tube.normals[static_cast<size_t>(k)] +
        std::sin(angle) * tube.binormals[static_cast<size_t>(k)];
    }
  }
  tube.reach.assign(tube.directions.size(), std::numeric_limits<double>::infinity());
  tube.heldByBone.assign(tube.directions.size(), 0);
  tube.heldByMuscle.assign(tube.directions.size(), 0);
  tube.low = tube.high = tube.centres[0];
  for (size_t k = 0; k < count; ++k)
  {
    const Eigen::Vector3d grow = Eigen::Vector3d::Constant(kMostRadiusScale * tube.Local(k));
    tube.low = tube.low.cwiseMin(tube.centres[k] - grow);
    tube.high = tube.high.cwiseMax(tube.centres[k] + grow);
  }
  return tube;
}

/// Each point of `tube` stops short of the first bone its ray enters.
void HoldOffBones(Tube& tube, const std::vector<const TriangleTree*>& bones)
{
  for (int k = 0; k < tube.rings; ++k)
  {
    const double local = tube.Local(static_cast<size_t>(k));
    const Eigen::Vector3d& centre = tube.centres[static_cast<size_t>(k)];
    for (int j = 0; j < tube.ringPoints; ++j)
    {
      const auto i = static_cast<size_t>(tube.Id(k, j));
      const double farthest = kMostRadiusScale * local;
      for (const TriangleTree* bone : bones)
      {
        if (const auto hit = bone->FirstEntry(centre, centre + farthest * tube.directions[i]))
        {
          const double limit =
            std::max(hit->t * farthest - kClearanceShare * local, tube.floors[static_cast<size_t>(k)]);
          if (limit < tube.reach[i])
          {
            tube.reach[i] = limit;
            tube.heldByBone[i] = 1;
          }
        }
      }
    }
  }
}

/// The distance from x to the segment of `other`'s centre line from ring k to ring k + 1.
double DistanceToSegment(const Eigen::Vector3d& x, const Tube& other, size_t k)
{
  const Eigen::Vector3d &a = other.centres[k], &b = other.centres[k + 1];
  return (a + SegmentFoot(x, a, b) * (b - a) - x).norm();
}

/// The distance from x to a neighbour's centre line, over its segments `near` (k: ring k to k+1).
double DistanceToCentreLine(const Tube& other, const std::vector<int>& near, const Eigen::Vector3d& x)
{
  double least = std::numeric_limits<double>::infinity();
  for (const int k : near)
  {
    least = std::min(least, DistanceToSegment(x, other, static_cast<size_t>(k)));
  }
  return least;
}

/// Each point of `tube` stops where its ray leaves the tube's share of the space it shares with
/// `others`: the points nearer its own centre line than any other's (a Voronoi diagram of the
/// centre lines; a point's distance to its own taken as its distance from its ring's centre,
/// which is never less, so that the cell is if anything smaller). The cells of two tubes do not
/// overlap, so their points stay apart whatever each widens to, and each centre line, hence each
/// path, keeps its own cell: only where paths cross do they meet.
void HoldOffNeighbours(Tube& tube, const std::vector<const Tube*>& others)
{
  for (int k = 0; k < tube.rings; ++k)
  {
    const auto ring = static_cast<size_t>(k);
    const double local = tube.Local(ring), farthest = kMostRadiusScale * local;
    const Eigen::Vector3d& centre = tube.centres[ring];
    // The neighbours' segments that can come within this ring's reach.
    std::vector<std::pair<const Tube*, std::vector<int>>> near;
    for (const Tube* other : others)
    {
      if (((centre.array() + farthest) < other->low.array()).any() ||
        ((centre.array() - farthest) > other->high.array()).any())
      {
        continue;
      }
      std::vector<int> segments;
      for (int s = 0; s + 1 < other->rings; ++s)
      {
        if (DistanceToSegment(centre, *other, static_cast<size_t>(s)) < 2 * farthest)
        {
          segments.push_back(s);
        }
      }
      if (!segments.empty())
      {
        near.emplace_back(other, std::move(segments));
      }
    }
    // At t along the ray, the cell's edge where a neighbour's centre line is nearer than t.
    const auto margin = [&](const Eigen::Vector3d& x, double t) {
      double least = std::numeric_limits<double>::infinity();
      for (const auto& [other, segments] : near)
      {
        least = std::min(least, DistanceToCentreLine(*other, segments, x));
      }
      return least - t; // > 0: x is in this tube's cell
    };
    if (near.empty() || margin(centre, 0) <= 0)
    {
      continue;
    }
    for (int j = 0; j < tube.ringPoints; ++j)
    {
      const auto i = static_cast<size_t>(tube.Id(k, j));
      const Eigen::Vector3d& direction = tube.directions[i];
      const double reach = std::min(tube.reach[i], farthest);
      // March out to the first step outside the cell, then halve the step.
      const double step = local / kCellSteps;
      double inner = 0, outer = -1;
      for (double t = step; t <= reach + 0.5 * step; t += step)
      {
        if (margin(centre + std::min(t, reach) * direction, std::min(t, reach)) <= 0)
        {
          outer = std::min(t, reach);
          break;
        }
        inner = std::min(t, reach);
      }
      if (outer < 0)
      {
        continue; // the cell reaches as far as the point may go
      }
      for (int halving = 0; halving < kCellHalvings; ++halving)
      {
        const double mid = 0.5 * (inner + outer);
        (margin(centre + mid * direction, mid) > 0 ? inner : outer) = mid;
      }
      const double limit = std::max(inner - kClearanceShare * local, tube.floors[ring]);
      if (limit < tube.reach[i])
      {
        tube.reach[i] = limit;
        tube.heldByMuscle[i] = 1;
      }
    }
  }
}

/// The surface of `tube` with its radii scaled (each within its reach) to the estimated volume.
MuscleFromPathResult Finish(Tube& tube)
{
  MuscleFromPathResult result = tube.result;
  const Eigen::Index first = static_cast<Eigen::Index>(tube.rings) * tube.ringPoints, last = first + 1;
  Points points(last + 1, 3);
  points.row(first) = tube.start.transpose();
  points.row(last) = tube.end.transpose();
  const auto place = [&](double scale) {
    for (int k = 0; k < tube.rings; ++k)
    {
      const double local = tube.Local(static_cast<size_t>(k));
      for (int j = 0; j < tube.ringPoints; ++j)
      {
        const auto i = static_cast<size_t>(tube.Id(k, j));
        points.row(tube.Id(k, j)) =
          (tube.centres[static_cast<size_t>(k)] + std::min(scale * local, tube.reach[i]) * tube.directions[i])
            .transpose();
      }
    }
    return SignedVolume(points, tube.triangles);
  };
  double scale = 1, volume = place(scale);
  if (volume < 0)
  {
    tube.triangles.col(1).swap(tube.triangles.col(2));
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
  // Where points are held, the volume grows slower than the scale squared: halve the bracket
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
    note << "the bones and the other muscles leave room for " << 100 * volume / result.estimatedVolume
         << " % of the estimated volume at three times the radii";
    result.notes.push_back(note.str());
  }
  for (size_t i = 0; i < tube.reach.size(); ++i)
  {
    const bool held = tube.reach[i] < scale * tube.Local(i / static_cast<size_t>(tube.ringPoints));
    result.pointsHeldByBones += held && tube.heldByBone[i] && !tube.heldByMuscle[i];
    result.pointsHeldByMuscles += held && tube.heldByMuscle[i];
  }
  result.surface = { points, tube.triangles };
  result.volume = volume;
  result.volumeKept = volume / result.estimatedVolume;
  result.bellyRadius = scale * tube.radius;
  result.tendonRadius = scale * tube.radius * tube.shares.front();
  return result;
}
}

MuscleFromPathResult MuscleFromPath(const Points& path, const MuscleProperties& muscle,
  const MuscleFromPathParameters& parameters, const std::vector<const TriangleTree*>& bones)
{
  Tube tube = MakeTube(path, muscle, parameters);
  HoldOffBones(tube, bones);
  return Finish(tube);
}

std::vector<MuscleFromPathResult> MusclesFromPaths(const std::vector<Points>& paths,
  const std::vector<MuscleProperties>& muscles, const MuscleFromPathParameters& parameters,
  const std::vector<const TriangleTree*>& bones, std::vector<std::string>& failures)
{
  if (muscles.size() != paths.size())
  {
    throw InputError("there are " + std::to_string(paths.size()) + " paths and " + std::to_string(muscles.size()) +
      " muscles' properties: one each");
  }
  failures.assign(paths.size(), std::string());
  std::vector<std::optional<Tube>> tubes(paths.size());
  for (size_t m = 0; m < paths.size(); ++m)
  {
    try
    {
      tubes[m] = MakeTube(paths[m], muscles[m], parameters);
    }
    catch (const InputError& e)
    {
      failures[m] = e.what(); // the others go on
    }
  }
  std::vector<MuscleFromPathResult> results(paths.size());
#pragma omp parallel for schedule(dynamic)
  for (std::ptrdiff_t m = 0; m < static_cast<std::ptrdiff_t>(paths.size()); ++m)
  {
    auto& tube = tubes[static_cast<size_t>(m)];
    if (!tube)
    {
      continue;
    }
    HoldOffBones(*tube, bones);
    if (!parameters.keepMusclesApart)
    {
      continue;
    }
    std::vector<const Tube*> others;
    for (size_t o = 0; o < tubes.size(); ++o)
    {
      if (o != static_cast<size_t>(m) && tubes[o])
      {
        others.push_back(&*tubes[o]);
      }
    }
    HoldOffNeighbours(*tube, others);
  }
  for (size_t m = 0; m < paths.size(); ++m)
  {
    if (tubes[m])
    {
      results[m] = Finish(*tubes[m]);
    }
  }
  return results;
}
}
