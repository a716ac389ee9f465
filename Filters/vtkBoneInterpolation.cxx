// SPDX-License-Identifier: BSD-3-Clause
#include "vtkBoneInterpolation.h"

#include "MDBlocks.h"
#include "MDConvert.h"
#include "MDReport.h"
#include "MDTime.h"
#include "Motion/BoneInterpolation.h"

#include <vtkAlgorithmOutput.h>
#include <vtkCellArray.h>
#include <vtkCellData.h>
#include <vtkDataArray.h>
#include <vtkFieldData.h>
#include <vtkIdTypeArray.h>
#include <vtkInformation.h>
#include <vtkInformationVector.h>
#include <vtkMath.h>
#include <vtkObjectFactory.h>
#include <vtkPointData.h>
#include <vtkPolyData.h>
#include <vtkStreamingDemandDrivenPipeline.h>

#include <algorithm>
#include <array>
#include <cmath>

vtkStandardNewMacro(vtkBoneInterpolation);

struct vtkBoneInterpolation::Pose
{
  vtkPolyData* restData = nullptr;
  std::string label;
  md::Points rest;
  md::Points current;
};

namespace
{
/// Same cells in the same order (compared only when the CP has cells at all).
bool SameCells(vtkCellArray* a, vtkCellArray* b)
{
  vtkNew<vtkIdTypeArray> legacyA, legacyB;
  a->ExportLegacyFormat(legacyA);
  b->ExportLegacyFormat(legacyB);
  return legacyA->GetNumberOfValues() == legacyB->GetNumberOfValues() &&
    std::equal(legacyA->GetPointer(0), legacyA->GetPointer(0) + legacyA->GetNumberOfValues(), legacyB->GetPointer(0));
}

bool SameTopology(vtkPolyData* rest, vtkPolyData* current)
{
  if (current->GetNumberOfCells() == 0)
  {
    return true;
  }
  return SameCells(rest->GetVerts(), current->GetVerts()) && SameCells(rest->GetLines(), current->GetLines()) &&
    SameCells(rest->GetPolys(), current->GetPolys()) && SameCells(rest->GetStrips(), current->GetStrips());
}

}

vtkBoneInterpolation::vtkBoneInterpolation()
{
  this->SetNumberOfInputPorts(2);
  this->SetNumberOfOutputPorts(1);
  this->NumberOfSteps = md::kDefaultNumberOfSteps;
  this->MaximumStepDisplacement = md::kDefaultMaximumStepDisplacement;
  this->InterpolationMode = static_cast<int>(md::kDefaultInterpolationMode);
}

int vtkBoneInterpolation::FillInputPortInformation(int port, vtkInformation* info)
{
  mdvtk::AcceptPolyDataOrMultiBlock(info);
  if (port == 1)
  {
    info->Set(vtkAlgorithm::INPUT_IS_OPTIONAL(), 1);
  }
  return 1;
}

