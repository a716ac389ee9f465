// SPDX-License-Identifier: BSD-3-Clause
#include "vtkInterpolatedMuscleDeformation.h"

#include "ActionLineMatching.h"
#include "InterpolatedDeformation.h"
#include "LocalFrame.h"
#include "MDBlocks.h"

#include <vtkAlgorithmOutput.h>
#include <vtkDoubleArray.h>
#include <vtkFieldData.h>
#include <vtkInformation.h>
#include <vtkInformationVector.h>
#include <vtkObjectFactory.h>
#include <vtkPointData.h>
#include <vtkPolyData.h>
#include <vtkStreamingDemandDrivenPipeline.h>
#include <vtkStringArray.h>
#include <vtkTable.h>

#include <algorithm>
#include <cmath>
#include <map>

vtkStandardNewMacro(vtkInterpolatedMuscleDeformation);

/// Every step of the last run, kept for the animation, with what it was computed from.
struct vtkInterpolatedMuscleDeformation::Cache
{
  vtkMTimeType inputsTime = 0;
  vtkMTimeType filterTime = 0;
  std::vector<size_t> blockOf;                // block of each muscle
  std::map<size_t, std::string> failedBlocks; // muscles that could not be deformed, and why
  md::InterpolationResult result;
  // What outputs 1 and 2 show at each step: the bones and matched action lines moved as the
  // method moved them (the same interpolators, in the same local frame).
  md::LocalFrame frame;
  std::vector<md::PoseInterpolator> boneMotions;
  std::vector<size_t> boneLeaf;                               // BonesRest leaf of each bone
  std::vector<std::vector<md::PoseInterpolator>> lineMotions; // per muscle
  std::vector<size_t> lineLeaf;                               // ActionLinesRest leaf of each muscle
};

namespace
{
const char* const PortNames[] = { "Input", "BonesRest", "BonesCurrent", "ActionLinesRest", "ActionLinesCurrent" };

}

vtkInterpolatedMuscleDeformation::vtkInterpolatedMuscleDeformation()
  : Computed(std::make_unique<Cache>())
  , KeptRest(std::make_unique<md::RestMappingCache>())
{
  this->SetNumberOfInputPorts(5);
  this->SetNumberOfOutputPorts(4);
}

int vtkInterpolatedMuscleDeformation::GetHullBuildCount() const
{
  return this->KeptRest->hullBuildCount;
}

int vtkInterpolatedMuscleDeformation::GetSurfaceEnergyBuildCount() const
{
  return this->KeptRest->energyBuildCount;
}

int vtkInterpolatedMuscleDeformation::FillOutputPortInformation(int port, vtkInformation* info)
{
  if (port == 3)
  {
    info->Set(vtkDataObject::DATA_TYPE_NAME(), "vtkTable");
    return 1;
  }
  return this->Superclass::FillOutputPortInformation(port, info);
}

int vtkInterpolatedMuscleDeformation::RequestDataObject(
  vtkInformation*, vtkInformationVector** inputVector, vtkInformationVector* outputVector)
{
  // Each output has the type of the input it follows: muscles, bones, action lines; then the table.
  mdvtk::OutputsFollowInputs(inputVector, outputVector, { 0, 1, 3 }, 3);
  return 1;
}

vtkInterpolatedMuscleDeformation::~vtkInterpolatedMuscleDeformation() = default;

int vtkInterpolatedMuscleDeformation::FillInputPortInformation(int, vtkInformation* info)
{
  mdvtk::AcceptPolyDataOrMultiBlock(info);
  return 1;
}

