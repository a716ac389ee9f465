// SPDX-License-Identifier: BSD-3-Clause
/**
 * @class   vtkActionLineMatching
 * @brief   Matches rest-pose and current-pose action lines point by point.
 *
 * Hajkova & Kohout, "Interpolation Method for Muscle Deformation", sec. 4.2:
 * both polylines are parameterised by normalised arc length; every point of
 * either line is kept and gets a partner on the other line, an existing point
 * within Tolerance or a new point inserted at the same normalised arc length.
 *
 * Input port 0: rest-pose (RP) action lines; input port 1 (CurrentPose):
 * current-pose (CP) action lines. Each is a vtkPolyData of polylines or a
 * vtkMultiBlockDataSet of them; blocks pair by name (else by order) and the
 * polylines inside a block pair by order.
 *
 * Output port 0: the matched RP lines, with point arrays CurrentPosition (the
 * matched CP point), ArcLength (normalised arc length) and Inserted (1 where
 * the point was inserted). Output port 1: the matched CP lines, with ArcLength
 * and Inserted. Matched lines have equal point counts.
 */
#pragma once

#include "MuscleDeformationFiltersModule.h"

#include <vtkPassInputTypeAlgorithm.h>

class MUSCLEDEFORMATIONFILTERS_EXPORT vtkActionLineMatching : public vtkPassInputTypeAlgorithm
{
public:
  static vtkActionLineMatching* New();
  vtkTypeMacro(vtkActionLineMatching, vtkPassInputTypeAlgorithm);
  void PrintSelf(ostream& os, vtkIndent indent) override;

  /// Largest difference of normalised arc length at which two points are
  /// matched rather than a new point inserted. Capped, per pair of lines, at
  /// half the smallest point spacing along either line (so that matching keeps
  /// the order of the points). Default 0.01.
  vtkSetClampMacro(Tolerance, double, 0.0, 0.5);
  vtkGetMacro(Tolerance, double);

  /// Connect the current-pose action lines.
  void SetCurrentPoseConnection(vtkAlgorithmOutput* output) { this->SetInputConnection(1, output); }

protected:
  vtkActionLineMatching();
  ~vtkActionLineMatching() override = default;

  int FillInputPortInformation(int port, vtkInformation* info) override;
  int RequestData(vtkInformation*, vtkInformationVector**, vtkInformationVector*) override;
  int RequestUpdateExtent(vtkInformation*, vtkInformationVector**, vtkInformationVector*) override;

  double Tolerance; // md::kDefaultMatchingTolerance, set by the constructor

private:
  vtkActionLineMatching(const vtkActionLineMatching&) = delete;
  void operator=(const vtkActionLineMatching&) = delete;
};