bool vtkBoneInterpolation::ReadPoses(vtkDataObject* restInput, vtkDataObject* currentInput, std::vector<Pose>& poses)
{
  std::vector<mdvtk::Leaf> restLeaves, currentLeaves;
  std::vector<size_t> partner;
  std::string error;
  if (!mdvtk::CollectLeaves(restInput, "Input", restLeaves, error) ||
    (currentInput &&
      (!mdvtk::CollectLeaves(currentInput, "CurrentPose", currentLeaves, error) ||
        !mdvtk::PairLeaves(this, restLeaves, "Input", currentLeaves, "CurrentPose", partner, error))))
  {
    vtkErrorMacro(<< error);
    return false;
  }
  poses.clear();
  poses.resize(restLeaves.size());
  for (size_t b = 0; b < restLeaves.size(); ++b)
  {
    Pose& pose = poses[b];
    const mdvtk::Leaf& rest = restLeaves[b];
    pose.restData = rest.data;
    pose.label = rest.label;
    vtkPolyData* current = currentInput ? currentLeaves[partner[b]].data : nullptr;
    if (!rest.data)
    {
      continue; // an empty block stays empty
    }
    if (rest.data->GetNumberOfPoints() == 0)
    {
      vtkErrorMacro(<< rest.label << " has no points");
      return false;
    }
    pose.rest = mdvtk::ToPoints(rest.data->GetPoints());
    if (currentInput)
    {
      const std::string& currentLabel = currentLeaves[partner[b]].label;
      if (!current || current->GetNumberOfPoints() != rest.data->GetNumberOfPoints())
      {
        vtkErrorMacro(<< rest.label << " has " << rest.data->GetNumberOfPoints() << " points but " << currentLabel
                      << " has " << (current ? current->GetNumberOfPoints() : 0)
                      << "; the current pose must have the same points in the same order");
        return false;
      }
      if (!SameTopology(rest.data, current))
      {
        vtkErrorMacro(<< rest.label << " and " << currentLabel
                      << " have different cells; the two poses must share one topology");
        return false;
      }
      pose.current = mdvtk::ToPoints(current->GetPoints());
    }
    else
    {
      vtkDataArray* position = rest.data->GetPointData()->GetArray(mdvtk::CurrentPositionArrayName);
      if (!position || position->GetNumberOfComponents() != 3)
      {
        vtkErrorMacro(<< "CurrentPose is not connected and " << rest.label
                      << " has no 3-component point array CurrentPosition; connect the current "
                         "pose, or use port 0 of ActionLineMatching");
        return false;
      }
      pose.current = mdvtk::ToPoints(position);
    }
    // The points of both inputs were checked by CollectLeaves; a CurrentPosition array's values
    // were not.
    if (!md::AllFinite(pose.current))
    {
      vtkErrorMacro(<< (currentInput ? currentLeaves[partner[b]].label : rest.label + " CurrentPosition")
                    << " has NaN or infinite coordinates");
      return false;
    }
  }
  return true;
}

int vtkBoneInterpolation::RequestInformation(
  vtkInformation*, vtkInformationVector** inputVector, vtkInformationVector* outputVector)
{
  auto automatic = [&](int& steps) {
    std::vector<Pose> poses;
    if (!this->ReadPoses(vtkDataObject::GetData(inputVector[0], 0),
          this->GetNumberOfInputConnections(1) ? vtkDataObject::GetData(inputVector[1], 0) : nullptr, poses))
    {
      return 0;
    }
    double largest = 0;
    for (const Pose& pose : poses)
    {
      largest = std::max(largest, md::MaximumDisplacement(pose.rest, pose.current));
    }
    int result = 1;
    mdvtk::CallCore(
      this, "", [&] { steps = md::AutomaticNumberOfSteps(largest, this->MaximumStepDisplacement); }, result);
    return result;
  };
  return mdvtk::AdvertiseSteps(
    this, outputVector, this->NumberOfSteps, { 0, 1 }, automatic, this->ResolvedNumberOfSteps);
}

int vtkBoneInterpolation::RequestUpdateExtent(
  vtkInformation*, vtkInformationVector** inputVector, vtkInformationVector* outputVector)
{
  mdvtk::ClearOutputs(outputVector);
  mdvtk::InputsAtTheirOwnTime(inputVector, 2); // our time is the interpolation step
  return 1;
}

