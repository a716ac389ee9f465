// SPDX-License-Identifier: BSD-3-Clause
// Moment arms of an OpenSim model's paths by tendon excursion: r = -dL/dq.
#pragma once

#include "OpenSim/OpenSimKinematics.h"
#include "OpenSim/OpenSimMotion.h"

#include <vector>

namespace md::osim
{
/// Length of `path` at `coordinates`: the straight segments between its active points (wrap
/// objects are not followed).
double PathLength(const Model& model, const Path& path, const std::vector<double>& coordinates);

/// The step of the central difference: 1e-4 rad for a rotational coordinate, 1e-4 of the model's
/// length unit for a translational one (1e-4 for a coupled one).
constexpr double kMomentArmStep = 1e-4;

/// The moment arm of `path` about `coordinate` at `coordinates` (couplers applied), in the model's
/// length unit per radian (rotational) or per length unit (translational): r = -dL/dq, OpenSim's
/// sign (positive where lengthening q shortens the path). A central difference of +-step in q with
/// the couplers applied again (a coupled coordinate follows, as in OpenSim). Where a conditional
/// point comes or goes within the step, the difference is one-sided, on the side whose active
/// points are those at q: the moment arm of the path as it is at q, as OpenSim's is.
double MomentArm(const Model& model, const Path& path, const std::vector<double>& coordinates, int coordinate,
  double step = kMomentArmStep);

/// `coordinates` with `coordinate` moved by `delta` and the coordinates coupled to it following
/// (a coupled coordinate moves alone), as a moment arm moves them.
std::vector<double> MovedCoordinate(const Model& model, std::vector<double> coordinates, int coordinate, double delta);

/// The coordinates whose value changes over `trajectory` (by more than 1e-12 of its first value,
/// relative), in the model's order.
std::vector<int> MovingCoordinates(const CoordinateTrajectory& trajectory);

/// Every path's length and its moment arm about each of `coordinates` at one pose.
struct PathMoments
{
  std::vector<double> length;                 ///< per path
  std::vector<std::vector<double>> momentArm; ///< [path][k]: about coordinates[k]
};

PathMoments MomentsAt(const Model& model, const std::vector<double>& pose, const std::vector<int>& coordinates);

/// MomentsAt at each of `poses` (in parallel: a path over several wrap objects costs tens of
/// microseconds a pose, and a table has three poses a coordinate a frame).
std::vector<PathMoments> MomentsAt(
  const Model& model, const std::vector<std::vector<double>>& poses, const std::vector<int>& coordinates);
}
