// SPDX-License-Identifier: BSD-3-Clause
#include "vtkActionLineGrouping.h"

#include "Common/Fnv1a.h"
#include "MDBlocks.h"
#include "MDConvert.h"
#include "MDReport.h"
#include "MDTime.h"
#include "OpenSim/OpenSimAttachment.h"

#include <vtkAppendPolyData.h>
#include <vtkCellData.h>
#include <vtkCompositeDataSet.h>
#include <vtkDoubleArray.h>
#include <vtkFieldData.h>
#include <vtkInformation.h>
#include <vtkInformationVector.h>
#include <vtkMultiBlockDataSet.h>
#include <vtkObjectFactory.h>
#include <vtkOutputWindow.h>
#include <vtkPointData.h>
#include <vtkPolyData.h>
#include <vtkSmartPointer.h>
#include <vtkStringArray.h>

#include <cstdint>
#include <map>
#include <sstream>

vtkStandardNewMacro(vtkActionLineGrouping);

struct vtkActionLineGrouping::Grouped
{
  std::vector<md::TriangleMesh> muscles;
  std::vector<md::Points> paths;
  std::vector<std::string> muscleNames, pathNames;
  std::string assignments;
  md::osim::PathGrouping grouping;
  std::string decision;
  /// The muscles no path runs inside, and why: named failed blocks, the others go on.
  std::map<size_t, std::string> failed;
  /// Output 0 (the rest pose's paths grouped) as built from paths with `pathsDigest`: the same
  /// while the grouping and the paths are, so it is not built again at every frame.
  vtkSmartPointer<vtkMultiBlockDataSet> pathsOutput;
  std::uint64_t pathsDigest = 0;

  bool DecidedOn(const std::vector<md::TriangleMesh>& otherMuscles, const std::vector<md::Points>& otherPaths,
    const std::vector<std::string>& otherMuscleNames, const std::vector<std::string>& otherPathNames,
    const std::string& otherAssignments) const
  {
    auto sameMesh = [](const md::TriangleMesh& a, const md::TriangleMesh& b) {
      return a.points.rows() == b.points.rows() && a.triangles.rows() == b.triangles.rows() && a.points == b.points &&
        a.triangles == b.triangles;
    };
    auto samePoints = [](const md::Points& a, const md::Points& b) {
      return a.rows() == b.rows() && a == b;
    };
    return otherAssignments == this->assignments && otherMuscleNames == this->muscleNames &&
      otherPathNames == this->pathNames &&
      std::equal(otherMuscles.begin(), otherMuscles.end(), this->muscles.begin(), this->muscles.end(), sameMesh) &&
      std::equal(otherPaths.begin(), otherPaths.end(), this->paths.begin(), this->paths.end(), samePoints);
  }
};

namespace
{
/// A hash (FNV-1a) of everything of the paths that output 0 copies: their point and cell counts
/// and every point and cell array's name, type and values.
std::uint64_t PathsDigest(const std::vector<mdvtk::Leaf>& paths)
{
  md::Fnv1a hash;
  auto addNumber = [&](long long value) {
    hash.Add(value);
  };
  for (const mdvtk::Leaf& path : paths)
  {
    vtkPolyData* data = path.data;
    addNumber(data ? data->GetNumberOfPoints() : -1);
    addNumber(data ? data->GetNumberOfCells() : -1);
    if (!data)
    {
      continue;
    }
    for (vtkFieldData* arrays :
      { static_cast<vtkFieldData*>(data->GetPointData()), static_cast<vtkFieldData*>(data->GetCellData()) })
    {
      addNumber(arrays->GetNumberOfArrays());
      for (int a = 0; a < arrays->GetNumberOfArrays(); ++a)
      {
        vtkAbstractArray* array = arrays->GetAbstractArray(a);
        const std::string name = array->GetName() ? array->GetName() : "";
        hash.Add(name.data(), name.size() + 1);
        addNumber(array->GetDataType());
        addNumber(array->GetNumberOfValues());
        if (auto* strings = vtkStringArray::SafeDownCast(array))
        {
          for (vtkIdType v = 0; v < strings->GetNumberOfValues(); ++v)
          {
            const std::string& value = strings->GetValue(v);
            hash.Add(value.data(), value.size() + 1);
          }
        }
        else if (auto* numbers = vtkDataArray::SafeDownCast(array))
        {
          hash.Add(numbers->GetVoidPointer(0),
            static_cast<size_t>(numbers->GetNumberOfValues()) * static_cast<size_t>(numbers->GetDataTypeSize()));
        }
        else
        {
          addNumber(reinterpret_cast<std::uintptr_t>(array)); // another kind: never taken as the same
        }
      }
    }
  }
  return hash.Value();
}
}

