// SPDX-License-Identifier: BSD-3-Clause
#include "vtkMuscleFromPath.h"

#include "Anatomy/MuscleFromPath.h"
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

#include <chrono>
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
  muscle.maxIsometricForce = FieldNumber(fieldData, "max_isometric_force");
  muscle.optimalFiberLength = FieldNumber(fieldData, "optimal_fiber_length");
  muscle.tendonSlackLength = FieldNumber(fieldData, "tendon_slack_length");
  muscle.pennationAngle = FieldNumber(fieldData, "pennation_angle_at_optimal");
  metresPerUnit = FieldNumber(fieldData, "MetresPerLengthUnit");
  std::string missing;
  for (const auto& [name, value] : { std::pair<const char*, double>{ "max_isometric_force", muscle.maxIsometricForce },
         { "optimal_fiber_length", muscle.optimalFiberLength }, { "tendon_slack_length", muscle.tendonSlackLength },
         { "MetresPerLengthUnit", metresPerUnit } })
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
  vtkDataObject* bones = port->GetNumberOfInformationObjects() > 0 ? vtkDataObject::GetData(port, 0) : nullptr;
  std::vector<mdvtk::Leaf> leaves;
  if (bones && !mdvtk::CollectLeaves(bones, "Bones", leaves, error))
  {
    return false;
  }
  for (const mdvtk::Leaf& leaf : leaves)
  {
    md::TriangleMesh mesh;
    if (!leaf.data || leaf.data->GetNumberOfPoints() == 0)
    {
      continue; // a body without a mesh (the ground)
    }
    if (mdvtk::ReadTriangles(leaf.data, mesh) < 0 || mesh.triangles.rows() == 0)
    {
      error = leaf.label + " has no triangles: a bone is a surface";
      return false;
    }
    if (!md::AllFinite(mesh.points))
    {
      error = leaf.label + " has a coordinate that is not a finite number";
      return false;
    }
    trees.push_back(std::make_unique<md::TriangleTree>(mesh));
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
  std::string cramped;    // the muscles the bones left too little room
  const auto fail = [&](size_t b, const std::string& message) {
    vtkErrorMacro(<< message);
    results[b] = mdvtk::FailedMuscle(leaves[b].data, message); // the other muscles go on
    ++failedCount;
  };
  for (size_t b = 0; b < leaves.size(); ++b)
  {
    if (mdvtk::ProgressOrStop(this, static_cast<double>(b) / leaves.size()))
    {
      return 1;
    }
    const mdvtk::Leaf& leaf = leaves[b];
    if (!leaf.data)
    {
      continue;
    }
    ++muscleCount;
    const auto start = std::chrono::steady_clock::now();
    const std::vector<md::Points> lines = mdvtk::ToPolylines(leaf.data);
    if (lines.size() != 1)
    {
      fail(b,
        leaf.label + " has " + std::to_string(lines.size()) + " polylines: a muscle's path is one" +
          mdvtk::UpstreamFailure(leaf.data));
      continue;
    }
    auto* type = vtkStringArray::SafeDownCast(leaf.data->GetFieldData()->GetAbstractArray("MuscleType"));
    if (type && type->GetNumberOfValues() > 0 && !leaf.data->GetFieldData()->GetArray("max_isometric_force"))
    {
      // A model's path actuator that is not a muscle (OpenSim's PathActuator): nothing to make.
      results[b] = mdvtk::FailedMuscle(leaf.data, "a " + type->GetValue(0) + ", not a muscle: no surface is made");
      notMuscles += (notMuscles.empty() ? "" : ", ") + mdvtk::NameOf(leaf) + " (" + type->GetValue(0) + ")";
      --muscleCount;
      continue;
    }
    md::MuscleProperties muscle;
    double metresPerUnit = 0;
    if (!ReadMuscle(leaf.data, muscle, metresPerUnit, error))
    {
      fail(b, leaf.label + " " + error);
      continue;
    }
    md::MuscleFromPathParameters parameters;
    const double centimetresPerUnit = 100 * metresPerUnit;
    parameters.specificTension = this->SpecificTension * centimetresPerUnit * centimetresPerUnit;
    parameters.numberOfPoints = this->NumberOfPoints;
    parameters.tendonRadiusRatio = this->TendonRadiusRatio;
    md::MuscleFromPathResult made;
    int result = 1;
    std::string failure;
    if (!mdvtk::CallCore(
          this, leaf.label + ": ", [&] { made = md::MuscleFromPath(lines[0], muscle, parameters, bones); }, result,
          &failure))
    {
      if (failure.empty())
      {
        return result; // stopped by the user
      }
      results[b] = mdvtk::FailedMuscle(leaf.data, failure);
      ++failedCount;
      continue;
    }
    auto surface = mdvtk::ToPolyData(made.surface);
    vtkFieldData* fieldData = surface->GetFieldData();
    fieldData->PassData(leaf.data->GetFieldData());
    mdvtk::AddFieldValue(fieldData, "EstimatedVolume", made.estimatedVolume);
    mdvtk::AddFieldValue(fieldData, "MuscleVolume", made.volume);
    mdvtk::AddFieldValue(
      fieldData, "PhysiologicalCrossSectionalArea", muscle.maxIsometricForce / parameters.specificTension);
    mdvtk::AddFieldValue(fieldData, "BellyStart", made.bellyStart);
    mdvtk::AddFieldValue(fieldData, "BellyEnd", made.bellyEnd);
    mdvtk::AddFieldValue(fieldData, "BellyRadius", made.bellyRadius);
    mdvtk::AddFieldValue(fieldData, "TendonRadius", made.tendonRadius);
    mdvtk::AddFieldValue(fieldData, "SpecificTension", this->SpecificTension);
    mdvtk::AddFieldValue(fieldData, "PointsHeldByBones", made.pointsHeldByBones);
    mdvtk::AddFieldValue(fieldData, "VolumeKept", made.volumeKept);
    if (!made.notes.empty())
    {
      vtkNew<vtkStringArray> notes;
      notes->SetName("Notes");
      for (const std::string& note : made.notes)
      {
        notes->InsertNextValue(note);
      }
      fieldData->AddArray(notes);
      if (made.volumeKept < 1 - 1e-6)
      {
        cramped += (cramped.empty() ? "" : ", ") + mdvtk::NameOf(leaf) + " " +
          std::to_string(static_cast<int>(std::floor(100 * made.volumeKept))) + " %";
      }
      if (made.bellyLimited)
      {
        noted += (noted.empty() ? "" : ", ") + mdvtk::NameOf(leaf);
      }
    }
    mdvtk::AddFieldValue(fieldData, mdvtk::array::ElapsedSeconds,
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
    results[b] = surface;
  }
  if (!notMuscles.empty())
  {
    vtkWarningMacro(<< "these paths are not muscles and get no surface (their blocks are left empty): " << notMuscles);
  }
  if (!cramped.empty())
  {
    vtkWarningMacro(<< "the bones leave too little room for the volume of these muscles (field data VolumeKept): "
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
}
