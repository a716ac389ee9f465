// SPDX-License-Identifier: BSD-3-Clause
#include "vtkMuscleFromPath.h"

#include "Anatomy/MuscleFromPath.h"
#include "Common/Clock.h"
#include "Geometry/TriangleTree.h"
#include "MDBlocks.h"
#include "MDConvert.h"
#include "MDReport.h"

#include <vtkDataArray.h>
#include <vtkFieldData.h>
#include <vtkInformation.h>
#include <vtkInformationVector.h>
#include <vtkObjectFactory.h>
#include <vtkPolyData.h>
#include <vtkStringArray.h>

#include <cmath>
#include <limits>

vtkStandardNewMacro(vtkMuscleFromPath);

namespace
{
/// The first value of the field array `name`, NaN when there is none.
double FieldNumber(vtkFieldData* fieldData, const char* name)
{
  vtkDataArray* array = fieldData ? fieldData->GetArray(name) : nullptr;
  return array && array->GetNumberOfTuples() > 0 ? array->GetTuple1(0) : std::numeric_limits<double>::quiet_NaN();
}

/// The muscle a path block describes, or an error naming what it lacks.
bool ReadMuscle(vtkPolyData* path, md::MuscleProperties& muscle, double& metresPerUnit, std::string& error)
{
  vtkFieldData* fieldData = path->GetFieldData();
  namespace array = mdvtk::array;
  muscle.maxIsometricForce = FieldNumber(fieldData, array::MaxIsometricForce);
  muscle.optimalFiberLength = FieldNumber(fieldData, array::OptimalFiberLength);
  muscle.tendonSlackLength = FieldNumber(fieldData, array::TendonSlackLength);
  muscle.pennationAngle = FieldNumber(fieldData, array::PennationAngleAtOptimal);
  metresPerUnit = FieldNumber(fieldData, array::MetresPerLengthUnit);
  std::string missing;
  for (const auto& [name, value] :
    { std::pair<const char*, double>{ array::MaxIsometricForce, muscle.maxIsometricForce },
      { array::OptimalFiberLength, muscle.optimalFiberLength }, { array::TendonSlackLength, muscle.tendonSlackLength },
      { array::MetresPerLengthUnit, metresPerUnit } })
  {
    if (!std::isfinite(value))
    {
      missing += (missing.empty() ? "" : ", ") + std::string(name);
    }
  }
  if (!missing.empty())
  {
    error = "has no " + missing +
      " in its field data: a muscle's surface is made from its properties, as the OpenSim Model Reader's "
      "MusclePathsRest gives them (a path actuator that is not a muscle has none)";
    return false;
  }
  if (!(metresPerUnit > 0))
  {
    error = "has a MetresPerLengthUnit that is not positive";
    return false;
  }
  return true;
}
}

vtkMuscleFromPath::vtkMuscleFromPath()
{
  this->SetNumberOfInputPorts(2);
  const md::MuscleFromPathParameters defaults;
  this->SpecificTension = defaults.specificTension * 100; // N/mm^2 -> N/cm^2
  this->NumberOfPoints = defaults.numberOfPoints;
  this->TendonRadiusRatio = defaults.tendonRadiusRatio;
  this->KeepMusclesApart = defaults.keepMusclesApart;
}

int vtkMuscleFromPath::FillInputPortInformation(int port, vtkInformation* info)
{
  mdvtk::AcceptPolyDataOrMultiBlock(info);
  if (port == 1)
  {
    info->Set(vtkAlgorithm::INPUT_IS_OPTIONAL(), 1);
  }
  return 1;
}

bool vtkMuscleFromPath::ReadBones(
  vtkInformationVector* port, std::vector<std::unique_ptr<md::TriangleTree>>& trees, std::string& error)
{
  std::vector<std::string> names;
  std::vector<md::TriangleMesh> meshes;
  if (!mdvtk::ReadMeshes(port, "Bones", names, meshes, error, /*skipEmpty=*/true)) // a body without a mesh
  {
    return false;
  }
  for (size_t b = 0; b < meshes.size(); ++b)
  {
    if (!md::AllFinite(meshes[b].points))
    {
      error = "Bones block '" + names[b] + "' has a coordinate that is not a finite number";
      return false;
    }
    trees.push_back(std::make_unique<md::TriangleTree>(meshes[b]));
  }
  return true;
}

