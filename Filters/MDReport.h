// SPDX-License-Identifier: BSD-3-Clause
// Calling the core from a filter and reporting what came of it: the one guard (CallCore),
// progress and the user's stop, one muscle's failure, and the measures written to field data.
// Not part of the public API.
#pragma once

#include "MDBlocks.h"

#include <vtkSmartPointer.h>

#include <cstdint>
#include <functional>
#include <map>
#include <string>
#include <vector>

class vtkAlgorithm;
class vtkFieldData;
class vtkObject;
class vtkPolyData;

namespace md
{
struct MuscleStepMeasures;
}

namespace mdvtk
{
/// Adds a one-value array to field data (a double, or an int for counts).
void AddFieldValue(vtkFieldData* fieldData, const char* name, double value);
void AddFieldValue(vtkFieldData* fieldData, const char* name, int value);
void AddFieldValue(vtkFieldData* fieldData, const char* name, std::int64_t value);

/// A progress callback for the core: reports `offset + share * fraction` as the filter's
/// progress and throws md::Cancelled when the user has asked the filter to stop (ParaView's
/// abort). Call only from the filter's own thread.
std::function<void(double)> ProgressOrCancel(vtkAlgorithm* filter, double offset = 0.0, double share = 1.0);
/// Reports `fraction` as the filter's progress; true when the user has asked it to stop (the
/// executive then empties the outputs, and RequestData returns 1).
bool ProgressOrStop(vtkAlgorithm* filter, double fraction);
/// Runs `work` (calls into the core) and turns the core's exceptions into what a filter reports:
/// md::InputError becomes an error (`context` + its message) and RequestData's result 0;
/// md::Cancelled (the user stopped the run) notes the abort, so that the executive empties the
/// outputs, and the result 1. Returns true when `work` completed; otherwise `result` is what
/// RequestData returns, and `reported` (optional) receives the error reported (empty when the
/// user stopped the run), for a filter that goes on with its other muscles.
bool CallCore(vtkAlgorithm* filter, const std::string& context, const std::function<void()>& work, int& result,
  std::string* reported = nullptr);

/// Reports `message` as an error of `filter` (unless `reported`) and records it as the failure of
/// muscle block `block`: one muscle's fault leaves that muscle out, the others go on.
void FailBlock(vtkObject* filter, std::map<size_t, std::string>& failedBlocks, size_t block, const std::string& message,
  bool reported = false);

/// One measure of a muscle, as the filters write it: to the muscle's field data (an int array for
/// a count, a double array otherwise) and to a column of their measures table.
struct Measure
{
  const char* name;
  double value;
  bool count = false;
};
/// Adds each of `measures` to `fieldData` (AddFieldValue).
void AddMeasures(vtkFieldData* fieldData, const std::vector<Measure>& measures);
/// What a muscle's step of the method, or frame of a motion, measured, in the order the filters
/// write it: `iterations` is the count to report, `stepShift` adds StepStaticShift.
std::vector<Measure> StepMeasures(const md::MuscleStepMeasures& s, int iterations, bool stepShift);

/// The output block of a muscle that could not be processed: no geometry (nothing silently
/// wrong to show), the input block's field data, and DeformationFailed / FailureMessage.
vtkSmartPointer<vtkPolyData> FailedMuscle(vtkPolyData* input, const std::string& message);
/// " (left out upstream: <why>)" for a block an earlier filter failed (its FailureMessage), or "":
/// for a message that says why the block is empty.
std::string UpstreamFailure(vtkPolyData* block);
/// Whether the user has asked `filter` to stop; safe to ask from worker threads (it only reads
/// the flag), for md::HullParameters::cancelled.
std::function<bool()> AbortRequested(vtkAlgorithm* filter);
}
