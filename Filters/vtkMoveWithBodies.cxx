// SPDX-License-Identifier: BSD-3-Clause
#include "vtkMoveWithBodies.h"

#include "Geometry/RigidMotion.h"
#include "MDBlocks.h"
#include "MDConvert.h"
#include "MDReport.h"
#include "MDTime.h"
#include "OpenSim/OpenSimAttachment.h"

#include <vtkAbstractArray.h>
#include <vtkDataArray.h>
#include <vtkFieldData.h>
#include <vtkInformation.h>
#include <vtkInformationVector.h>
#include <vtkObjectFactory.h>
#include <vtkPointData.h>
#include <vtkPolyData.h>
#include <vtkStringArray.h>
#include <vtkTable.h>

#include <algorithm>
#include <map>

vtkStandardNewMacro(vtkMoveWithBodies);

vtkMoveWithBodies::vtkMoveWithBodies()
  : InputChecked(std::make_unique<mdvtk::InputCheck>())
{
  this->SetNumberOfInputPorts(2);
}

vtkMoveWithBodies::~vtkMoveWithBodies()
{
  this->SetBodyOfSurface(nullptr);
}

int vtkMoveWithBodies::FillInputPortInformation(int port, vtkInformation* info)
{
  if (port == 1)
  {
    info->Set(vtkAlgorithm::INPUT_REQUIRED_DATA_TYPE(), "vtkTable");
    return 1;
  }
  mdvtk::AcceptPolyDataOrMultiBlock(info);
  return 1;
}

int vtkMoveWithBodies::RequestInformation(
  vtkInformation*, vtkInformationVector** inputVector, vtkInformationVector* outputVector)
{
  // The surfaces move in the body transforms' time.
  mdvtk::CopyTimeSteps(inputVector[1]->GetInformationObject(0), outputVector->GetInformationObject(0));
  return 1;
}

int vtkMoveWithBodies::RequestUpdateExtent(
  vtkInformation* request, vtkInformationVector** inputVector, vtkInformationVector* outputVector)
{
  mdvtk::ClearOutputs(outputVector); // no stale result if an input fails upstream
  return this->Superclass::RequestUpdateExtent(request, inputVector, outputVector);
}

