// SPDX-License-Identifier: BSD-3-Clause
#include "OpenSim/MomentArms.h"

#include <algorithm>
#include <cmath>
#include <iterator>
#include <vector>

namespace md::osim
{
namespace
{
/// The path points a path has (its points over wrap objects aside: how many there are follows
/// the length over the surface).
std::vector<int> ActivePathPoints(const PathGeometry& g)
{
  std::vector<int> active;
  std::copy_if(g.pointIndex.begin(), g.pointIndex.end(), std::back_inserter(active), [](int k) { return k >= 0; });
  return active;
}

/// -dL/dq from the path at q and at q -+ step: central, or one-sided where the active path
/// points differ from those at q on one side.
double Excursion(const PathGeometry& here, const PathGeometry& low, const PathGeometry& high, double step)
{
  const std::vector<int> active = ActivePathPoints(here);
  const bool lowSame = ActivePathPoints(low) == active, highSame = ActivePathPoints(high) == active;
  if (lowSame == highSame) // the usual case; both differ only for a step wider than a range
  {
    return -(high.length - low.length) / (2.0 * step);
  }
  return highSame ? -(high.length - here.length) / step : -(here.length - low.length) / step;
}
}

std::vector<double> MovedCoordinate(const Model& model, std::vector<double> coordinates, int coordinate, double delta)
{
  coordinates[coordinate] += delta;
  const bool dependent = std::any_of(model.couplers.begin(), model.couplers.end(),
    [coordinate](const CoordinateCoupler& c) { return c.dependent == coordinate; });
  if (!dependent)
  {
    ApplyCouplers(model, coordinates);
  }
  return coordinates;
}

double PathLength(const Model& model, const Path& path, const std::vector<double>& coordinates)
{
  return PathAt(model, path, coordinates, BodyPoses(model, coordinates)).length;
}

double MomentArm(
  const Model& model, const Path& path, const std::vector<double>& coordinates, int coordinate, double step)
{
  const std::vector<double> below = MovedCoordinate(model, coordinates, coordinate, -step);
  const std::vector<double> above = MovedCoordinate(model, coordinates, coordinate, step);
  return Excursion(PathAt(model, path, coordinates, BodyPoses(model, coordinates)),
    PathAt(model, path, below, BodyPoses(model, below)), PathAt(model, path, above, BodyPoses(model, above)), step);
}

std::vector<int> MovingCoordinates(const CoordinateTrajectory& trajectory)
{
  std::vector<int> moving;
  if (trajectory.frames.empty())
  {
    return moving;
  }
  const std::vector<double>& first = trajectory.frames.front();
  for (size_t c = 0; c < first.size(); ++c)
  {
    const double tolerance = 1e-12 * std::max(1.0, std::abs(first[c]));
    if (std::any_of(trajectory.frames.begin(), trajectory.frames.end(),
          [&](const std::vector<double>& frame) { return std::abs(frame[c] - first[c]) > tolerance; }))
    {
      moving.push_back(static_cast<int>(c));
    }
  }
  return moving;
}

PathMoments MomentsAt(const Model& model, const std::vector<double>& pose, const std::vector<int>& coordinates)
{
  PathMoments moments;
  const std::vector<RigidTransform> poses = BodyPoses(model, pose);
  std::vector<PathGeometry> here;
  for (const Path& path : model.paths)
  {
    here.push_back(PathAt(model, path, pose, poses));
    moments.length.push_back(here.back().length);
  }
  moments.momentArm.assign(model.paths.size(), std::vector<double>(coordinates.size()));
  for (size_t k = 0; k < coordinates.size(); ++k)
  {
    const std::vector<double> below = MovedCoordinate(model, pose, coordinates[k], -kMomentArmStep);
    const std::vector<double> above = MovedCoordinate(model, pose, coordinates[k], kMomentArmStep);
    const std::vector<RigidTransform> belowPoses = BodyPoses(model, below), abovePoses = BodyPoses(model, above);
    for (size_t p = 0; p < model.paths.size(); ++p)
    {
      const Path& path = model.paths[p];
      moments.momentArm[p][k] = Excursion(
        here[p], PathAt(model, path, below, belowPoses), PathAt(model, path, above, abovePoses), kMomentArmStep);
    }
  }
  return moments;
}

std::vector<PathMoments> MomentsAt(
  const Model& model, const std::vector<std::vector<double>>& poses, const std::vector<int>& coordinates)
{
  std::vector<PathMoments> moments(poses.size());
  const auto count = static_cast<int>(poses.size());
#pragma omp parallel for schedule(dynamic, 4)
  for (int k = 0; k < count; ++k)
  {
    moments[static_cast<size_t>(k)] = MomentsAt(model, poses[static_cast<size_t>(k)], coordinates);
  }
  return moments;
}
}