vtkActionLineGrouping::vtkActionLineGrouping()
  : Checked(new mdvtk::InputCheck[2])
{
  this->SetNumberOfInputPorts(3);
  this->SetNumberOfOutputPorts(2);
}

vtkActionLineGrouping::~vtkActionLineGrouping()
{
  this->SetPathsOfMuscle(nullptr);
}

int vtkActionLineGrouping::FillInputPortInformation(int port, vtkInformation* info)
{
  mdvtk::AcceptPolyDataOrMultiBlock(info);
  if (port == 2)
  {
    info->Set(vtkAlgorithm::INPUT_IS_OPTIONAL(), 1);
  }
  return 1;
}

int vtkActionLineGrouping::RequestInformation(
  vtkInformation*, vtkInformationVector** inputVector, vtkInformationVector* outputVector)
{
  // The current pose's paths carry the motion's time.
  mdvtk::CopyTimeSteps(inputVector[2]->GetInformationObject(0), outputVector->GetInformationObject(1));
  return 1;
}

int vtkActionLineGrouping::RequestUpdateExtent(
  vtkInformation* request, vtkInformationVector** inputVector, vtkInformationVector* outputVector)
{
  mdvtk::ClearOutputs(outputVector); // no stale result if an input fails upstream
  return this->Superclass::RequestUpdateExtent(request, inputVector, outputVector);
}

/// The inputs as read: the muscles (`meshes`, named `muscleNames`) and the paths at rest
/// (`lines`, named `pathNames`), and the current pose's paths (`current`, the partner of path p
/// is current[currentOf[p]]) when connected.
struct vtkActionLineGrouping::Inputs
{
  std::vector<mdvtk::Leaf> muscles, paths, current;
  std::vector<size_t> currentOf;
  bool haveCurrent = false;
  std::vector<md::TriangleMesh> meshes;
  std::vector<md::Points> lines;
  std::vector<std::string> muscleNames, pathNames;
};

int vtkActionLineGrouping::RequestData(
  vtkInformation*, vtkInformationVector** inputVector, vtkInformationVector* outputVector)
{
  this->Decision.clear();
  Inputs in;
  if (!this->ReadInputs(inputVector, in))
  {
    return 0;
  }
  const std::string assignments = this->PathsOfMuscle ? this->PathsOfMuscle : "";
  if (this->LastGrouping &&
    this->LastGrouping->DecidedOn(in.meshes, in.lines, in.muscleNames, in.pathNames, assignments))
  {
    this->Decision = this->LastGrouping->decision;
  }
  else
  {
    this->LastGrouping.reset();
    int result = 1;
    if (!this->Group(in, assignments, result))
    {
      return result;
    }
  }
  vtkMultiBlockDataSet* grouped = vtkMultiBlockDataSet::GetData(outputVector, 0);
  const std::uint64_t digest = PathsDigest(in.paths);
  if (this->LastGrouping->pathsOutput && this->LastGrouping->pathsDigest == digest)
  {
    grouped->ShallowCopy(this->LastGrouping->pathsOutput);
  }
  else
  {
    this->BuildGrouped(in, false, grouped);
    mdvtk::MarkRoles(grouped, mdvtk::Role::ActionLine);
    this->LastGrouping->pathsOutput = vtkSmartPointer<vtkMultiBlockDataSet>::New();
    this->LastGrouping->pathsOutput->ShallowCopy(grouped);
    this->LastGrouping->pathsDigest = digest;
  }
  if (in.haveCurrent)
  {
    this->BuildGrouped(in, true, vtkMultiBlockDataSet::GetData(outputVector, 1));
    mdvtk::MarkRoles(vtkMultiBlockDataSet::GetData(outputVector, 1), mdvtk::Role::ActionLine);
  }
  return 1;
}

