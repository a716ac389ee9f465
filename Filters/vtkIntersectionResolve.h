// SPDX-License-Identifier: BSD-3-Clause
/**
 * @class   vtkIntersectionResolve
 * @brief   Moves the points of deformable meshes out of obstacles (static intersections).
 *
 * Hajkova & Kohout's static intersection resolution, once after a
 * deformation: the points of the Input meshes (muscles) inside an obstacle
 * are grouped into edge-connected groups, and each group moves out to the
 * obstacle's surface along one direction (the mean of its points' ways to
 * their nearest surface points; a point whose exit that way is more than
 * twice as far as its nearest surface point goes to the nearest point).
 * The Input meshes are obstacles for each other: both sides then move, each
 * by DeformableShare of the way (0.6, as the original), so that neither is
 * pushed all the way. The Obstacles (bones) do not move.
 *
 * Overlap that already exists in the rest pose (scans overlap the bones) is
 * left alone when InputRest (the Input meshes in the rest pose, same points)
 * is connected: a point inside an obstacle there stays out of the resolution
 * for that obstacle, and does not count as new penetration. ObstaclesRest
 * gives the obstacles in the rest pose (same connections and blocks as
 * Obstacles); without it the obstacles are taken not to have moved. Without
 * InputRest every penetrating point is resolved.
 *
 * Inputs: 0 Input; 1 Obstacles (any number, optional); 2 InputRest
 * (optional); 3 ObstaclesRest (any number, optional).
 *
 * Output: the Input with moved points, point array StaticShift (the move of
 * each point), and field data PenetratingPointCount and
 * PenetratingGroupCount (found), MaxPenetrationDepth (found, before the
 * move), MaxStaticShift, and NewPenetrationCount and MaxNewPenetrationDepth
 * (what is left after the move).
 */
#pragma once

#include "MuscleDeformationFiltersModule.h"

#include <vtkPassInputTypeAlgorithm.h>

class MUSCLEDEFORMATIONFILTERS_EXPORT vtkIntersectionResolve : public vtkPassInputTypeAlgorithm
{
public:
  static vtkIntersectionResolve* New();
  vtkTypeMacro(vtkIntersectionResolve, vtkPassInputTypeAlgorithm);
  void PrintSelf(ostream& os, vtkIndent indent) override;

  void AddObstacleConnection(vtkAlgorithmOutput* output) { this->AddInputConnection(1, output); }
  void RemoveAllObstacles() { this->SetInputConnection(1, nullptr); }
  void SetInputRestConnection(vtkAlgorithmOutput* output) { this->SetInputConnection(2, output); }
  void AddObstacleRestConnection(vtkAlgorithmOutput* output) { this->AddInputConnection(3, output); }
  void RemoveAllObstaclesRest() { this->SetInputConnection(3, nullptr); }

  /// Share of the correction each side takes when the obstacle is another
  /// Input mesh. Default 0.6.
  vtkSetClampMacro(DeformableShare, double, 0.0, 1.0);
  vtkGetMacro(DeformableShare, double);

protected:
  vtkIntersectionResolve();
  ~vtkIntersectionResolve() override = default;
  int FillInputPortInformation(int port, vtkInformation* info) override;
  int RequestData(vtkInformation*, vtkInformationVector**, vtkInformationVector*) override;
  int RequestUpdateExtent(vtkInformation*, vtkInformationVector**, vtkInformationVector*) override;

  double DeformableShare; // the core's default (md::StaticResolveParameters), set by the constructor

private:
  vtkIntersectionResolve(const vtkIntersectionResolve&) = delete;
  void operator=(const vtkIntersectionResolve&) = delete;
  struct Read;
  /// Reads the meshes to resolve and the obstacles in both poses; false when an input cannot be
  /// read (reported). A mesh that cannot be used is left out, in read.failedBlocks.
  bool ReadInputs(vtkInformationVector** inputVector, Read& read);
  /// Whether the rest-pose obstacles (when given) pair with the obstacles, one for one.
  bool ObstaclesPair(const Read& read);
};