int vtkInterpolatedMuscleDeformation::RequestInformation(
  vtkInformation*, vtkInformationVector** inputVector, vtkInformationVector* outputVector)
{
  int steps = this->NumberOfSteps;
  if (steps == 0)
  {
    // The automatic count depends on the bones, which the pipeline only
    // produces after this pass: bring those inputs up to date first.
    for (int port = 1; port <= 2; ++port)
    {
      if (this->GetNumberOfInputConnections(port) > 0)
      {
        this->GetInputAlgorithm(port, 0)->Update(this->GetInputConnection(port, 0)->GetIndex());
      }
    }
    std::vector<md::BoneMotion> bones;
    std::string error;
    if (!mdvtk::ReadBones(nullptr, vtkDataObject::GetData(inputVector[1], 0), PortNames[1],
          vtkDataObject::GetData(inputVector[2], 0), PortNames[2], bones, error))
    {
      vtkErrorMacro(<< error);
      return 0;
    }
    md::InterpolationParameters parameters;
    parameters.numberOfSteps = 0;
    parameters.maximumStepDisplacement = this->MaximumStepDisplacement; // bones in world units here
    int result = 1;
    if (!mdvtk::CallCore(
          this, "", [&] { steps = md::ResolveNumberOfSteps(bones, parameters); }, result))
    {
      return result;
    }
  }
  this->ResolvedNumberOfSteps = steps;
  std::vector<double> times(static_cast<size_t>(steps) + 1);
  for (int j = 0; j <= steps; ++j)
  {
    times[j] = j;
  }
  const double range[2] = { 0.0, static_cast<double>(steps) };
  for (int port = 0; port < this->GetNumberOfOutputPorts(); ++port)
  {
    vtkInformation* outInfo = outputVector->GetInformationObject(port);
    outInfo->Set(vtkStreamingDemandDrivenPipeline::TIME_STEPS(), times.data(), steps + 1);
    outInfo->Set(vtkStreamingDemandDrivenPipeline::TIME_RANGE(), range, 2);
  }
  return 1;
}

int vtkInterpolatedMuscleDeformation::RequestUpdateExtent(
  vtkInformation*, vtkInformationVector** inputVector, vtkInformationVector* outputVector)
{
  mdvtk::ClearOutputs(outputVector);
  // Our time is the interpolation step, not a time of the inputs.
  for (int port = 0; port < 5; ++port)
  {
    for (int i = 0; i < inputVector[port]->GetNumberOfInformationObjects(); ++i)
    {
      inputVector[port]->GetInformationObject(i)->Remove(vtkStreamingDemandDrivenPipeline::UPDATE_TIME_STEP());
    }
  }
  return 1;
}