bool vtkActionLineGrouping::ReadInputs(vtkInformationVector** inputVector, Inputs& in)
{
  std::string error;
  in.haveCurrent = inputVector[2]->GetNumberOfInformationObjects() > 0;
  if (!mdvtk::CollectLeaves(vtkDataObject::GetData(inputVector[0], 0), "Input", in.muscles, error, this->Checked[0]) ||
    !mdvtk::CollectLeaves(vtkDataObject::GetData(inputVector[1], 0), "Paths", in.paths, error, this->Checked[1]) ||
    (in.haveCurrent &&
      (!mdvtk::CollectLeaves(vtkDataObject::GetData(inputVector[2], 0), "PathsCurrent", in.current, error) ||
        !mdvtk::PairLeaves(this, in.paths, "Paths", in.current, "PathsCurrent", in.currentOf, error))))
  {
    vtkErrorMacro(<< error);
    return false;
  }
  in.meshes.resize(in.muscles.size());
  for (size_t m = 0; m < in.muscles.size(); ++m)
  {
    const mdvtk::Leaf& muscle = in.muscles[m];
    if (!muscle.data || mdvtk::ReadTriangles(muscle.data, in.meshes[m]) < 0 || in.meshes[m].triangles.rows() == 0)
    {
      vtkErrorMacro(<< muscle.label << " has no triangles: the muscles must be closed surfaces");
      return false;
    }
    in.muscleNames.push_back(muscle.name.empty() ? "muscle " + std::to_string(m) : muscle.name);
  }
  for (size_t p = 0; p < in.paths.size(); ++p)
  {
    const mdvtk::Leaf& path = in.paths[p];
    const std::vector<md::Points> polylines = path.data ? mdvtk::ToPolylines(path.data) : std::vector<md::Points>();
    if (polylines.size() != 1 || polylines[0].rows() < 2)
    {
      vtkErrorMacro(<< path.label << " must hold one polyline of at least 2 points (one path)");
      return false;
    }
    in.lines.push_back(polylines[0]);
    in.pathNames.push_back(path.name.empty() ? "path " + std::to_string(p) : path.name);
  }
  return true;
}

