// SPDX-License-Identifier: BSD-3-Clause
#include "MDTime.h"

#include <vtkStreamingDemandDrivenPipeline.h>

#include <vtkAlgorithm.h>
#include <vtkAlgorithmOutput.h>
#include <vtkDataObject.h>
#include <vtkInformation.h>
#include <vtkInformationVector.h>

#include <algorithm>
#include <cmath>

namespace mdvtk
{
std::vector<double> TimesOf(vtkInformation* info)
{
  if (!info || !info->Has(vtkStreamingDemandDrivenPipeline::TIME_STEPS()))
  {
    return {};
  }
  const double* values = info->Get(vtkStreamingDemandDrivenPipeline::TIME_STEPS());
  return std::vector<double>(values, values + info->Length(vtkStreamingDemandDrivenPipeline::TIME_STEPS()));
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
}