int vtkInterpolatedMuscleDeformation::RequestData(
  vtkInformation* request, vtkInformationVector** inputVector, vtkInformationVector* outputVector)
{
  vtkDataObject* input = vtkDataObject::GetData(inputVector[0], 0);
  vtkDataObject* inputs[5];
  vtkMTimeType inputsTime = 0;
  for (int port = 0; port < 5; ++port)
  {
    inputs[port] = vtkDataObject::GetData(inputVector[port], 0);
    inputsTime = std::max(inputsTime, inputs[port] ? inputs[port]->GetMTime() : 0);
  }
  std::vector<mdvtk::Leaf> muscles;
  std::string error;
  if (!mdvtk::CollectLeaves(input, PortNames[0], muscles, error))
  {
    vtkErrorMacro(<< error);
    return 0;
  }

  Cache& cache = *this->Computed;
  if (cache.result.points.empty() || cache.inputsTime != inputsTime || cache.filterTime != this->GetMTime() ||
    cache.result.numberOfSteps != this->ResolvedNumberOfSteps)
  {
    cache = Cache{};
    // Everything is read and checked before any work.
    std::vector<mdvtk::Leaf> restLines, currentLines;
    std::vector<size_t> restLinesOf, currentLinesOf;
    std::vector<md::BoneMotion> bones;
    if (!mdvtk::CollectLeaves(inputs[3], PortNames[3], restLines, error) ||
      !mdvtk::CollectLeaves(inputs[4], PortNames[4], currentLines, error) ||
      !mdvtk::PairLeaves(this, muscles, PortNames[0], restLines, PortNames[3], restLinesOf, error) ||
      !mdvtk::PairLeaves(this, restLines, PortNames[3], currentLines, PortNames[4], currentLinesOf, error) ||
      !mdvtk::ReadBones(this, inputs[1], PortNames[1], inputs[2], PortNames[2], bones, error, &cache.boneLeaf))
    {
      vtkErrorMacro(<< error);
      return 0;
    }
    // One muscle's fault is reported and that muscle left out; the others go on.
    auto fail = [&](size_t block, const std::string& message, bool reported = false) {
      if (!reported)
      {
        vtkErrorMacro(<< message);
      }
      cache.failedBlocks[block] = message;
    };
    // Everything in the muscles' local frame from here on, the matching of the action lines
    // too: the same answer wherever the data sits and whatever its units.
    std::vector<md::MuscleMotion> motions;
    for (size_t b = 0; b < muscles.size(); ++b)
    {
      const mdvtk::Leaf& leaf = muscles[b];
      if (!leaf.data)
      {
        continue;
      }
      md::MuscleMotion motion;
      motion.name = leaf.name.empty() ? leaf.label : leaf.name;
      mdvtk::ReadTriangles(leaf.data, motion.muscle);
      if (motion.muscle.triangles.rows() == 0)
      {
        fail(b, leaf.label + " has no surface (no polygons); a muscle must be a closed triangle surface");
        continue;
      }
      motions.push_back(std::move(motion));
      cache.blockOf.push_back(b);
    }
    std::vector<md::Points> worldMuscles; // the rest pose as given: step 0 shows it exactly
    std::vector<const md::Points*> restPoints;
    for (const md::MuscleMotion& motion : motions)
    {
      worldMuscles.push_back(motion.muscle.points);
    }
    for (const md::Points& points : worldMuscles)
    {
      restPoints.push_back(&points);
    }
    const md::LocalFrame frame = md::LocalFrame::Around(restPoints);
    for (md::BoneMotion& bone : bones)
    {
      frame.ToLocal(bone.rest.points);
      frame.ToLocal(bone.current);
    }
    std::vector<md::MuscleMotion> matched; // the muscles whose lines could be matched
    std::vector<size_t> matchedBlocks;
    std::vector<const md::Points*> matchedRest;
    for (size_t m = 0; m < motions.size(); ++m)
    {
      md::MuscleMotion& motion = motions[m];
      const size_t b = cache.blockOf[m];
      const mdvtk::Leaf& leaf = muscles[b];
      frame.ToLocal(motion.muscle.points);
      const mdvtk::Leaf& restLeaf = restLines[restLinesOf[b]];
      const mdvtk::Leaf& currentLeaf = currentLines[currentLinesOf[restLinesOf[b]]];
      std::vector<md::Points> rest = restLeaf.data ? mdvtk::ToPolylines(restLeaf.data) : std::vector<md::Points>{};
      std::vector<md::Points> current =
        currentLeaf.data ? mdvtk::ToPolylines(currentLeaf.data) : std::vector<md::Points>{};
      for (auto* lines : { &rest, &current })
      {
        for (md::Points& line : *lines)
        {
          frame.ToLocal(line);
        }
      }
      if (rest.empty())
      {
        fail(b,
          restLeaf.label + " has no polylines: muscle " + leaf.label +
            " needs its action lines, or nothing says where it goes");
        continue;
      }
      if (rest.size() != current.size())
      {
        fail(b,
          restLeaf.label + " has " + std::to_string(rest.size()) + " action lines but " + currentLeaf.label + " has " +
            std::to_string(current.size()) + ": the lines of a muscle pair by order");
        continue;
      }
      int result = 1;
      std::string failure;
      if (!mdvtk::CallCore(
            this, "an action line of " + restLeaf.label + " or " + currentLeaf.label + ": ",
            [&] {
              for (size_t l = 0; l < rest.size(); ++l)
              {
                const md::MatchedActionLines pair = md::MatchActionLines(rest[l], current[l], this->MatchingTolerance);
                motion.lines.push_back({ pair.rest, pair.current });
              }
              for (const std::string& note : md::LimitActionLinePoints(motion.lines))
              {
                vtkWarningMacro(<< restLeaf.label << ": " << note);
              }
            },
            result, &failure))
      {
        if (failure.empty())
        {
          return result; // stopped by the user
        }
        fail(b, failure, true);
        continue;
      }
      cache.lineMotions.emplace_back();
      for (const md::MatchedLine& line : motion.lines)
      {
        cache.lineMotions.back().emplace_back(
          line.rest, line.current, static_cast<md::InterpolationMode>(this->BoneInterpolationMode));
      }
      cache.lineLeaf.push_back(restLinesOf[b]);
      matched.push_back(std::move(motion));
      matchedBlocks.push_back(b);
      matchedRest.push_back(&worldMuscles[m]);
    }

    md::InterpolationParameters parameters;
    parameters.numberOfSteps = this->ResolvedNumberOfSteps;
    parameters.maximumStepDisplacement = frame.LengthToLocal(this->MaximumStepDisplacement);
    parameters.interpolationMode = static_cast<md::InterpolationMode>(this->BoneInterpolationMode);
    parameters.settleOnSurface = this->DeformationMesh == MUSCLE_SURFACE;
    parameters.hullMode = static_cast<md::HullMode>(this->HullMode);
    parameters.refitRegularisation = this->RefitRegularisation;
    parameters.staticResolve.deformableShare = this->DeformableShare;
    parameters.deformation.maximumIterations = this->MaximumNumberOfIterations;
    parameters.deformation.convergenceTolerance = frame.LengthToLocal(this->ConvergenceTolerance);
    parameters.deformation.preserveVolume = this->PreserveVolume;
    parameters.deformation.contactWeight = this->BoneContactWeight;
    parameters.hull.targetNumberOfPoints = this->HullTargetNumberOfPoints;
    parameters.hull.cancelled = mdvtk::AbortRequested(this);
    if (matched.empty() && !cache.failedBlocks.empty())
    {
      cache = Cache{};
      return 0; // every muscle failed, each said why (no muscle at all is the core's error)
    }
    motions = std::move(matched);
    cache.blockOf = std::move(matchedBlocks);
    restPoints = std::move(matchedRest);
    int result = 1;
    if (!mdvtk::CallCore(
          this, "",
          [&] {
            cache.result = md::DeformByInterpolation(
              motions, bones, parameters, mdvtk::ProgressOrCancel(this), this->KeptRest.get());
          },
          result))
    {
      cache = Cache{};
      return result;
    }
    md::ResultToWorld(frame, restPoints, cache.result);
    for (size_t m = 0; m < motions.size(); ++m)
    {
      if (!cache.result.failures[m].empty())
      {
        fail(cache.blockOf[m], muscles[cache.blockOf[m]].label + ": " + cache.result.failures[m]);
      }
    }
    cache.frame = frame;
    for (const md::BoneMotion& bone : bones)
    {
      cache.boneMotions.emplace_back(
        bone.rest.points, bone.current, static_cast<md::InterpolationMode>(this->BoneInterpolationMode));
    }
    for (const std::string& warning : cache.result.warnings)
    {
      vtkWarningMacro(<< warning);
    }
    cache.inputsTime = inputsTime;
    cache.filterTime = this->GetMTime();
  }

  const md::InterpolationResult& r = cache.result;
  const int steps = r.numberOfSteps;
  // The time asked for on the port whose request this is: all three outputs show that step.
  int port = request->Has(vtkDemandDrivenPipeline::FROM_OUTPUT_PORT())
    ? request->Get(vtkDemandDrivenPipeline::FROM_OUTPUT_PORT())
    : 0;
  port = port < 0 || port >= this->GetNumberOfOutputPorts() ? 0 : port;
  vtkInformation* outInfo = outputVector->GetInformationObject(port);
  int step = steps;
  if (outInfo->Has(vtkStreamingDemandDrivenPipeline::UPDATE_TIME_STEP()))
  {
    const double time = outInfo->Get(vtkStreamingDemandDrivenPipeline::UPDATE_TIME_STEP());
    step = static_cast<int>(std::lround(std::clamp(time, 0.0, static_cast<double>(steps))));
  }
  // Time j is step j of N: after N changes the same time is another point of the motion. Said,
  // not silent, when the view stays on the time it showed before the change.
  if (this->ShownNumberOfSteps > 0 && steps != this->ShownNumberOfSteps && step == this->ShownStep && step != 0)
  {
    vtkWarningMacro(<< "NumberOfSteps is now " << steps << ": time " << step << " shows step " << step << " of "
                    << steps << " (" << 100.0 * step / steps << " % of the motion), where it showed step " << step
                    << " of " << this->ShownNumberOfSteps << " (" << 100.0 * step / this->ShownNumberOfSteps
                    << " %); time " << steps << " is the current pose");
  }
  this->ShownNumberOfSteps = steps;
  this->ShownStep = step;
  std::vector<vtkSmartPointer<vtkPolyData>> outputs(muscles.size());
  std::vector<std::string> names;                                   // Measures rows
  std::vector<std::pair<std::string, std::vector<double>>> columns; // Measures columns
  std::vector<size_t> failedRows;                                   // muscles not deformed: NaN
  std::map<size_t, size_t> muscleOfBlock;
  for (size_t m = 0; m < cache.blockOf.size(); ++m)
  {
    muscleOfBlock[cache.blockOf[m]] = m; // failedBlocks has the core's failures too: they go first
  }
  for (size_t b = 0; b < muscles.size(); ++b)
  {
    const auto failed = cache.failedBlocks.find(b);
    const auto found = muscleOfBlock.find(b);
    if (failed == cache.failedBlocks.end() && found == muscleOfBlock.end())
    {
      continue; // an empty block
    }
    names.push_back(muscles[b].name.empty() ? muscles[b].label : muscles[b].name);
    if (failed != cache.failedBlocks.end())
    {
      outputs[b] = mdvtk::FailedMuscle(muscles[b].data, failed->second);
      failedRows.push_back(names.size() - 1);
      continue;
    }
    const size_t m = found->second;
    const md::Points& points = r.points[step][m];
    const md::Points& rest = r.points[0][m];
    const md::MuscleStepMeasures& s = r.measures[step][m];
    auto output = vtkSmartPointer<vtkPolyData>::New();
    output->ShallowCopy(muscles[b].data);
    output->SetPoints(mdvtk::ToVtkPoints(points));
    output->GetPointData()->AddArray(mdvtk::ToVtkArray(mdvtk::DisplacementArrayName, points - rest));
    // No static move at step 0: zeros.
    output->GetPointData()->AddArray(mdvtk::ToVtkArray(mdvtk::StaticShiftArrayName,
      s.staticShift.rows() ? s.staticShift : md::Points(md::Points::Zero(points.rows(), 3))));
    double hullSeconds = r.restHullSeconds[m];
    for (int j = 1; j <= step; ++j)
    {
      hullSeconds += r.measures[j][m].hullSeconds;
    }
    vtkNew<vtkFieldData> fieldData;
    fieldData->DeepCopy(muscles[b].data->GetFieldData());
    // Each measure goes to the muscle's field data and to its row of the Measures table.
    size_t measureIndex = 0;
    auto measure = [&](const char* name, auto value) {
      mdvtk::AddFieldValue(fieldData, name, value);
      if (columns.size() <= measureIndex)
      {
        columns.emplace_back(name, std::vector<double>());
      }
      columns[measureIndex].second.resize(names.size() - 1, std::nan("")); // the failed rows before
      columns[measureIndex++].second.push_back(static_cast<double>(value));
    };
    measure(mdvtk::VolumeChangeArrayName, s.volumeChangePercent);
    measure("NewPenetrationCount", s.newPenetrationCount);
    measure("MaxNewPenetrationDepth", s.maxNewPenetrationDepth);
    measure("NewBonePenetrationCount", s.newBonePenetrationCount);
    measure("MaxNewBonePenetrationDepth", s.maxNewBonePenetrationDepth);
    measure("MaxStaticShift", s.maxStaticShift);
    measure("StepStaticShift", s.stepStaticShift);
    measure("SharpEdgeCount", s.sharpEdgeCount);
    measure("FlippedTriangleCount", s.flippedTriangleCount);
    measure("NumberOfIterations", s.iterations);
    measure("Converged", s.converged ? 1 : 0);
    measure("PointsFrozenInObstacles", s.pointsFrozenInObstacles);
    measure("InterpolationStep", step);
    measure("NumberOfSteps", steps);
    measure("HullSeconds", hullSeconds);
    measure("StepSeconds", r.stepSeconds[step]);
    measure("ElapsedSeconds", r.totalSeconds);
    output->SetFieldData(fieldData);
    outputs[b] = output;
  }
  mdvtk::AssignLeaves(input, vtkDataObject::GetData(outputVector, 0), outputs, mdvtk::Role::Muscle);

  // Output 3: the same measures as a table, one row per muscle, for a spreadsheet view.
  vtkTable* table = vtkTable::GetData(outputVector, 3);
  vtkNew<vtkStringArray> muscleColumn;
  muscleColumn->SetName("Muscle");
  for (const std::string& name : names)
  {
    muscleColumn->InsertNextValue(name);
  }
  table->AddColumn(muscleColumn);
  columns.emplace_back(mdvtk::FailedArrayName, std::vector<double>(names.size(), 0.0));
  for (size_t row : failedRows)
  {
    columns.back().second[row] = 1;
  }
  for (auto& [name, values] : columns)
  {
    values.resize(names.size(), std::nan("")); // the failed rows after the last deformed one
    vtkNew<vtkDoubleArray> column;
    column->SetName(name.c_str());
    for (double value : values)
    {
      column->InsertNextValue(value);
    }
    table->AddColumn(column);
  }

  // Outputs 1 and 2: the bones and the matched action lines at the same step, as the method
  // moved them, so that the muscles are never shown against bones of another step.
  std::vector<mdvtk::Leaf> boneLeaves, lineLeaves;
  if (!mdvtk::CollectLeaves(inputs[1], PortNames[1], boneLeaves, error) ||
    !mdvtk::CollectLeaves(inputs[3], PortNames[3], lineLeaves, error))
  {
    vtkErrorMacro(<< error);
    return 0;
  }
  std::vector<vtkSmartPointer<vtkPolyData>> boneOutputs(boneLeaves.size());
  for (size_t k = 0; k < cache.boneMotions.size(); ++k)
  {
    md::Points points = cache.boneMotions[k].AtStep(step, steps);
    cache.frame.ToWorld(points);
    auto bone = vtkSmartPointer<vtkPolyData>::New();
    bone->ShallowCopy(boneLeaves[cache.boneLeaf[k]].data);
    bone->SetPoints(mdvtk::ToVtkPoints(points));
    boneOutputs[cache.boneLeaf[k]] = bone;
  }
  mdvtk::AssignLeaves(inputs[1], vtkDataObject::GetData(outputVector, 1), boneOutputs, mdvtk::Role::Bone);
  std::vector<vtkSmartPointer<vtkPolyData>> lineOutputs(lineLeaves.size());
  for (size_t m = 0; m < cache.lineMotions.size(); ++m)
  {
    std::vector<md::Points> lines;
    for (const md::PoseInterpolator& line : cache.lineMotions[m])
    {
      lines.push_back(line.AtStep(step, steps));
      cache.frame.ToWorld(lines.back());
    }
    lineOutputs[cache.lineLeaf[m]] = mdvtk::ToPolyLines(lines);
  }
  mdvtk::AssignLeaves(inputs[3], vtkDataObject::GetData(outputVector, 2), lineOutputs, mdvtk::Role::ActionLine);
  for (int p = 0; p < this->GetNumberOfOutputPorts(); ++p)
  {
    vtkDataObject::GetData(outputVector, p)
      ->GetInformation()
      ->Set(vtkDataObject::DATA_TIME_STEP(), static_cast<double>(step));
  }
  this->UpdateProgress(1.0);
  return 1;
}

