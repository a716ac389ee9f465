// SPDX-License-Identifier: BSD-3-Clause
#include "Motion/BoneInterpolation.h"

#include <algorithm>
#include <cmath>
#include <exception>
#include <limits>
#include <sstream>

namespace md
{
double MaximumDisplacement(const Points& rest, const Points& current)
{
  if (rest.rows() == 0)
  {
    return 0;
  }
  return (current - rest).rowwise().norm().maxCoeff();
}

int AutomaticNumberOfSteps(double maximumDisplacement, double maximumStepDisplacement)
{
  if (!(maximumStepDisplacement > 0) || !std::isfinite(maximumDisplacement))
  {
    throw InputError("the maximum step displacement must be positive");
  }
  const double steps = std::ceil(maximumDisplacement / maximumStepDisplacement);
  constexpr double mostSteps = 10000; // keeps a bad unit choice from running forever
  if (steps > mostSteps)
  {
    throw InputError("the motion would need more than 10000 steps of the given maximum step "
                     "displacement; is its unit that of the data?");
  }
  return std::max(1, static_cast<int>(steps));
}

PoseInterpolator::PoseInterpolator(const Points& rest, const Points& current, InterpolationMode mode)
  : Rest(rest)
  , Current(current)
  , Mode_(mode)
{
  if (rest.rows() != current.rows())
  {
    throw InputError("the rest pose has " + std::to_string(rest.rows()) + " points but the current pose has " +
      std::to_string(current.rows()) + "; both poses must have the same points in the same order");
  }
  if (rest.rows() == 0)
  {
    throw InputError("the geometry has no points");
  }
  if (!AllFinite(rest) || !AllFinite(current))
  {
    throw InputError("the geometry has non-finite (NaN or infinite) coordinates");
  }
  if (mode == InterpolationMode::Rigid)
  {
    this->Fit_ = FitRigidTransform(rest, current);
    const Eigen::Vector3d centroid = rest.colwise().mean().transpose();
    this->Screw.emplace(this->Fit_->transform, centroid);
    this->Residual = current - this->Fit_->transform.Apply(rest);
  }
}

double PoseInterpolator::RotationAngle() const
{
  return this->Screw ? this->Screw->AngleRadians() : 0.0;
}

std::string PoseInterpolator::NonRigidWarning(const std::string& name) const
{
  if (!this->Fit_)
  {
    return {};
  }
  const double diagonal = (this->Rest.colwise().maxCoeff() - this->Rest.colwise().minCoeff()).norm();
  const double residual = this->Fit_->maxResidual;
  if (!(residual > kNonRigidShare * diagonal))
  {
    return {};
  }
  std::ostringstream message;
  message << "the motion of " << name << " is not rigid: the best rigid fit misses the current pose by up to "
          << 100.0 * residual / diagonal
          << " % of its size; Rigid mode blends that residual in linearly, Linear mode may suit this motion better";
  return message.str();
}

Points PoseInterpolator::AtStep(int step, int numberOfSteps) const
{
  if (numberOfSteps < 1)
  {
    throw InputError("the number of interpolation steps must be at least 1");
  }
  step = std::clamp(step, 0, numberOfSteps);
  return this->AtFraction(static_cast<double>(step) / numberOfSteps);
}

Points PoseInterpolator::AtFraction(double s) const
{
  s = std::clamp(s, 0.0, 1.0);
  // The end poses are returned exactly, not recomputed.
  if (s == 0.0)
  {
    return this->Rest;
  }
  if (s == 1.0)
  {
    return this->Current;
  }
  if (this->Mode_ == InterpolationMode::Linear)
  {
    return (1.0 - s) * this->Rest + s * this->Current;
  }
  return this->Screw->At(s).Apply(this->Rest) + s * this->Residual;
}

std::vector<PoseInterpolator> PoseInterpolators(
  const std::vector<Points>& rest, const std::vector<Points>& current, InterpolationMode mode)
{
  if (rest.size() != current.size())
  {
    throw InputError("the rest pose has " + std::to_string(rest.size()) + " parts but the current pose has " +
      std::to_string(current.size()));
  }
  std::vector<std::optional<PoseInterpolator>> built(rest.size());
  std::vector<std::exception_ptr> failed(rest.size()); // no exception may leave a parallel region
#pragma omp parallel for schedule(dynamic, 1)
  for (int k = 0; k < static_cast<int>(rest.size()); ++k)
  {
    try
    {
      built[k].emplace(rest[k], current[k], mode);
    }
    catch (...)
    {
      failed[k] = std::current_exception();
    }
  }
  std::vector<PoseInterpolator> interpolators;
  for (size_t k = 0; k < built.size(); ++k)
  {
    if (failed[k])
    {
      std::rethrow_exception(failed[k]);
    }
    interpolators.push_back(std::move(*built[k]));
  }
  return interpolators;
}
}
