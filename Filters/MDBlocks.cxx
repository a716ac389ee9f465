// SPDX-License-Identifier: BSD-3-Clause
#include "MDBlocks.h"

#include "MDConvert.h"

#include "Method/InterpolatedDeformation.h"

#include <vtkAOSDataArrayTemplate.h>
#include <vtkAbstractArray.h>
#include <vtkAlgorithm.h>
#include <vtkCellArray.h>
#include <vtkCellArrayIterator.h>
#include <vtkCellData.h>
#include <vtkCompositeDataSet.h>
#include <vtkDataArray.h>
#include <vtkDataObjectTreeIterator.h>
#include <vtkFieldData.h>
#include <vtkIdTypeArray.h>
#include <vtkInformation.h>
#include <vtkInformationVector.h>
#include <vtkMultiBlockDataSet.h>
#include <vtkPointData.h>
#include <vtkPoints.h>
#include <vtkPolyData.h>
#include <vtkTable.h>
#include <vtkUnsignedCharArray.h>

#include <algorithm>
#include <map>
#include <optional>
#include <set>
#include <sstream>

namespace mdvtk
{
using md::Points;

namespace
{
template<typename Visitor>
void ForEachLeaf(vtkMultiBlockDataSet* tree, Visitor&& visit)
{
  vtkSmartPointer<vtkDataObjectTreeIterator> it;
  it.TakeReference(tree->NewTreeIterator());
  it->VisitOnlyLeavesOn();
  it->SkipEmptyNodesOff();
  it->TraverseSubTreeOn();
  for (it->InitTraversal(); !it->IsDoneWithTraversal(); it->GoToNextItem())
  {
    visit(it.Get());
  }
}
}

void AcceptPolyDataOrMultiBlock(vtkInformation* info)
{
  info->Remove(vtkAlgorithm::INPUT_REQUIRED_DATA_TYPE());
  info->Append(vtkAlgorithm::INPUT_REQUIRED_DATA_TYPE(), "vtkPolyData");
  info->Append(vtkAlgorithm::INPUT_REQUIRED_DATA_TYPE(), "vtkMultiBlockDataSet");
}

namespace
{
/// The first of `count` ids outside [0, points), if any.
template<typename Value>
std::optional<vtkIdType> FirstOutOfRange(const Value* ids, vtkIdType count, vtkIdType points)
{
  for (vtkIdType i = 0; i < count; ++i)
  {
    if (ids[i] < 0 || static_cast<vtkIdType>(ids[i]) >= points)
    {
      return static_cast<vtkIdType>(ids[i]);
    }
  }
  return std::nullopt;
}

/// The same for a cell array's connectivity, read in place when it is of VTK's usual storage.
std::optional<vtkIdType> FirstIdOutOfRange(vtkDataArray* ids, vtkIdType points)
{
  const vtkIdType count = ids->GetNumberOfValues();
  if (auto* wide = vtkAOSDataArrayTemplate<vtkTypeInt64>::FastDownCast(ids))
  {
    return FirstOutOfRange(wide->GetPointer(0), count, points);
  }
  if (auto* narrow = vtkAOSDataArrayTemplate<vtkTypeInt32>::FastDownCast(ids))
  {
    return FirstOutOfRange(narrow->GetPointer(0), count, points);
  }
  vtkNew<vtkIdTypeArray> copy;
  copy->DeepCopy(ids);
  return FirstOutOfRange(copy->GetPointer(0), count, points);
}
}

bool CheckPolyData(vtkPolyData* data, const std::string& label, std::string& error)
{
  const vtkIdType points = data->GetNumberOfPoints();
  // Coordinates: finite, and small enough that products of three of them (volumes) stay finite.
  const Points coordinates = ToPoints(data->GetPoints());
  for (Eigen::Index i = 0; i < coordinates.rows(); ++i)
  {
    if (!coordinates.row(i).allFinite())
    {
      error = label + " has NaN or infinite coordinates (point " + std::to_string(i) + ")";
      return false;
    }
    if (coordinates.row(i).cwiseAbs().maxCoeff() > 1e100)
    {
      error = label + " has coordinates beyond 1e100 in magnitude (point " + std::to_string(i) +
        "), where the geometry's arithmetic would overflow";
      return false;
    }
  }
  vtkCellArray* cellArrays[4] = { data->GetVerts(), data->GetLines(), data->GetPolys(), data->GetStrips() };
  static const char* kinds[4] = { "vertex", "line", "polygon", "strip" };
  for (int k = 0; k < 4; ++k)
  {
    vtkCellArray* cells = cellArrays[k];
    if (!cells || cells->GetNumberOfConnectivityIds() == 0)
    {
      continue;
    }
    // Every id is read (not the array's cached range, which an array changed without
    // Modified() would leave stale).
    const std::optional<vtkIdType> bad = FirstIdOutOfRange(cells->GetConnectivityArray(), points);
    if (bad)
    {
      error = label + " has a " + kinds[k] + " cell that refers to point " + std::to_string(*bad) + ", but it has " +
        std::to_string(points) + " points (ids 0 to " + std::to_string(points - 1) + ")";
      return false;
    }
  }
  vtkPointData* pointData = data->GetPointData();
  for (int a = 0; a < pointData->GetNumberOfArrays(); ++a)
  {
    vtkAbstractArray* array = pointData->GetAbstractArray(a);
    if (array && array->GetNumberOfTuples() != points)
    {
      error = label + ": point array '" + (array->GetName() ? array->GetName() : "") + "' has " +
        std::to_string(array->GetNumberOfTuples()) + " values but the block has " + std::to_string(points) + " points";
      return false;
    }
  }
  return true;
}

namespace
{
bool CollectLeaves(
  vtkDataObject* input, const std::string& inputName, std::vector<Leaf>& leaves, std::string& error, bool checkData)
{
  leaves.clear();
  if (!input)
  {
    error = inputName + " is missing";
    return false;
  }
  if (auto* polyData = vtkPolyData::SafeDownCast(input))
  {
    leaves.push_back(Leaf{ "", polyData, inputName });
    return !checkData || CheckPolyData(polyData, inputName, error);
  }
  auto* tree = vtkMultiBlockDataSet::SafeDownCast(input);
  if (!tree)
  {
    error =
      inputName + " is a " + input->GetClassName() + "; it must be a vtkPolyData or a vtkMultiBlockDataSet of them";
    return false;
  }
  bool ok = true;
  ForEachLeaf(tree, [&](vtkDataObjectTreeIterator* it) {
    std::string name;
    if (it->HasCurrentMetaData() && it->GetCurrentMetaData()->Has(vtkCompositeDataSet::NAME()))
    {
      name = it->GetCurrentMetaData()->Get(vtkCompositeDataSet::NAME());
    }
    const std::string label =
      inputName + " block " + (name.empty() ? "#" + std::to_string(leaves.size()) : "'" + name + "'");
    vtkDataObject* leaf = it->GetCurrentDataObject();
    auto* polyData = vtkPolyData::SafeDownCast(leaf);
    if (leaf && !polyData && ok)
    {
      error = label + " is a " + leaf->GetClassName() + ", not a vtkPolyData";
      ok = false;
    }
    if (polyData && ok && checkData)
    {
      ok = CheckPolyData(polyData, label, error);
    }
    leaves.push_back(Leaf{ name, polyData, label });
  });
  if (ok && leaves.empty())
  {
    error = inputName + " is a multiblock with no blocks";
    ok = false;
  }
  return ok;
}
}

bool CollectLeaves(vtkDataObject* input, const std::string& inputName, std::vector<Leaf>& leaves, std::string& error)
{
  return CollectLeaves(input, inputName, leaves, error, true);
}

bool CollectLeaves(vtkDataObject* input, const std::string& inputName, std::vector<Leaf>& leaves, std::string& error,
  InputCheck& checked)
{
  const vtkMTimeType time = DataMTime(input); // the checks modify nothing
  if (!CollectLeaves(input, inputName, leaves, error, !checked.Unchanged(input, time)))
  {
    return false;
  }
  checked.Passed(input, time);
  return true;
}

vtkMTimeType DataMTime(vtkDataObject* input)
{
  vtkMTimeType latest = input ? input->GetMTime() : 0;
  if (auto* tree = vtkMultiBlockDataSet::SafeDownCast(input))
  {
    ForEachLeaf(tree, [&](vtkDataObjectTreeIterator* it) {
      if (vtkDataObject* leaf = it->GetCurrentDataObject())
      {
        latest = std::max(latest, leaf->GetMTime());
      }
    });
  }
  return latest;
}

bool PairLeaves(vtkObject* reporter, const std::vector<Leaf>& a, const std::string& nameA, const std::vector<Leaf>& b,
  const std::string& nameB, std::vector<size_t>& partner, std::string& error)
{
  partner.assign(a.size(), 0);
  auto uniquelyNamed = [](const std::vector<Leaf>& leaves) {
    std::set<std::string> names;
    for (const Leaf& leaf : leaves)
    {
      if (leaf.name.empty() || !names.insert(leaf.name).second)
      {
        return false;
      }
    }
    return true;
  };
  std::map<std::string, size_t> indexOfName;
  for (size_t j = 0; j < b.size(); ++j)
  {
    indexOfName[b[j].name] = j;
  }
  size_t shared = 0;
  for (const Leaf& leaf : a)
  {
    shared += !leaf.name.empty() && indexOfName.count(leaf.name) ? 1 : 0;
  }
  const bool aNamed = uniquelyNamed(a), bNamed = uniquelyNamed(b);
  if (aNamed && bNamed && (shared > 0 || a.size() != b.size()))
  {
    // Names that pair some blocks but not all are a mistake (a block left out or renamed), not
    // a reason to fall back to the order, which would pair the wrong muscles.
    for (size_t i = 0; i < a.size(); ++i)
    {
      auto found = indexOfName.find(a[i].name);
      if (found == indexOfName.end())
      {
        error = a[i].label + " has no block of the same name in " + nameB;
        return false;
      }
      partner[i] = found->second;
      indexOfName.erase(found);
    }
    if (!indexOfName.empty())
    {
      error = b[indexOfName.begin()->second].label + " has no block of the same name in " + nameA;
      return false;
    }
    return true;
  }
  if (a.size() != b.size())
  {
    error = nameA + " has " + std::to_string(a.size()) + " block(s) but " + nameB + " has " + std::to_string(b.size()) +
      "; blocks pair by name when both inputs name them alike, or else by order";
    return false;
  }
  for (size_t i = 0; i < a.size(); ++i)
  {
    partner[i] = i;
  }
  // Named blocks that share no name (the GUI names the blocks of Group Datasets after its
  // inputs: 'femur_r.vtk' against 'Transform1') pair by order; say which with which.
  if (reporter && a.size() > 1 && shared == 0 && (aNamed || bNamed))
  {
    std::string pairs;
    for (size_t i = 0; i < a.size() && i < 4; ++i)
    {
      pairs += (i ? ", '" : "'") + a[i].name + "' with '" + b[i].name + "'";
    }
    vtkWarningWithObjectMacro(
      reporter, << nameA << " and " << nameB << " share no block name, so their blocks pair by order: " << pairs
                << (a.size() > 4 ? ", ..." : "") << ". Give the blocks the same names to pair them by name.");
  }
  return true;
}

void OutputsFollowInputs(vtkInformationVector** inputVector, vtkInformationVector* outputVector,
  const std::vector<int>& followed, int tablePort)
{
  if (!vtkTable::GetData(outputVector, tablePort))
  {
    vtkNew<vtkTable> table;
    outputVector->GetInformationObject(tablePort)->Set(vtkDataObject::DATA_OBJECT(), table);
  }
  for (size_t port = 0; port < followed.size(); ++port)
  {
    vtkDataObject* input = vtkDataObject::GetData(inputVector[followed[port]], 0);
    if (!input)
    {
      continue;
    }
    vtkInformation* info = outputVector->GetInformationObject(static_cast<int>(port));
    vtkDataObject* output = vtkDataObject::GetData(info);
    if (!output || !output->IsA(input->GetClassName()))
    {
      vtkSmartPointer<vtkDataObject> made;
      made.TakeReference(input->NewInstance());
      info->Set(vtkDataObject::DATA_OBJECT(), made);
    }
  }
}

void ClearOutputs(vtkInformationVector* outputVector)
{
  for (int port = 0; port < outputVector->GetNumberOfInformationObjects(); ++port)
  {
    if (vtkDataObject* output = vtkDataObject::GetData(outputVector, port))
    {
      output->Initialize();
    }
  }
}

namespace
{
void MarkRole(vtkPolyData* leaf, Role role, size_t index)
{
  vtkCellData* cells = leaf->GetCellData();
  const int value = role == Role::Muscle ? static_cast<int>(Role::Muscle) + static_cast<int>(index % MuscleShades)
                                         : static_cast<int>(role);
  auto array = vtkSmartPointer<vtkUnsignedCharArray>::New();
  array->SetName(RoleArrayName);
  array->SetNumberOfTuples(leaf->GetNumberOfCells());
  array->Fill(value);
  cells->AddArray(array);
  if (!cells->GetScalars() && !leaf->GetPointData()->GetScalars())
  {
    cells->SetActiveScalars(RoleArrayName);
  }
}
}

void MarkRoles(vtkDataObject* data, Role role)
{
  if (role == Role::AsGiven)
  {
    return;
  }
  if (auto* polyData = vtkPolyData::SafeDownCast(data))
  {
    MarkRole(polyData, role, 0);
  }
  else if (auto* tree = vtkMultiBlockDataSet::SafeDownCast(data))
  {
    size_t index = 0;
    ForEachLeaf(tree, [&](vtkDataObjectTreeIterator* it) {
      if (auto* leaf = vtkPolyData::SafeDownCast(it->GetCurrentDataObject()))
      {
        MarkRole(leaf, role, index);
      }
      ++index;
    });
  }
}

std::string DefaultDisplaySettings()
{
  // Muscle shades that tell neighbours apart and still read as muscle; bone ivory; action
  // lines a blue that stands out against both.
  const double muscles[MuscleShades][3] = { { 0.78, 0.24, 0.22 }, { 0.91, 0.55, 0.47 }, { 0.60, 0.13, 0.16 },
    { 0.85, 0.42, 0.27 }, { 0.84, 0.35, 0.46 }, { 0.68, 0.31, 0.22 }, { 0.95, 0.67, 0.60 }, { 0.72, 0.18, 0.32 } };
  const double bone[3] = { 0.89, 0.85, 0.76 };
  const double line[3] = { 0.10, 0.35, 0.85 };
  const double hull[3] = { 0.20, 0.62, 0.50 };
  std::ostringstream annotations, colours;
  auto add = [&](int value, const std::string& text, const double* rgb) {
    annotations << (annotations.tellp() > 0 ? ", " : "") << '"' << value << "\", \"" << text << '"';
    colours << (colours.tellp() > 0 ? ", " : "") << rgb[0] << ", " << rgb[1] << ", " << rgb[2];
  };
  add(static_cast<int>(Role::Bone), "Bone", bone);
  for (int k = 0; k < MuscleShades; ++k)
  {
    add(static_cast<int>(Role::Muscle) + k, "Muscle " + std::to_string(k + 1), muscles[k]);
  }
  add(static_cast<int>(Role::ActionLine), "Action line", line);
  add(static_cast<int>(Role::Hull), "Hull", hull);
  std::ostringstream json;
  json << "{ \"array_lookup_tables\": { \"" << RoleArrayName << "\": { \"PVLookupTable\": { "
       << "\"IndexedLookup\": 1, \"AnnotationsInitialized\": 1, "
       << "\"Annotations\": [" << annotations.str() << "], \"IndexedColors\": [" << colours.str() << "] } } }, "
       << "\"representations\": { \"" << ActionLinesRepresentation << "\": { "
       << "\"LineWidth\": 4, \"RenderLinesAsTubes\": 1 } } }";
  return json.str();
}

void AddBlock(vtkMultiBlockDataSet* tree, const std::string& name, vtkDataObject* block)
{
  const unsigned int index = tree->GetNumberOfBlocks();
  tree->SetBlock(index, block);
  tree->GetMetaData(index)->Set(vtkCompositeDataSet::NAME(), name.c_str());
}

void AssignLeaves(
  vtkDataObject* input, vtkDataObject* output, const std::vector<vtkSmartPointer<vtkPolyData>>& results, Role role)
{
  if (auto* polyData = vtkPolyData::SafeDownCast(output))
  {
    if (!results.empty() && results.front())
    {
      polyData->ShallowCopy(results.front());
    }
    MarkRoles(output, role);
    return;
  }
  auto* inTree = vtkMultiBlockDataSet::SafeDownCast(input);
  auto* outTree = vtkMultiBlockDataSet::SafeDownCast(output);
  if (!inTree || !outTree)
  {
    return;
  }
  outTree->CopyStructure(inTree);
  size_t index = 0;
  ForEachLeaf(inTree, [&](vtkDataObjectTreeIterator* it) {
    if (index < results.size())
    {
      outTree->SetDataSet(it, results[index]);
    }
    ++index;
  });
  MarkRoles(output, role);
}

std::string NameOf(const Leaf& leaf)
{
  return leaf.name.empty() ? leaf.label : leaf.name;
}

bool ReadMuscleSurface(const Leaf& leaf, TriangleMesh& surface, std::string& error, vtkIdType* converted)
{
  const vtkIdType notTriangles = ReadTriangles(leaf.data, surface);
  if (converted)
  {
    *converted = notTriangles;
  }
  if (surface.triangles.rows() == 0)
  {
    error = leaf.label + " has no surface (no polygons); a muscle must be a closed triangle surface";
    return false;
  }
  return true;
}

bool ReadMeshes(vtkInformationVector* port, const std::string& portName, std::vector<std::string>& names,
  std::vector<TriangleMesh>& meshes, std::string& error, bool skipEmpty)
{
  for (int c = 0; c < port->GetNumberOfInformationObjects(); ++c)
  {
    std::vector<Leaf> leaves;
    const std::string name = portName + " connection " + std::to_string(c + 1);
    if (!CollectLeaves(vtkDataObject::GetData(port, c), name, leaves, error))
    {
      return false;
    }
    for (const Leaf& leaf : leaves)
    {
      if (!leaf.data || (skipEmpty && leaf.data->GetNumberOfPoints() == 0))
      {
        continue;
      }
      TriangleMesh mesh;
      ReadTriangles(leaf.data, mesh);
      if (mesh.triangles.rows() == 0)
      {
        error = leaf.label + " is not a usable mesh: it has no triangles";
        return false;
      }
      names.push_back(leaf.name.empty() ? leaf.label : leaf.name);
      meshes.push_back(std::move(mesh));
    }
  }
  return true;
}

bool ReadBones(vtkObject* reporter, vtkDataObject* rest, const std::string& restName, vtkDataObject* current,
  const std::string& currentName, std::vector<md::BoneMotion>& bones, std::string& error,
  std::vector<size_t>* leafOfBone)
{
  std::vector<Leaf> restLeaves, currentLeaves;
  std::vector<size_t> partner;
  if (!CollectLeaves(rest, restName, restLeaves, error) || !CollectLeaves(current, currentName, currentLeaves, error) ||
    !PairLeaves(reporter, restLeaves, restName, currentLeaves, currentName, partner, error))
  {
    return false;
  }
  for (size_t b = 0; b < restLeaves.size(); ++b)
  {
    const Leaf& r = restLeaves[b];
    const Leaf& c = currentLeaves[partner[b]];
    if (!r.data && !c.data)
    {
      continue; // an empty block in both poses
    }
    if (!r.data || !c.data)
    {
      // Dropping it would silently take an obstacle away.
      error = (r.data ? c.label : r.label) + " is empty but " + (r.data ? r.label : c.label) +
        " is not: a bone needs its surface in both poses";
      return false;
    }
    md::BoneMotion bone;
    bone.name = r.name.empty() ? r.label : r.name;
    ReadTriangles(r.data, bone.rest);
    bone.current = ToPoints(c.data->GetPoints());
    if (bone.rest.points.rows() != bone.current.rows())
    {
      error = r.label + " has " + std::to_string(bone.rest.points.rows()) + " points but " + c.label + " has " +
        std::to_string(bone.current.rows()) + ": a bone must have the same points in both poses";
      return false;
    }
    if (bone.rest.triangles.rows() == 0)
    {
      error = r.label + " has no surface (no polygons)";
      return false;
    }
    bones.push_back(std::move(bone));
    if (leafOfBone)
    {
      leafOfBone->push_back(b);
    }
  }
  return true;
}
}
