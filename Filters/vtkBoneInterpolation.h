// SPDX-License-Identifier: BSD-3-Clause
/**
 * @class   vtkBoneInterpolation
 * @brief   Geometry at an intermediate step between its rest and current pose.
 *
 * Hajkova & Kohout, "Interpolation Method for Muscle Deformation", sec. 4.1:
 * the motion from the rest pose (RP, input port 0) to the current pose (CP,
 * input port 1, same points in the same order) is split into NumberOfSteps
 * steps. The output advertises time steps 0, 1, ..., N: time j is step j,
 * 0 being the RP and N the CP, both reproduced exactly.
 *
 * InterpolationMode Linear is the paper's eq. 1, x(j) = rp + j (cp - rp) / N.
 * It shortens a rotating bone at the intermediate steps (by 1 - cos(angle/4),
 * 13 % at the middle of a 60 degree rotation for points far from the axis).
 * Rigid fits the RP -> CP rigid motion (Kabsch) and moves the body along the
 * screw motion of that fit: the rotation by quaternion slerp about the screw
 * axis, the slide along it linearly, so every intermediate bone is congruent
 * to the RP and a rotation about a joint keeps the joint centre in place. What
 * the fit does not explain (a non-rigid CP) is blended in linearly; its size
 * is reported in field data and a warning is given when it exceeds 0.1 % of
 * the body's size.
 *
 * Works on bones and on matched action lines (port 0 of vtkActionLineMatching:
 * when CurrentPose is not connected, the point array CurrentPosition is used).
 * Inputs are vtkPolyData or vtkMultiBlockDataSet (blocks paired by name, else
 * by order); all blocks share one number of steps.
 */
#pragma once

#include "MuscleDeformationFiltersModule.h"

#include <vtkPassInputTypeAlgorithm.h>

#include <set>
#include <string>

class MUSCLEDEFORMATIONFILTERS_EXPORT vtkBoneInterpolation : public vtkPassInputTypeAlgorithm
{
public:
  static vtkBoneInterpolation* New();
  vtkTypeMacro(vtkBoneInterpolation, vtkPassInputTypeAlgorithm);
  void PrintSelf(ostream& os, vtkIndent indent) override;

  enum InterpolationModes
  {
    LINEAR = 0,
    RIGID = 1
  };

  /// Number of steps N from the RP to the CP; 0 chooses it automatically so
  /// that no point moves more than MaximumStepDisplacement in one step.
  /// Default 4.
  vtkSetClampMacro(NumberOfSteps, int, 0, 10000);
  vtkGetMacro(NumberOfSteps, int);

  /// Largest displacement of a point in one step when NumberOfSteps is 0, in
  /// the units of the data. Default 20.
  vtkSetClampMacro(MaximumStepDisplacement, double, 1e-9, VTK_DOUBLE_MAX);
  vtkGetMacro(MaximumStepDisplacement, double);

  /// LINEAR (the paper's eq. 1) or RIGID (default).
  vtkSetClampMacro(InterpolationMode, int, LINEAR, RIGID);
  vtkGetMacro(InterpolationMode, int);

  /// The step N actually used (valid after UpdateInformation).
  vtkGetMacro(ResolvedNumberOfSteps, int);

  void SetCurrentPoseConnection(vtkAlgorithmOutput* output) { this->SetInputConnection(1, output); }

protected:
  vtkBoneInterpolation();
  ~vtkBoneInterpolation() override = default;

  int FillInputPortInformation(int port, vtkInformation* info) override;
  int RequestInformation(vtkInformation*, vtkInformationVector**, vtkInformationVector*) override;
  int RequestUpdateExtent(vtkInformation*, vtkInformationVector**, vtkInformationVector*) override;
  int RequestData(vtkInformation*, vtkInformationVector**, vtkInformationVector*) override;

  // The core's defaults (md::kDefault...), set by the constructor.
  int NumberOfSteps;
  double MaximumStepDisplacement;
  int InterpolationMode;
  int ResolvedNumberOfSteps = 1;

private:
  vtkBoneInterpolation(const vtkBoneInterpolation&) = delete;
  void operator=(const vtkBoneInterpolation&) = delete;

  struct Pose;
  /// Pairs the RP and CP blocks and reads their points; false after an error.
  bool ReadPoses(vtkDataObject* rest, vtkDataObject* current, std::vector<Pose>& poses);

  /// The warnings said since the inputs or properties last changed (at `WarningsSaidFor`): a
  /// warning of the inputs is said once, not at every step an animation asks for.
  std::set<std::string> WarningsSaid;
  vtkMTimeType WarningsSaidFor = 0;
};