int vtkBoneInterpolation::RequestData(
  vtkInformation*, vtkInformationVector** inputVector, vtkInformationVector* outputVector)
{
  vtkDataObject* restInput = vtkDataObject::GetData(inputVector[0], 0);
  vtkDataObject* currentInput =
    this->GetNumberOfInputConnections(1) ? vtkDataObject::GetData(inputVector[1], 0) : nullptr;
  std::vector<Pose> poses;
  if (!this->ReadPoses(restInput, currentInput, poses))
  {
    return 0;
  }
  const int steps = this->ResolvedNumberOfSteps;
  const int step = mdvtk::StepAsked(outputVector->GetInformationObject(0), steps, 0);
  const auto mode = static_cast<md::InterpolationMode>(this->InterpolationMode);
  const vtkMTimeType inputsTime =
    std::max({ this->GetMTime(), restInput->GetMTime(), currentInput ? currentInput->GetMTime() : 0 });
  if (inputsTime != this->WarningsSaidFor)
  {
    this->WarningsSaid.clear();
    this->WarningsSaidFor = inputsTime;
  }

  std::vector<vtkSmartPointer<vtkPolyData>> results(poses.size());
  for (size_t b = 0; b < poses.size(); ++b)
  {
    this->UpdateProgress(static_cast<double>(b) / poses.size());
    const Pose& pose = poses[b];
    if (!pose.restData)
    {
      continue;
    }
    md::Points positions;
    auto output = vtkSmartPointer<vtkPolyData>::New();
    output->ShallowCopy(pose.restData);
    output->GetFieldData()->DeepCopy(pose.restData->GetFieldData());
    vtkFieldData* fieldData = output->GetFieldData();
    int result = 1;
    if (!mdvtk::CallCore(
          this, pose.label + ": ",
          [&] {
            const md::PoseInterpolator interpolator(pose.rest, pose.current, mode);
            positions = interpolator.AtStep(step, steps);
            if (interpolator.Fit())
            {
              const md::RigidFit& fit = *interpolator.Fit();
              mdvtk::AddFieldValue(fieldData, "RigidFitRMSResidual", fit.rmsResidual);
              mdvtk::AddFieldValue(fieldData, "RigidFitMaxResidual", fit.maxResidual);
              mdvtk::AddFieldValue(
                fieldData, "RotationAngleDegrees", vtkMath::DegreesFromRadians(interpolator.RotationAngle()));
              if (const std::string warning = interpolator.NonRigidWarning(pose.label);
                  !warning.empty() && this->WarningsSaid.insert(warning).second)
              {
                vtkWarningMacro(<< warning);
              }
            }
          },
          result))
    {
      return result;
    }
    output->SetPoints(mdvtk::ToVtkPoints(positions));
    mdvtk::AddFieldValue(fieldData, mdvtk::array::InterpolationStep, step);
    mdvtk::AddFieldValue(fieldData, mdvtk::array::NumberOfSteps, steps);
    mdvtk::AddFieldValue(fieldData, "InterpolationFraction", static_cast<double>(step) / steps);
    results[b] = output;
  }
  vtkDataObject* output = vtkDataObject::GetData(outputVector, 0);
  // What it moves keeps its role; unmarked input is bones, or action lines when it has no faces.
  mdvtk::Role role = mdvtk::Role::Bone;
  for (const Pose& pose : poses)
  {
    if (pose.restData && pose.restData->GetCellData()->GetArray(mdvtk::RoleArrayName))
    {
      role = mdvtk::Role::AsGiven;
      break;
    }
    if (pose.restData && pose.restData->GetNumberOfPolys() == 0 && pose.restData->GetNumberOfLines() > 0)
    {
      role = mdvtk::Role::ActionLine;
    }
  }
  mdvtk::AssignLeaves(restInput, output, results, role);
  output->GetInformation()->Set(vtkDataObject::DATA_TIME_STEP(), static_cast<double>(step));
  return 1;
}

void vtkBoneInterpolation::PrintSelf(ostream& os, vtkIndent indent)
{
  this->Superclass::PrintSelf(os, indent);
  os << indent << "NumberOfSteps: " << this->NumberOfSteps << "\n";
  os << indent << "MaximumStepDisplacement: " << this->MaximumStepDisplacement << "\n";
  os << indent << "InterpolationMode: " << (this->InterpolationMode == LINEAR ? "Linear" : "Rigid") << "\n";
  os << indent << "ResolvedNumberOfSteps: " << this->ResolvedNumberOfSteps << "\n";
}
