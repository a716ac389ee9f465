// SPDX-License-Identifier: BSD-3-Clause
// Time in the filters: the steps an interpolating filter advertises and is asked for, the times a
// motion's frames pass on. Not part of the public API.
#pragma once

#include <functional>
#include <vector>

class vtkAlgorithm;
class vtkInformation;
class vtkInformationVector;

namespace mdvtk
{
/// The time steps (TIME_STEPS) `info` advertises; none for none or a null `info`.
std::vector<double> TimesOf(vtkInformation* info);
/// Advertises the time steps and range of `from` (an input's information) on `to` (an output's),
/// or none when `from` has none.
void CopyTimeSteps(vtkInformation* from, vtkInformation* to);

/// The time steps 0, 1, ..., `steps` of a filter whose time is its interpolation step.
std::vector<double> StepTimes(int steps);
/// Advertises `times` (TIME_STEPS and TIME_RANGE) on every output of `outputVector`, or none
/// when `times` is empty.
void AdvertiseTimes(vtkInformationVector* outputVector, const std::vector<double>& times);
/// The interpolation step asked of output `outInfo` (its UPDATE_TIME_STEP rounded into
/// [0, steps]), or `fallback` when none is asked.
int StepAsked(vtkInformation* outInfo, int steps, int fallback);
/// Asks the inputs of ports 0 .. `ports` - 1 for their default time (a filter whose time is its
/// interpolation step, not one of its inputs').
void InputsAtTheirOwnTime(vtkInformationVector** inputVector, int ports);
/// Brings the inputs of `ports` up to date, for RequestInformation to read their data.
void UpdateInputs(vtkAlgorithm* filter, const std::vector<int>& ports);
/// RequestInformation of a filter whose time is its interpolation step: `numberOfSteps` steps, or
/// when that is 0 as many as `automatic` finds (called once the inputs of `ports` are up to date;
/// it returns RequestInformation's result, and sets `steps` when that is 1), advertised as the
/// times 0 ... N on every output, N in `resolved`. Returns RequestInformation's result.
int AdvertiseSteps(vtkAlgorithm* filter, vtkInformationVector* outputVector, int numberOfSteps,
  const std::vector<int>& ports, const std::function<int(int& steps)>& automatic, int& resolved);
/// Index of the entry of `times` (ascending, not empty) nearest `time`; the earlier one at a tie.
int NearestTime(const std::vector<double>& times, double time);
/// Stamps every output of `outputVector` with DATA_TIME_STEP `time`.
void SetDataTime(vtkInformationVector* outputVector, double time);
}
