// SPDX-License-Identifier: BSD-3-Clause
#include "MDBlocks.h"

#include "Method/InterpolatedDeformation.h"

#include <vtkStreamingDemandDrivenPipeline.h>

#include <vtkAOSDataArrayTemplate.h>
#include <vtkAbstractArray.h>
#include <vtkAlgorithm.h>
#include <vtkAlgorithmOutput.h>
#include <vtkCellArray.h>
#include <vtkCellArrayIterator.h>
#include <vtkCellData.h>
#include <vtkCompositeDataSet.h>
#include <vtkDataObjectTreeIterator.h>
#include <vtkDoubleArray.h>
#include <vtkFieldData.h>
#include <vtkIdList.h>
#include <vtkIdTypeArray.h>
#include <vtkInformation.h>
#include <vtkInformationVector.h>
#include <vtkIntArray.h>
#include <vtkMultiBlockDataSet.h>
#include <vtkPointData.h>
#include <vtkPoints.h>
#include <vtkPolyData.h>
#include <vtkStringArray.h>
#include <vtkTable.h>
#include <vtkTriangleFilter.h>
#include <vtkUnsignedCharArray.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <optional>
#include <set>
#include <sstream>

namespace mdvtk
{
using md::Points;
using md::TriangleMesh;
using md::Triangles;
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

void AddFieldValue(vtkFieldData* fieldData, const char* name, double value)
{
  vtkNew<vtkDoubleArray> array;
  array->SetName(name);
  array->InsertNextValue(value);
  fieldData->AddArray(array);
}

void AddFieldValue(vtkFieldData* fieldData, const char* name, int value)
{
  vtkNew<vtkIntArray> array;
  array->SetName(name);
  array->InsertNextValue(value);
  fieldData->AddArray(array);
}

void AddFieldValue(vtkFieldData* fieldData, const char* name, std::int64_t value)
{
  AddFieldValue(fieldData, name, static_cast<int>(value));
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

/// Fails, naming the block, on coordinates that are not finite or beyond 1e100, a cell that
/// refers to a point the block does not have, or a point array whose tuples do not match the
/// points: what would otherwise be read past an array's end or overflow.
bool CheckLeaf(vtkPolyData* data, const std::string& label, std::string& error)
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
    return !checkData || CheckLeaf(polyData, inputName, error);
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
      ok = CheckLeaf(polyData, label, error);
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

std::function<void(double)> ProgressOrCancel(vtkAlgorithm* filter, double offset, double share)
{
  return [=](double fraction) {
    filter->UpdateProgress(offset + share * fraction);
    if (filter->CheckAbort())
    {
      throw md::Cancelled();
    }
  };
}

bool ProgressOrStop(vtkAlgorithm* filter, double fraction)
{
  filter->UpdateProgress(fraction);
  return filter->CheckAbort() != 0;
}

bool CallCore(vtkAlgorithm* filter, const std::string& context, const std::function<void()>& work, int& result,
  std::string* reported)
{
  std::string message;
  try
  {
    work();
    return true;
  }
  catch (const md::Error& e) // InputError or ComputationError: the message says which
  {
    message = context + e.what();
  }
  catch (const md::Cancelled&)
  {
    filter->CheckAbort(); // sets AbortOutput: the executive empties the outputs
    result = 1;
    if (reported)
    {
      reported->clear();
    }
    return false;
  }
  catch (const std::bad_alloc&)
  {
    message = context + "out of memory; try fewer hull points or a coarser surface";
  }
  catch (const std::exception& e)
  {
    message = context + "unexpected failure: " + e.what();
  }
  vtkErrorWithObjectMacro(filter, << message);
  result = 0;
  if (reported)
  {
    *reported = message;
  }
  return false;
}

std::string NameOf(const Leaf& leaf)
{
  return leaf.name.empty() ? leaf.label : leaf.name;
}

bool ReadMuscleSurface(const Leaf& leaf, TriangleMesh& surface, std::string& error)
{
  ReadTriangles(leaf.data, surface);
  if (surface.triangles.rows() == 0)
  {
    error = leaf.label + " has no surface (no polygons); a muscle must be a closed triangle surface";
    return false;
  }
  return true;
}

void FailBlock(vtkObject* filter, std::map<size_t, std::string>& failedBlocks, size_t block, const std::string& message,
  bool reported)
{
  if (!reported)
  {
    vtkErrorWithObjectMacro(filter, << message);
  }
  failedBlocks[block] = message;
}

vtkSmartPointer<vtkPolyData> MovedCopy(vtkPolyData* input, const Points& points)
{
  auto output = vtkSmartPointer<vtkPolyData>::New();
  output->ShallowCopy(input);
  vtkNew<vtkFieldData> fieldData;
  fieldData->DeepCopy(input->GetFieldData());
  output->SetFieldData(fieldData);
  output->SetPoints(ToVtkPoints(points));
  return output;
}

vtkSmartPointer<vtkPolyData> MovedMuscle(vtkPolyData* input, const Points& points, const Points& displacement)
{
  vtkSmartPointer<vtkPolyData> output = MovedCopy(input, points);
  output->GetPointData()->AddArray(ToVtkArray(DisplacementArrayName, displacement));
  return output;
}

void AddMeasures(vtkFieldData* fieldData, const std::vector<Measure>& measures)
{
  for (const Measure& measure : measures)
  {
    if (measure.count)
    {
      AddFieldValue(fieldData, measure.name, static_cast<int>(measure.value));
    }
    else
    {
      AddFieldValue(fieldData, measure.name, measure.value);
    }
  }
}

std::vector<Measure> StepMeasures(const md::MuscleStepMeasures& s, int iterations, bool stepShift)
{
  auto count = [](std::int64_t value) {
    return static_cast<double>(value);
  };
  std::vector<Measure> measures = {
    { VolumeChangeArrayName, s.volumeChangePercent },
    { array::NewPenetrationCount, count(s.newPenetrationCount), true },
    { array::MaxNewPenetrationDepth, s.maxNewPenetrationDepth },
    { array::NewBonePenetrationCount, count(s.newBonePenetrationCount), true },
    { array::MaxNewBonePenetrationDepth, s.maxNewBonePenetrationDepth },
    { array::MaxStaticShift, s.maxStaticShift },
  };
  if (stepShift)
  {
    measures.push_back({ array::StepStaticShift, s.stepStaticShift });
  }
  measures.push_back({ array::SharpEdgeCount, count(s.sharpEdgeCount), true });
  measures.push_back({ array::FlippedTriangleCount, count(s.flippedTriangleCount), true });
  measures.push_back({ array::NumberOfIterations, count(iterations), true });
  measures.push_back({ array::Converged, s.converged ? 1.0 : 0.0, true });
  return measures;
}

std::vector<double> StepTimes(int steps)
{
  std::vector<double> times(static_cast<size_t>(steps) + 1);
  for (int j = 0; j <= steps; ++j)
  {
    times[j] = j;
  }
  return times;
}

void AdvertiseTimes(vtkInformationVector* outputVector, const std::vector<double>& times)
{
  using SDDP = vtkStreamingDemandDrivenPipeline;
  for (int port = 0; port < outputVector->GetNumberOfInformationObjects(); ++port)
  {
    vtkInformation* info = outputVector->GetInformationObject(port);
    info->Remove(SDDP::TIME_STEPS());
    info->Remove(SDDP::TIME_RANGE());
    if (!times.empty())
    {
      info->Set(SDDP::TIME_STEPS(), times.data(), static_cast<int>(times.size()));
      const double range[2] = { times.front(), times.back() };
      info->Set(SDDP::TIME_RANGE(), range, 2);
    }
  }
}

int StepAsked(vtkInformation* outInfo, int steps, int fallback)
{
  using SDDP = vtkStreamingDemandDrivenPipeline;
  if (!outInfo->Has(SDDP::UPDATE_TIME_STEP()))
  {
    return fallback;
  }
  const double time = outInfo->Get(SDDP::UPDATE_TIME_STEP());
  return static_cast<int>(std::lround(std::clamp(time, 0.0, static_cast<double>(steps))));
}

void InputsAtTheirOwnTime(vtkInformationVector** inputVector, int ports)
{
  for (int port = 0; port < ports; ++port)
  {
    for (int i = 0; i < inputVector[port]->GetNumberOfInformationObjects(); ++i)
    {
      inputVector[port]->GetInformationObject(i)->Remove(vtkStreamingDemandDrivenPipeline::UPDATE_TIME_STEP());
    }
  }
}

void UpdateInputs(vtkAlgorithm* filter, const std::vector<int>& ports)
{
  for (int port : ports)
  {
    if (filter->GetNumberOfInputConnections(port) > 0)
    {
      filter->GetInputAlgorithm(port, 0)->Update(filter->GetInputConnection(port, 0)->GetIndex());
    }
  }
}

int NearestTime(const std::vector<double>& times, double time)
{
  const auto after = std::lower_bound(times.begin(), times.end(), time);
  size_t k = static_cast<size_t>(after - times.begin());
  if (k == times.size() || (k > 0 && time - times[k - 1] < times[k] - time))
  {
    k = k == 0 ? 0 : k - 1;
  }
  return static_cast<int>(k);
}

int AdvertiseSteps(vtkAlgorithm* filter, vtkInformationVector* outputVector, int numberOfSteps,
  const std::vector<int>& ports, const std::function<int(int& steps)>& automatic, int& resolved)
{
  int steps = numberOfSteps;
  if (steps == 0)
  {
    // The automatic count depends on the inputs' data, which the pipeline only produces after
    // this pass: bring those inputs up to date first.
    UpdateInputs(filter, ports);
    if (const int result = automatic(steps); result != 1 || steps == 0)
    {
      return result;
    }
  }
  resolved = steps;
  AdvertiseTimes(outputVector, StepTimes(steps));
  return 1;
}

void SetDataTime(vtkInformationVector* outputVector, double time)
{
  for (int port = 0; port < outputVector->GetNumberOfInformationObjects(); ++port)
  {
    vtkDataObject::GetData(outputVector, port)->GetInformation()->Set(vtkDataObject::DATA_TIME_STEP(), time);
  }
}

vtkSmartPointer<vtkPolyData> FailedMuscle(vtkPolyData* input, const std::string& message)
{
  auto output = vtkSmartPointer<vtkPolyData>::New();
  if (input)
  {
    output->GetFieldData()->DeepCopy(input->GetFieldData());
  }
  AddFieldValue(output->GetFieldData(), FailedArrayName, 1);
  vtkNew<vtkStringArray> why;
  why->SetName(FailureMessageArrayName);
  why->InsertNextValue(message);
  output->GetFieldData()->AddArray(why);
  return output;
}

std::function<bool()> AbortRequested(vtkAlgorithm* filter)
{
  return [filter] {
    return filter->GetAbortExecute() != 0;
  };
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

void CopyTimeSteps(vtkInformation* from, vtkInformation* to)
{
  using SDDP = vtkStreamingDemandDrivenPipeline;
  to->Remove(SDDP::TIME_STEPS());
  to->Remove(SDDP::TIME_RANGE());
  if (from && from->Has(SDDP::TIME_STEPS()))
  {
    to->CopyEntry(from, SDDP::TIME_STEPS());
  }
  if (from && from->Has(SDDP::TIME_RANGE()))
  {
    to->CopyEntry(from, SDDP::TIME_RANGE());
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

Points ToPoints(vtkDataArray* array)
{
  const vtkIdType n = array ? array->GetNumberOfTuples() : 0;
  Points out(n, 3);
  if (n == 0)
  {
    return out;
  }
  // One call into VTK per array rather than per point: VTK here is built -O0. Scans are usually
  // float: read from its memory directly (a DeepCopy into doubles goes value by value).
  if (auto* floats = vtkAOSDataArrayTemplate<float>::FastDownCast(array))
  {
    if (floats->GetNumberOfComponents() == 3)
    {
      const float* values = floats->GetPointer(0);
      std::copy(values, values + 3 * n, out.data());
      return out;
    }
  }
  vtkSmartPointer<vtkDoubleArray> doubles = vtkDoubleArray::SafeDownCast(array);
  if (!doubles)
  {
    doubles = vtkSmartPointer<vtkDoubleArray>::New();
    doubles->DeepCopy(array);
  }
  std::copy(doubles->GetPointer(0), doubles->GetPointer(0) + 3 * n, out.data());
  return out;
}

Points ToPoints(vtkPoints* points)
{
  return ToPoints(points ? points->GetData() : nullptr);
}

vtkSmartPointer<vtkPoints> ToVtkPoints(const Points& points)
{
  auto out = vtkSmartPointer<vtkPoints>::New();
  out->SetData(ToVtkArray(nullptr, points));
  return out;
}

vtkSmartPointer<vtkDoubleArray> ToVtkArray(const char* name, const Points& values)
{
  auto array = vtkSmartPointer<vtkDoubleArray>::New();
  array->SetName(name);
  array->SetNumberOfComponents(3);
  array->SetNumberOfTuples(values.rows());
  std::copy(values.data(), values.data() + values.size(), array->GetPointer(0));
  return array;
}

vtkSmartPointer<vtkPolyData> ToPolyData(const TriangleMesh& mesh)
{
  auto polyData = vtkSmartPointer<vtkPolyData>::New();
  polyData->SetPoints(ToVtkPoints(mesh.points));
  vtkNew<vtkIdTypeArray> connectivity;
  connectivity->SetNumberOfValues(mesh.triangles.size());
  std::copy(mesh.triangles.data(), mesh.triangles.data() + mesh.triangles.size(), connectivity->GetPointer(0));
  vtkNew<vtkCellArray> polys;
  polys->SetData(3, connectivity);
  polyData->SetPolys(polys);
  return polyData;
}

vtkSmartPointer<vtkPolyData> ToPolyLines(const std::vector<Points>& lines)
{
  Eigen::Index total = 0;
  for (const Points& line : lines)
  {
    total += line.rows();
  }
  Points all(total, 3);
  vtkNew<vtkCellArray> cells;
  vtkIdType next = 0;
  for (const Points& line : lines)
  {
    const auto n = static_cast<vtkIdType>(line.rows());
    all.middleRows(next, n) = line;
    cells->InsertNextCell(n);
    for (vtkIdType k = 0; k < n; ++k)
    {
      cells->InsertCellPoint(next + k);
    }
    next += n;
  }
  auto output = vtkSmartPointer<vtkPolyData>::New();
  output->SetPoints(ToVtkPoints(all));
  output->SetLines(cells);
  return output;
}

std::vector<Points> ToPolylines(vtkPolyData* polyData, const Points* values)
{
  std::vector<Points> lines;
  vtkCellArray* cells = polyData ? polyData->GetLines() : nullptr;
  if (!cells || cells->GetNumberOfCells() == 0)
  {
    return lines;
  }
  const Points all = values ? Points() : ToPoints(polyData->GetPoints());
  const Points& source = values ? *values : all;
  auto it = vtk::TakeSmartPointer(cells->NewIterator());
  for (it->GoToFirstCell(); !it->IsDoneWithTraversal(); it->GoToNextCell())
  {
    vtkIdType size;
    const vtkIdType* ids;
    it->GetCurrentCell(size, ids);
    Points line(size, 3);
    for (vtkIdType k = 0; k < size; ++k)
    {
      line.row(k) = source.row(ids[k]);
    }
    lines.push_back(std::move(line));
  }
  return lines;
}

/// The polygons of `input` as triangles (polygons and strips triangulated).
/// Returns the number of cells that were not triangles.
vtkIdType ReadTriangles(vtkPolyData* input, TriangleMesh& mesh)
{
  vtkIdType converted = input->GetNumberOfStrips();
  vtkCellArray* polys = input->GetPolys();
  if (polys->IsHomogeneous() != 3)
  {
    auto it = vtk::TakeSmartPointer(polys->NewIterator());
    for (it->GoToFirstCell(); !it->IsDoneWithTraversal(); it->GoToNextCell())
    {
      converted += it->GetCurrentCell()->GetNumberOfIds() != 3 ? 1 : 0;
    }
  }
  vtkSmartPointer<vtkPolyData> triangles = input;
  if (converted > 0)
  {
    vtkNew<vtkTriangleFilter> triangulate;
    triangulate->SetInputData(input);
    triangulate->PassVertsOff();
    triangulate->PassLinesOff();
    triangulate->Update();
    triangles = triangulate->GetOutput();
  }
  mesh.points = ToPoints(triangles->GetPoints());
  vtkCellArray* cells = triangles->GetPolys();
  if (cells->GetNumberOfConnectivityIds() == 3 * cells->GetNumberOfCells())
  {
    vtkNew<vtkIdTypeArray> connectivity;
    connectivity->DeepCopy(cells->GetConnectivityArray());
    mesh.triangles.resize(cells->GetNumberOfCells(), 3);
    std::copy(connectivity->GetPointer(0), connectivity->GetPointer(0) + mesh.triangles.size(), mesh.triangles.data());
    return converted;
  }
  // Cells the triangulation left as they were (polygons of one or two points): not triangles.
  std::vector<std::int64_t> ids;
  auto it = vtk::TakeSmartPointer(cells->NewIterator());
  for (it->GoToFirstCell(); !it->IsDoneWithTraversal(); it->GoToNextCell())
  {
    vtkIdType size;
    const vtkIdType* cell;
    it->GetCurrentCell(size, cell);
    if (size == 3)
    {
      ids.insert(ids.end(), cell, cell + 3);
    }
  }
  mesh.triangles.resize(static_cast<Eigen::Index>(ids.size() / 3), 3);
  std::copy(ids.begin(), ids.end(), mesh.triangles.data());
  return converted;
}
bool ReadMeshes(vtkInformationVector* port, const std::string& portName, std::vector<std::string>& names,
  std::vector<TriangleMesh>& meshes, std::string& error)
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
      if (!leaf.data)
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
