// SPDX-License-Identifier: BSD-3-Clause
// Interpolation of a body between its rest pose and its current pose
// (Hajkova & Kohout, sec. 4.1, eq. 1; and a rigid mode beyond the paper).
#pragma once

#include "Common/MeshTypes.h"
#include "Geometry/RigidMotion.h"

#include <optional>
#include <string>
#include <vector>

namespace md
{
enum class InterpolationMode
{
  Linear = 0, ///< x_i(s) = (1 - s) rp_i + s cp_i: the paper's eq. 1
  Rigid = 1,  ///< screw motion of the fitted rigid transform (keeps the bone congruent)
};

/// The defaults of an interpolation from one pose to the next (the method's and the filters').
constexpr int kDefaultNumberOfSteps = 4;
constexpr double kDefaultMaximumStepDisplacement = 20; ///< data units, when the number of steps is automatic
constexpr InterpolationMode kDefaultInterpolationMode = InterpolationMode::Rigid;

/// Largest |cp_i - rp_i|.
double MaximumDisplacement(const Points& rest, const Points& current);

/// Steps needed so that no point moves more than maximumStepDisplacement in one
/// step: ceil(maximumDisplacement / maximumStepDisplacement), at least 1.
int AutomaticNumberOfSteps(double maximumDisplacement, double maximumStepDisplacement);

/// A fit residual above this share of a body's size makes its motion not rigid (a warning):
/// well above the rounding of scanned or OpenSim-moved bones, well below a visible deformation.
constexpr double kNonRigidShare = 1e-3;

class PoseInterpolator
{
public:
  /// rest and current must have the same number of points (InputError otherwise).
  PoseInterpolator(const Points& rest, const Points& current, InterpolationMode mode);

  /// Positions at step `step` of `numberOfSteps`: step 0 is the rest pose and
  /// step numberOfSteps the current pose, both exactly.
  Points AtStep(int step, int numberOfSteps) const;
  /// Positions at fraction s in [0, 1] of the way.
  Points AtFraction(double s) const;

  /// The least-squares rigid fit of the RP -> CP motion (computed in Rigid mode only).
  const std::optional<RigidFit>& Fit() const { return this->Fit_; }
  /// Rotation angle of the fitted motion (Rigid mode), in radians.
  double RotationAngle() const;
  /// In Rigid mode, when the best rigid fit misses the current pose by more than
  /// kNonRigidShare of the body's size (its bounding-box diagonal at rest): the warning that says
  /// so, naming the body `name`. Empty otherwise.
  std::string NonRigidWarning(const std::string& name) const;

private:
  Points Rest;
  Points Current;
  InterpolationMode Mode_;
  std::optional<RigidFit> Fit_;
  std::optional<ScrewInterpolation> Screw;
  Points Residual; // CP minus the fitted rigid motion of the RP, blended in linearly
};

/// One PoseInterpolator per pair rest[k] -> current[k], built in parallel (each fits a rigid
/// motion to all the points of a bone). Throws the first pair's InputError.
std::vector<PoseInterpolator> PoseInterpolators(
  const std::vector<Points>& rest, const std::vector<Points>& current, InterpolationMode mode);
}