void vtkInterpolatedMuscleDeformation::PrintSelf(ostream& os, vtkIndent indent)
{
  this->Superclass::PrintSelf(os, indent);
  os << indent << "NumberOfSteps: " << this->NumberOfSteps << "\n";
  os << indent << "MaximumStepDisplacement: " << this->MaximumStepDisplacement << "\n";
  os << indent << "BoneInterpolationMode: " << this->BoneInterpolationMode << "\n";
  os << indent << "DeformationMesh: " << this->DeformationMesh << "\n";
  os << indent << "HullMode: " << this->HullMode << "\n";
  os << indent << "MatchingTolerance: " << this->MatchingTolerance << "\n";
  os << indent << "DeformableShare: " << this->DeformableShare << "\n";
  os << indent << "MaximumNumberOfIterations: " << this->MaximumNumberOfIterations << "\n";
  os << indent << "ConvergenceTolerance: " << this->ConvergenceTolerance << "\n";
  os << indent << "PreserveVolume: " << this->PreserveVolume << "\n";
  os << indent << "HullTargetNumberOfPoints: " << this->HullTargetNumberOfPoints << "\n";
  os << indent << "BoneContactWeight: " << this->BoneContactWeight << "\n";
  os << indent << "RefitRegularisation: " << this->RefitRegularisation << "\n";
  os << indent << "ResolvedNumberOfSteps: " << this->ResolvedNumberOfSteps << "\n";
  os << indent << "HullBuildCount: " << this->GetHullBuildCount() << "\n";
  os << indent << "SurfaceEnergyBuildCount: " << this->GetSurfaceEnergyBuildCount() << "\n";
}
