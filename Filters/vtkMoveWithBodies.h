// SPDX-License-Identifier: BSD-3-Clause
/**
 * @class   vtkMoveWithBodies
 * @brief   Moves surfaces (scanned bones) with the bodies of an OpenSim model.
 *
 * Input 0: surfaces in the rest pose (a vtkPolyData or a multiblock of them), in the frame and
 * units of the OpenSimModelReader's outputs. Input 1 (BodyTransforms): the reader's
 * BodyTransforms table. Each surface moves with one body: the one BodyOfSurface names for it
 * ("iliac_r=pelvis; sacrum=pelvis"), else the body of its name ("femur_r.vtk" -> femur_r), else
 * an error naming the surface and the bodies. The output is the surfaces at the reader's current
 * time, with field data Body. Where the table has rows of stepped poses (the reader's
 * MomentArmStep: column Pose), each surface also gets its points at each of them as a point
 * array PointsAt(<pose>).
 */
#pragma once

#include "MuscleDeformationFiltersModule.h"

#include <vtkPassInputTypeAlgorithm.h>

#include <memory>

namespace mdvtk
{
class InputCheck;
}

class MUSCLEDEFORMATIONFILTERS_EXPORT vtkMoveWithBodies : public vtkPassInputTypeAlgorithm
{
public:
  static vtkMoveWithBodies* New();
  vtkTypeMacro(vtkMoveWithBodies, vtkPassInputTypeAlgorithm);
  void PrintSelf(ostream& os, vtkIndent indent) override;

  void SetBodyTransformsConnection(vtkAlgorithmOutput* output) { this->SetInputConnection(1, output); }

  /// "surface=body; surface=body": which body a surface moves with, where its name does not say.
  vtkGetStringMacro(BodyOfSurface);
  vtkSetStringMacro(BodyOfSurface);

protected:
  vtkMoveWithBodies();
  ~vtkMoveWithBodies() override;

  int FillInputPortInformation(int port, vtkInformation* info) override;
  int RequestInformation(vtkInformation*, vtkInformationVector**, vtkInformationVector*) override;
  int RequestData(vtkInformation*, vtkInformationVector**, vtkInformationVector*) override;
  int RequestUpdateExtent(vtkInformation*, vtkInformationVector**, vtkInformationVector*) override;

  char* BodyOfSurface = nullptr;
  /// The surfaces as they last passed the input checks: at every frame of a motion they are the
  /// same rest pose, not checked again.
  std::unique_ptr<mdvtk::InputCheck> InputChecked;

private:
  vtkMoveWithBodies(const vtkMoveWithBodies&) = delete;
  void operator=(const vtkMoveWithBodies&) = delete;
};
