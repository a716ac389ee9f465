// SPDX-License-Identifier: BSD-3-Clause
/**
 * @class   vtkMusculoskeletalPhantom
 * @brief   A synthetic right hip in its rest and current pose.
 *
 * Made by the project itself so that demos and tests never depend on outside
 * data: a pelvis-like bone (Pelvis), a femur-like bone with a head (Femur) and
 * three muscles spanning the hip (Iliopsoas, GluteusMaximus with two bundles,
 * RectusFemoris), each with action lines from origin through via points to
 * insertion. All surfaces are closed, manifold, outward-oriented triangle
 * meshes that do not overlap in the rest pose. The current pose flexes the hip
 * by Flexion degrees about the hip centre (the origin; x lateral, y anterior,
 * z superior; millimetres at Scale 1). The Iliopsoas's pelvic via point is
 * active only below 40 degrees of flexion, so its current action line can have
 * fewer points than its rest one; at large flexion the femur sweeps into the
 * rest-pose RectusFemoris.
 *
 * Output ports (each a vtkMultiBlockDataSet of named vtkPolyData blocks):
 * 0 Muscles (rest pose), 1 BonesRest, 2 BonesCurrent, 3 ActionLinesRest,
 * 4 ActionLinesCurrent. Action lines have one block per muscle, named as the
 * muscle, holding its polylines with the cell array ActionLineName.
 */
#pragma once

#include "MuscleDeformationFiltersModule.h"

#include <vtkMultiBlockDataSetAlgorithm.h>

class MUSCLEDEFORMATIONFILTERS_EXPORT vtkMusculoskeletalPhantom : public vtkMultiBlockDataSetAlgorithm
{
public:
  static vtkMusculoskeletalPhantom* New();
  vtkTypeMacro(vtkMusculoskeletalPhantom, vtkMultiBlockDataSetAlgorithm);
  void PrintSelf(ostream& os, vtkIndent indent) override;

  enum OutputPorts
  {
    MUSCLES = 0,
    BONES_REST = 1,
    BONES_CURRENT = 2,
    ACTION_LINES_REST = 3,
    ACTION_LINES_CURRENT = 4
  };

  /// Hip flexion of the current pose, degrees. Default 60.
  vtkSetClampMacro(Flexion, double, -30.0, 120.0);
  vtkGetMacro(Flexion, double);

  /// Overall size: 1 is an adult hip in millimetres. Default 1.
  vtkSetClampMacro(Scale, double, 1e-3, 1e3);
  vtkGetMacro(Scale, double);

  /// Points around each cross-section of every surface. Default 24.
  vtkSetClampMacro(Resolution, int, 6, 256);
  vtkGetMacro(Resolution, int);

protected:
  vtkMusculoskeletalPhantom();
  ~vtkMusculoskeletalPhantom() override = default;

  int RequestData(vtkInformation*, vtkInformationVector**, vtkInformationVector*) override;

  double Flexion = 30.0;
  double Scale = 1.0;
  int Resolution = 24;

private:
  vtkMusculoskeletalPhantom(const vtkMusculoskeletalPhantom&) = delete;
  void operator=(const vtkMusculoskeletalPhantom&) = delete;
};
