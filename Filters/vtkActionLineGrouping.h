// SPDX-License-Identifier: BSD-3-Clause
/**
 * @class   vtkActionLineGrouping
 * @brief   Groups muscle paths (one polyline per path, e.g. an OpenSim model's) into the action
 *          lines of muscle surfaces: one block per surface, holding its paths.
 *
 * Input 0: the muscle surfaces (rest pose). Input 1 (Paths): the paths in the rest pose, one
 * block per path (OpenSimModelReader's MusclePathsRest). Input 2 (PathsCurrent, optional): the
 * same paths in the current pose (the reader's MusclePaths). Each path goes to the surface that
 * holds the largest share of its length (at least 5 %), unless PathsOfMuscle names it
 * ("gluteus_maximus_r=glut_max1_r,glut_max2_r; ..."). What was decided is said in the output
 * (field data ActionLinePaths and PathInsideFraction on each block) and in a message.
 * Outputs: 0 the grouped paths in the rest pose, 1 in the current pose (empty without input 2),
 * each block named as its muscle: the ActionLinesRest and ActionLinesCurrent of
 * InterpolatedMuscleDeformation.
 */
#pragma once

#include "MuscleDeformationFiltersModule.h"

#include <vtkMultiBlockDataSetAlgorithm.h>

#include <memory>
#include <string>

namespace mdvtk
{
class InputCheck;
}

class MUSCLEDEFORMATIONFILTERS_EXPORT vtkActionLineGrouping : public vtkMultiBlockDataSetAlgorithm
{
public:
  static vtkActionLineGrouping* New();
  vtkTypeMacro(vtkActionLineGrouping, vtkMultiBlockDataSetAlgorithm);
  void PrintSelf(ostream& os, vtkIndent indent) override;

  void SetPathsConnection(vtkAlgorithmOutput* output) { this->SetInputConnection(1, output); }
  void SetPathsCurrentConnection(vtkAlgorithmOutput* output) { this->SetInputConnection(2, output); }

  /// "muscle=path,path; muscle=path": paths given to muscles by hand (the others are decided).
  vtkGetStringMacro(PathsOfMuscle);
  vtkSetStringMacro(PathsOfMuscle);

  /// What was decided at the last update, one line per path.
  const std::string& GetDecision() const { return this->Decision; }

protected:
  vtkActionLineGrouping();
  ~vtkActionLineGrouping() override;

  int FillInputPortInformation(int port, vtkInformation* info) override;
  int RequestInformation(vtkInformation*, vtkInformationVector**, vtkInformationVector*) override;
  int RequestData(vtkInformation*, vtkInformationVector**, vtkInformationVector*) override;
  int RequestUpdateExtent(vtkInformation*, vtkInformationVector**, vtkInformationVector*) override;

  char* PathsOfMuscle = nullptr;
  std::string Decision;

  /// The last grouping and what it was decided on: a new time of PathsCurrent alone (every
  /// frame of a motion) reuses it, and says nothing again.
  struct Grouped;
  std::unique_ptr<Grouped> LastGrouping;
  /// The muscles and the rest pose's paths as they last passed the input checks: the same at
  /// every frame of a motion, not checked again.
  std::unique_ptr<mdvtk::InputCheck[]> Checked;

private:
  vtkActionLineGrouping(const vtkActionLineGrouping&) = delete;
  void operator=(const vtkActionLineGrouping&) = delete;
  struct Inputs;
  /// Reads the muscles and the paths in both poses; false when one cannot be read (reported).
  bool ReadInputs(vtkInformationVector** inputVector, Inputs& in);
  /// Decides which paths are whose (GroupPaths), says so, and keeps it in LastGrouping; false
  /// (with RequestData's `result`) when a muscle gets none or the assignments are bad.
  bool Group(Inputs& in, const std::string& assignments, int& result);
  /// One block per muscle of `output`: its paths appended, at rest or in the current pose.
  void BuildGrouped(const Inputs& in, bool current, vtkMultiBlockDataSet* output);
};