int vtkMuscleFromPath::RequestUpdateExtent(
  vtkInformation* request, vtkInformationVector** inputVector, vtkInformationVector* outputVector)
{
  mdvtk::ClearOutputs(outputVector); // no stale result if an input fails upstream
  return this->Superclass::RequestUpdateExtent(request, inputVector, outputVector);
}

int vtkMuscleFromPath::RequestData(
  vtkInformation*, vtkInformationVector** inputVector, vtkInformationVector* outputVector)
{
  vtkDataObject* input = vtkDataObject::GetData(inputVector[0], 0);
  std::vector<mdvtk::Leaf> leaves;
  std::string error;
  if (!mdvtk::CollectLeaves(input, "Input", leaves, error))
  {
    vtkErrorMacro(<< error);
    return 0;
  }
  std::vector<std::unique_ptr<md::TriangleTree>> boneTrees;
  if (!this->ReadBones(inputVector[1], boneTrees, error))
  {
    vtkErrorMacro(<< error);
    return 0;
  }
  std::vector<const md::TriangleTree*> bones;
  for (const auto& tree : boneTrees)
  {
    bones.push_back(tree.get());
  }
  std::vector<vtkSmartPointer<vtkPolyData>> results(leaves.size());
  size_t muscleCount = 0, failedCount = 0;
  std::string noted;      // the muscles whose belly a limit set
  std::string notMuscles; // the model's paths that are not muscles
  std::string cramped;    // the muscles the bones and the others left too little room
  const auto fail = [&](size_t b, const std::string& message) {
    vtkErrorMacro(<< message);
    results[b] = mdvtk::FailedMuscle(leaves[b].data, message); // the other muscles go on
    ++failedCount;
  };
  // The muscles to make: their blocks, paths and properties, in one length unit.
  std::vector<size_t> blocks;
  std::vector<md::Points> paths;
  std::vector<md::MuscleProperties> muscles;
  double unit = 0; // metres per length unit, the first muscle's
  for (size_t b = 0; b < leaves.size(); ++b)
  {
    const mdvtk::Leaf& leaf = leaves[b];
    if (!leaf.data)
    {
      continue;
    }
    const std::vector<md::Points> lines = mdvtk::ToPolylines(leaf.data);
    auto* type = vtkStringArray::SafeDownCast(leaf.data->GetFieldData()->GetAbstractArray(mdvtk::array::MuscleType));
    if (type && type->GetNumberOfValues() > 0 && !leaf.data->GetFieldData()->GetArray(mdvtk::array::MaxIsometricForce))
    {
      // A model's path actuator that is not a muscle (OpenSim's PathActuator): nothing to make.
      results[b] = mdvtk::FailedMuscle(leaf.data, "a " + type->GetValue(0) + ", not a muscle: no surface is made");
      notMuscles += (notMuscles.empty() ? "" : ", ") + mdvtk::NameOf(leaf) + " (" + type->GetValue(0) + ")";
      continue;
    }
    ++muscleCount;
    md::MuscleProperties muscle;
    double metresPerUnit = 0;
    if (lines.size() != 1)
    {
      fail(b,
        leaf.label + " has " + std::to_string(lines.size()) + " polylines: a muscle's path is one" +
          mdvtk::UpstreamFailure(leaf.data));
    }
    else if (!ReadMuscle(leaf.data, muscle, metresPerUnit, error))
    {
      fail(b, leaf.label + " " + error);
    }
    else if (unit > 0 && metresPerUnit != unit)
    {
      fail(b,
        leaf.label + " is in a length unit of " + std::to_string(metresPerUnit) + " m, the muscles before it in " +
          std::to_string(unit) + " m: one unit for all");
    }
    else
    {
      unit = metresPerUnit;
      blocks.push_back(b);
      paths.push_back(lines[0]);
      muscles.push_back(muscle);
    }
  }
  md::MuscleFromPathParameters parameters;
  const double centimetresPerUnit = 100 * unit;
  parameters.specificTension = this->SpecificTension * centimetresPerUnit * centimetresPerUnit;
  parameters.numberOfPoints = this->NumberOfPoints;
  parameters.tendonRadiusRatio = this->TendonRadiusRatio;
  std::vector<md::MuscleFromPathResult> made(paths.size());
  std::vector<std::string> failures(paths.size());
  int result = 1;
  std::string failure;
  const auto start = md::Clock::now();
  parameters.keepMusclesApart = this->KeepMusclesApart;
  const auto make = [&] {
    made = md::MusclesFromPaths(paths, muscles, parameters, bones, failures);
  };
  if (!paths.empty() && !mdvtk::CallCore(this, "", make, result, &failure))
  {
    return result; // stopped by the user, or reported
  }
  const double seconds = md::SecondsSince(start);
  for (size_t m = 0; m < paths.size(); ++m)
  {
    const size_t b = blocks[m];
    const mdvtk::Leaf& leaf = leaves[b];
    if (!failures[m].empty())
    {
      fail(b, leaf.label + ": " + failures[m]);
      continue;
    }
    const md::MuscleFromPathResult& muscle = made[m];
    auto surface = mdvtk::ToPolyData(muscle.surface);
    vtkFieldData* fieldData = surface->GetFieldData();
    fieldData->PassData(leaf.data->GetFieldData());
    mdvtk::AddFieldValue(fieldData, "EstimatedVolume", muscle.estimatedVolume);
    mdvtk::AddFieldValue(fieldData, "MuscleVolume", muscle.volume);
    mdvtk::AddFieldValue(
      fieldData, "PhysiologicalCrossSectionalArea", muscles[m].maxIsometricForce / parameters.specificTension);
    mdvtk::AddFieldValue(fieldData, "BellyStart", muscle.bellyStart);
    mdvtk::AddFieldValue(fieldData, "BellyEnd", muscle.bellyEnd);
    mdvtk::AddFieldValue(fieldData, "BellyRadius", muscle.bellyRadius);
    mdvtk::AddFieldValue(fieldData, "TendonRadius", muscle.tendonRadius);
    mdvtk::AddFieldValue(fieldData, "SpecificTension", this->SpecificTension);
    mdvtk::AddFieldValue(fieldData, "PointsHeldByBones", muscle.pointsHeldByBones);
    mdvtk::AddFieldValue(fieldData, "PointsHeldByMuscles", muscle.pointsHeldByMuscles);
    mdvtk::AddFieldValue(fieldData, "VolumeKept", muscle.volumeKept);
    if (!muscle.notes.empty())
    {
      vtkNew<vtkStringArray> notes;
      notes->SetName("Notes");
      for (const std::string& note : muscle.notes)
      {
        notes->InsertNextValue(note);
      }
      fieldData->AddArray(notes);
    }
    if (muscle.volumeKept < 1 - 1e-6)
    {
      cramped += (cramped.empty() ? "" : ", ") + mdvtk::NameOf(leaf) + " " +
        std::to_string(static_cast<int>(std::floor(100 * muscle.volumeKept))) + " %";
    }
    if (muscle.bellyLimited)
    {
      noted += (noted.empty() ? "" : ", ") + mdvtk::NameOf(leaf);
    }
    // The time of the whole model's making, shared out.
    mdvtk::AddFieldValue(fieldData, mdvtk::array::ElapsedSeconds, seconds / static_cast<double>(paths.size()));
    results[b] = surface;
  }
  if (!notMuscles.empty())
  {
    vtkWarningMacro(<< "these paths are not muscles and get no surface (their blocks are left empty): " << notMuscles);
  }
  if (!cramped.empty())
  {
    vtkWarningMacro(<< "the bones and the other muscles leave too little room for the volume of these muscles "
                       "(field data VolumeKept): "
                    << cramped);
  }
  if (!noted.empty())
  {
    // Once for all the muscles, not once each: a whole model has dozens with long tendons.
    vtkWarningMacro(<< "the belly of these muscles takes a share of the path set by a limit (at least a third, at "
                       "most nine tenths), not the path less the tendon slack length (each muscle's field data "
                       "Notes says by how much): "
                    << noted);
  }
  mdvtk::AssignLeaves(input, vtkDataObject::GetData(outputVector, 0), results, mdvtk::Role::Muscle);
  return muscleCount > 0 && failedCount == muscleCount ? 0 : 1; // each failure was reported
}

void vtkMuscleFromPath::PrintSelf(ostream& os, vtkIndent indent)
{
  this->Superclass::PrintSelf(os, indent);
  os << indent << "SpecificTension: " << this->SpecificTension << "\n";
  os << indent << "NumberOfPoints: " << this->NumberOfPoints << "\n";
  os << indent << "TendonRadiusRatio: " << this->TendonRadiusRatio << "\n";
  os << indent << "KeepMusclesApart: " << this->KeepMusclesApart << "\n";
}