bool vtkActionLineGrouping::Group(Inputs& in, const std::string& assignments, int& result)
{
  md::osim::PathGrouping decided;
  if (!mdvtk::CallCore(
        this, "PathsOfMuscle: ",
        [&] {
          decided = md::osim::GroupPaths(
            in.meshes, in.muscleNames, in.lines, in.pathNames, md::osim::ParseAssignments(assignments));
        },
        result))
  {
    return false;
  }
  std::ostringstream decision, unassigned;
  for (size_t p = 0; p < in.paths.size(); ++p)
  {
    if (decided.muscleOfPath[p] < 0)
    {
      unassigned << (unassigned.tellp() > 0 ? ", " : "") << in.pathNames[p];
      continue;
    }
    decision << in.pathNames[p] << " -> " << in.muscleNames[decided.muscleOfPath[p]] << " ("
             << (decided.assignedByUser[p] ? "as given, " : "")
             << static_cast<int>(100 * decided.insideFraction[p] + 0.5) << " % of its length inside)\n";
  }
  // A muscle no path reaches is left out, named, as a failed block; the others go on.
  std::map<size_t, std::string> failed;
  for (size_t m = 0; m < in.muscles.size(); ++m)
  {
    if (std::find(decided.muscleOfPath.begin(), decided.muscleOfPath.end(), static_cast<int>(m)) ==
      decided.muscleOfPath.end())
    {
      mdvtk::FailBlock(this, failed, m,
        in.muscles[m].label + ": no path runs inside this muscle (at least 5 % of a path's length); name its paths " +
          "in PathsOfMuscle (e.g. " + in.muscleNames[m] + "=" + in.pathNames.front() + ")");
    }
  }
  if (failed.size() == in.muscles.size())
  {
    result = 0;
    return false; // nothing left to group, each failure said
  }
  this->Decision = decision.str();
  vtkOutputWindow::GetInstance()->DisplayText(("ActionLineGrouping:\n" + this->Decision).c_str());
  if (unassigned.tellp() > 0)
  {
    vtkWarningMacro(<< "paths that run inside no muscle (less than 5 % of their length) are left out: "
                    << unassigned.str());
  }
  this->LastGrouping.reset(new Grouped{
    std::move(in.meshes), in.lines, in.muscleNames, in.pathNames, assignments, decided, this->Decision, failed });
  return true;
}

void vtkActionLineGrouping::BuildGrouped(const Inputs& in, bool current, vtkMultiBlockDataSet* output)
{
  const md::osim::PathGrouping& grouping = this->LastGrouping->grouping;
  // Its ExecuteAppend only, on paths that are never empty: no pipeline pass per muscle (at every
  // frame of a motion, a third of this filter's time went on those passes).
  vtkNew<vtkAppendPolyData> append;
  for (size_t m = 0; m < in.muscles.size(); ++m)
  {
    const auto failed = this->LastGrouping->failed.find(m);
    if (failed != this->LastGrouping->failed.end())
    {
      mdvtk::AddBlock(output, in.muscleNames[m], mdvtk::FailedMuscle(nullptr, failed->second));
      continue;
    }
    std::vector<vtkSmartPointer<vtkPolyData>> copies;
    vtkNew<vtkStringArray> names;
    names->SetName("ActionLinePaths");
    vtkNew<vtkDoubleArray> shares;
    shares->SetName("PathInsideFraction");
    for (size_t p = 0; p < in.paths.size(); ++p)
    {
      if (grouping.muscleOfPath[p] != static_cast<int>(m))
      {
        continue;
      }
      vtkPolyData* line = current ? in.current[in.currentOf[p]].data : in.paths[p].data;
      auto copy = vtkSmartPointer<vtkPolyData>::New();
      copy->ShallowCopy(line);
      copy->GetFieldData()->Initialize();
      if (!copy->GetCellData()->GetAbstractArray(mdvtk::array::ActionLineName))
      {
        vtkNew<vtkStringArray> lineName;
        lineName->SetName(mdvtk::array::ActionLineName);
        lineName->InsertNextValue(in.pathNames[p]);
        copy->GetCellData()->AddArray(lineName);
      }
      copies.push_back(copy);
      names->InsertNextValue(in.pathNames[p]);
      shares->InsertNextValue(grouping.insideFraction[p]);
    }
    std::vector<vtkPolyData*> inputs(copies.begin(), copies.end());
    auto block = vtkSmartPointer<vtkPolyData>::New();
    append->ExecuteAppend(block, inputs.data(), static_cast<int>(inputs.size()));
    block->GetFieldData()->AddArray(names);
    block->GetFieldData()->AddArray(shares);
    mdvtk::AddBlock(output, in.muscleNames[m], block);
  }
}

void vtkActionLineGrouping::PrintSelf(ostream& os, vtkIndent indent)
{
  this->Superclass::PrintSelf(os, indent);
  os << indent << "PathsOfMuscle: " << (this->PathsOfMuscle ? this->PathsOfMuscle : "") << "\n";
}
