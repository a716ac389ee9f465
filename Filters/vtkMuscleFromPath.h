// SPDX-License-Identifier: BSD-3-Clause
/**
 * @class   vtkMuscleFromPath
 * @brief   A muscle surface for each muscle path of a model: 3-D muscles without scanned ones.
 *
 * Input: muscle paths in the rest pose (a vtkPolyData or a multiblock of them, one polyline per
 * block), such as the OpenSimModelReader's MusclePathsRest, each with the field data the reader
 * writes: max_isometric_force (N), optimal_fiber_length and tendon_slack_length (in the path's
 * unit), MetresPerLengthUnit.
 *
 * Each muscle becomes a closed, manifold, outward-oriented tube around its path
 * (md::MuscleFromPath): its belly holds the muscle's volume, PCSA x optimal fibre length with
 * PCSA = max isometric force / SpecificTension, and spans the path less the tendon slack length,
 * the tendon shared by both ends; it tapers smoothly to TendonRadiusRatio of the belly's radius,
 * and its ends are flat caps on the path's first and last points (the attachments, which the
 * deformation filters find from the action lines' ends). NumberOfPoints sets the resolution.
 *
 * Output: one surface per input block (same structure and names), with the input block's field
 * data and EstimatedVolume, MuscleVolume (the surface's), PhysiologicalCrossSectionalArea (in
 * the path's unit squared), BellyStart, BellyEnd (arc lengths along the path), BellyRadius,
 * TendonRadius, SpecificTension and ElapsedSeconds. A block that cannot be made (no polyline, no
 * muscle properties) is reported by name and left empty (DeformationFailed, FailureMessage); the
 * others are made; a model's path that is not a muscle (a PathActuator) is left empty the same
 * way, with a warning. What the input forced (a tendon that leaves the belly less than a third of the
 * path) is said in a warning and in the block's string field data Notes.
 *
 * Input 1 (Bones, optional): bone surfaces in the rest pose (the reader's BodiesRest). Each
 * surface point stops short of the first bone its ray from the tube's centre enters, and the
 * others widen to keep the volume (md::MuscleFromPath): an open bone mesh is a one-sided
 * obstacle, met from its outer side; a path that runs in a bone keeps its tube there. Field data
 * PointsHeldByBones and VolumeKept (1 unless the bones left too little room, said in a warning).
 *
 * With KeepMusclesApart (the default), the muscles share the space between them
 * (md::MusclesFromPaths): a point belongs to the muscle whose smoothed path is nearest, each
 * surface point stops short of its muscle's share, and the rest widens to keep the volume; only
 * where paths cross or meet (a shared insertion) do muscles still overlap. Field data
 * PointsHeldByMuscles.
 */
#pragma once

#include "MuscleDeformationFiltersModule.h"

#include <vtkPassInputTypeAlgorithm.h>

#include <memory>
#include <string>
#include <vector>

namespace md
{
class TriangleTree;
}

class MUSCLEDEFORMATIONFILTERS_EXPORT vtkMuscleFromPath : public vtkPassInputTypeAlgorithm
{
public:
  static vtkMuscleFromPath* New();
  vtkTypeMacro(vtkMuscleFromPath, vtkPassInputTypeAlgorithm);
  void PrintSelf(ostream& os, vtkIndent indent) override;

  void SetBonesConnection(vtkAlgorithmOutput* output) { this->SetInputConnection(1, output); }

  /// Specific tension, N/cm^2: the force of a unit of physiological cross-section. Default 60.
  vtkSetClampMacro(SpecificTension, double, 1e-3, 1e6);
  vtkGetMacro(SpecificTension, double);

  /// Points of each surface. Default 600.
  vtkSetClampMacro(NumberOfPoints, int, 26, 1000000);
  vtkGetMacro(NumberOfPoints, int);

  /// A tendon's radius as a share of the belly's. Default 0.25.
  vtkSetClampMacro(TendonRadiusRatio, double, 0.01, 1.0);
  vtkGetMacro(TendonRadiusRatio, double);

  /// Share the space between the muscles so that they do not overlap. Default on.
  vtkSetMacro(KeepMusclesApart, bool);
  vtkGetMacro(KeepMusclesApart, bool);
  vtkBooleanMacro(KeepMusclesApart, bool);

protected:
  vtkMuscleFromPath();
  ~vtkMuscleFromPath() override = default;

  /// The trees of the bones on input 1 (none when it is empty); false, with `error`, when a bone
  /// cannot be read.
  bool ReadBones(vtkInformationVector* port, std::vector<std::unique_ptr<md::TriangleTree>>& trees, std::string& error);

  int FillInputPortInformation(int port, vtkInformation* info) override;
  int RequestUpdateExtent(vtkInformation*, vtkInformationVector**, vtkInformationVector*) override;
  int RequestData(vtkInformation*, vtkInformationVector**, vtkInformationVector*) override;

  double SpecificTension;
  int NumberOfPoints;
  double TendonRadiusRatio;
  bool KeepMusclesApart;

private:
  vtkMuscleFromPath(const vtkMuscleFromPath&) = delete;
  void operator=(const vtkMuscleFromPath&) = delete;
};
