// SPDX-License-Identifier: BSD-3-Clause
/**
 * @class   vtkPathsOverBones
 * @brief   Keeps muscle paths out of the bones: each path a taut string through its own points
 *          that runs over a bone's surface where its straight segment would enter the bone.
 *
 * Input 0: the paths (polylines; a vtkPolyData or a multiblock of them), such as the
 * OpenSimModelReader's MusclePaths or MusclePathsRest. Input 1 (Bones): closed bone surfaces in
 * the same pose (MoveWithBodies' output, or the rest pose's bones). Each segment between two of a
 * path's points gets PointsPerSegment points, which lie on the straight segment where no bone is
 * in the way and over the bone's surface where one is (md::PathOverBones); a segment that starts
 * or ends inside a bone (an attachment) may run in it until it first leaves it.
 *
 * Over a motion (inputs with time steps) every frame starts from the frame before, so a path
 * stays on the side of a bone it was on and moves continuously; a frame asked for out of order is
 * reached by computing the frames before it (kept, so each is computed once), and is the same
 * whichever order frames are asked in.
 *
 * Output: the paths with the same blocks, cells and cell data; the path's own points keep their
 * point data, and the points between take, in string arrays (PathPointName, PathPointBody), the
 * name and body of the bone they lie on (empty where none). Field data PathLength is the path's
 * length (the straight one in StraightPathLength). Where the paths and the bones carry stepped
 * poses (point arrays PointsAt(<pose>): OpenSimModelReader's MomentArmStep, passed on by
 * MoveWithBodies), the path at each of them is kept over the bones too, started from the frame's.
 */
#pragma once

#include "MuscleDeformationFiltersModule.h"

#include <vtkPassInputTypeAlgorithm.h>

#include <memory>

class MUSCLEDEFORMATIONFILTERS_EXPORT vtkPathsOverBones : public vtkPassInputTypeAlgorithm
{
public:
  static vtkPathsOverBones* New();
  vtkTypeMacro(vtkPathsOverBones, vtkPassInputTypeAlgorithm);
  void PrintSelf(ostream& os, vtkIndent indent) override;

  void SetBonesConnection(vtkAlgorithmOutput* output) { this->SetInputConnection(1, output); }

  /// Points between each two of a path's own points: how finely a path follows a bone.
  vtkSetClampMacro(PointsPerSegment, int, 1, 200);
  vtkGetMacro(PointsPerSegment, int);

  /// Frames computed since the filter was made (frames kept are not computed again).
  vtkGetMacro(FramesComputed, int);

protected:
  vtkPathsOverBones();
  ~vtkPathsOverBones() override;

  int FillInputPortInformation(int port, vtkInformation* info) override;
  int RequestInformation(vtkInformation*, vtkInformationVector**, vtkInformationVector*) override;
  int RequestUpdateExtent(vtkInformation*, vtkInformationVector**, vtkInformationVector*) override;
  int RequestData(vtkInformation*, vtkInformationVector**, vtkInformationVector*) override;

  int PointsPerSegment;
  int FramesComputed = 0;

private:
  vtkPathsOverBones(const vtkPathsOverBones&) = delete;
  void operator=(const vtkPathsOverBones&) = delete;
  struct Internals;
  std::unique_ptr<Internals> In;
};