int vtkMoveWithBodies::RequestData(
  vtkInformation*, vtkInformationVector** inputVector, vtkInformationVector* outputVector)
{
  vtkDataObject* input = vtkDataObject::GetData(inputVector[0], 0);
  vtkTable* table = vtkTable::GetData(inputVector[1], 0);
  vtkDataObject* output = vtkDataObject::GetData(outputVector, 0);
  std::vector<mdvtk::Leaf> leaves;
  std::string error;
  if (!mdvtk::CollectLeaves(input, "Input", leaves, error, *this->InputChecked))
  {
    vtkErrorMacro(<< error);
    return 0;
  }
  vtkStringArray* bodies = table ? vtkStringArray::SafeDownCast(table->GetColumnByName(mdvtk::array::Body)) : nullptr;
  std::vector<vtkDataArray*> values;
  for (const char* name : mdvtk::array::TransformColumns)
  {
    values.push_back(table ? vtkDataArray::SafeDownCast(table->GetColumnByName(name)) : nullptr);
  }
  if (!bodies || std::find(values.begin(), values.end(), nullptr) != values.end())
  {
    vtkErrorMacro(<< "BodyTransforms must be the BodyTransforms output of an OpenSim Model Reader "
                     "(a table with columns Body, R00 ... R22, Tx, Ty, Tz)");
    return 0;
  }
  // Rows of a stepped pose (column Pose, OpenSimModelReader's MomentArmStep) move the surfaces'
  // points to point arrays PointsAt(<pose>); the others are the frame's.
  auto* poseColumn = vtkStringArray::SafeDownCast(table->GetColumnByName(mdvtk::array::Pose));
  std::vector<std::string> bodyNames, steppedNames;
  std::vector<md::RigidTransform> motions;
  std::map<std::string, std::map<std::string, md::RigidTransform>> stepped; // [pose][body]
  for (vtkIdType row = 0; row < table->GetNumberOfRows(); ++row)
  {
    const std::string pose = poseColumn ? poseColumn->GetValue(row) : std::string();
    md::RigidTransform t;
    for (int i = 0; i < 9; ++i)
    {
      t.rotation(i / 3, i % 3) = values[i]->GetComponent(row, 0);
    }
    for (int i = 0; i < 3; ++i)
    {
      t.translation[i] = values[9 + i]->GetComponent(row, 0);
    }
    const std::string problem = md::NotARigidMotion(t);
    if (!problem.empty())
    {
      vtkErrorMacro(<< "BodyTransforms row " << row << " (body '" << bodies->GetValue(row) << "'): " << problem);
      return 0;
    }
    if (!pose.empty())
    {
      if (stepped.find(pose) == stepped.end())
      {
        steppedNames.push_back(pose);
      }
      stepped[pose][bodies->GetValue(row)] = t;
      continue;
    }
    bodyNames.push_back(bodies->GetValue(row));
    motions.push_back(t);
  }
  std::vector<vtkSmartPointer<vtkPolyData>> results(leaves.size());
  std::vector<std::pair<std::string, std::vector<std::string>>> assignments;
  std::vector<int> bodyOfLeaf(leaves.size(), -1);
  int result = 1;
  if (!mdvtk::CallCore(
        this, "BodyOfSurface: ",
        [&] {
          assignments = md::osim::ParseAssignments(this->BodyOfSurface ? this->BodyOfSurface : "");
          for (size_t i = 0; i < leaves.size(); ++i)
          {
            bodyOfLeaf[i] =
              md::osim::BodyOfSurface(leaves[i].name.empty() ? "Input" : leaves[i].name, bodyNames, assignments);
          }
        },
        result))
  {
    return result;
  }
  for (size_t i = 0; i < leaves.size(); ++i)
  {
    if (!leaves[i].data)
    {
      continue;
    }
    const std::string name = leaves[i].name.empty() ? "Input" : leaves[i].name;
    const int body = bodyOfLeaf[i];
    if (body < 0)
    {
      std::string list;
      for (const std::string& b : bodyNames)
      {
        list += (list.empty() ? "" : ", ") + b;
      }
      vtkErrorMacro(<< leaves[i].label << ": no body of the model is named after '" << name
                    << "'; say which body it moves with in BodyOfSurface (e.g. " << md::osim::WithoutExtension(name)
                    << "=pelvis). The bodies: " << list);
      return 0;
    }
    auto moved = vtkSmartPointer<vtkPolyData>::New();
    moved->ShallowCopy(leaves[i].data);
    if (leaves[i].data->GetPoints())
    {
      const md::Points rest = mdvtk::ToPoints(leaves[i].data->GetPoints());
      moved->SetPoints(mdvtk::ToVtkPoints(motions[body].Apply(rest)));
      for (const std::string& pose : steppedNames)
      {
        const auto t = stepped[pose].find(bodyNames[body]);
        if (t == stepped[pose].end())
        {
          vtkErrorMacro(<< "BodyTransforms has rows of pose '" << pose << "' but none of body '" << bodyNames[body]
                        << "'");
          return 0;
        }
        vtkSmartPointer<vtkDataArray> at = mdvtk::ToVtkPoints(t->second.Apply(rest))->GetData();
        at->SetName(mdvtk::PointsAt(pose).c_str());
        moved->GetPointData()->AddArray(at);
      }
    }
    vtkNew<vtkFieldData> fieldData;
    fieldData->ShallowCopy(leaves[i].data->GetFieldData());
    vtkNew<vtkStringArray> bodyArray;
    bodyArray->SetName(mdvtk::array::Body);
    bodyArray->InsertNextValue(bodyNames[body]);
    fieldData->AddArray(bodyArray);
    moved->SetFieldData(fieldData);
    results[i] = moved;
  }
  mdvtk::AssignLeaves(input, output, results, mdvtk::Role::AsGiven); // moves whatever it is given
  // The pose's coordinates (BodyTransforms' field data: Time, each coordinate's value,
  // RotationalCoordinates) go with the moved surfaces, for the motion filter's moment arms.
  // A new field data: the output's may be the input's, shared.
  vtkNew<vtkFieldData> pose;
  pose->ShallowCopy(output->GetFieldData());
  for (int a = 0; a < table->GetFieldData()->GetNumberOfArrays(); ++a)
  {
    pose->AddArray(table->GetFieldData()->GetAbstractArray(a));
  }
  output->SetFieldData(pose);
  return 1;
}

void vtkMoveWithBodies::PrintSelf(ostream& os, vtkIndent indent)
{
  this->Superclass::PrintSelf(os, indent);
  os << indent << "BodyOfSurface: " << (this->BodyOfSurface ? this->BodyOfSurface : "") << "\n";
}
