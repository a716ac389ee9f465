// SPDX-License-Identifier: BSD-3-Clause
// A muscle's properties as a musculoskeletal model gives them (OpenSim's Muscle).
#pragma once

#include <cmath>
#include <limits>

namespace md
{
/// NaN where the model does not give a value (a path actuator that is not a muscle).
struct MuscleProperties
{
  static constexpr double kUnknown = std::numeric_limits<double>::quiet_NaN();
  double maxIsometricForce = kUnknown;  ///< N
  double optimalFiberLength = kUnknown; ///< a length (the model's unit, or the output's)
  double tendonSlackLength = kUnknown;  ///< a length, as optimalFiberLength
  double pennationAngle = kUnknown;     ///< radians, at the optimal fibre length

  bool Known() const
  {
    return std::isfinite(this->maxIsometricForce) && std::isfinite(this->optimalFiberLength) &&
      std::isfinite(this->tendonSlackLength) && std::isfinite(this->pennationAngle);
  }
};
}
