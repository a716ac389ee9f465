// SPDX-License-Identifier: BSD-3-Clause
#include "MDReport.h"

#include "Method/InterpolatedDeformation.h"

#include <vtkAlgorithm.h>
#include <vtkDoubleArray.h>
#include <vtkFieldData.h>
#include <vtkInformation.h>
#include <vtkIntArray.h>
#include <vtkPolyData.h>
#include <vtkStringArray.h>

#include <map>

namespace mdvtk
{

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

void FailBlock(vtkObject* filter, std::map<size_t, std::string>& failedBlocks, size_t block, const std::string& message,
  bool reported)
{
  if (!reported)
  {
    vtkErrorWithObjectMacro(filter, << message);
  }
  failedBlocks[block] = message;
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

std::string UpstreamFailure(vtkPolyData* block)
{
  auto* why =
    block ? vtkStringArray::SafeDownCast(block->GetFieldData()->GetAbstractArray(FailureMessageArrayName)) : nullptr;
  return why && why->GetNumberOfValues() > 0 ? " (left out upstream: " + why->GetValue(0) + ")" : "";
}

std::function<bool()> AbortRequested(vtkAlgorithm* filter)
{
  return [filter] {
    return filter->GetAbortExecute() != 0;
  };
}
}
