// SPDX-License-Identifier: BSD-3-Clause
#include "vtkInterpolatedMuscleDeformation.h"

#include "Anatomy/MuscleFibres.h"
#include "Geometry/LocalFrame.h"
#include "MDAttachments.h"
#include "MDBlocks.h"
#include "MDConvert.h"
#include "MDFibres.h"
#include "MDReport.h"
#include "MDTime.h"
#include "Method/InterpolatedDeformation.h"
#include "Motion/ActionLineMatching.h"

#include <vtkAlgorithmOutput.h>
#include <vtkCompositeDataSet.h>
#include <vtkDoubleArray.h>
#include <vtkFieldData.h>
#include <vtkInformation.h>
#include <vtkInformationVector.h>
#include <vtkMultiBlockDataSet.h>
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
  std::shared_ptr<const mdvtk::MadeFibres> fibres;            // per muscle, in `frame`, and the bones' rest trees
};

/// The muscles' action lines as given: ActionLinesRest leaf restOf[b] of muscle block b, and
/// ActionLinesCurrent leaf currentOf[r] of rest leaf r.
struct vtkInterpolatedMuscleDeformation::Lines
{
  std::vector<mdvtk::Leaf> rest, current;
  std::vector<size_t> restOf, currentOf;
};

namespace
{
const char* const PortNames[] = { "Input", "BonesRest", "BonesCurrent", "ActionLinesRest", "ActionLinesCurrent",
  "Attachments" };
constexpr int kAttachmentsPort = 5;
constexpr int kTablePort = 3, kFibresPort = 4;

/// Output 3: a row per muscle, a column per measure (NaN in the rows of the muscles that failed),
/// then DeformationFailed.
class MeasuresTable
{
public:
  void AddRow(const std::string& name, const std::vector<mdvtk::Measure>& measures)
  {
    this->Names.push_back(name);
    this->Failed.push_back(0.0);
    for (size_t k = 0; k < measures.size(); ++k)
    {
      if (this->Columns.size() <= k)
      {
        this->Columns.emplace_back(measures[k].name, std::vector<double>());
      }
      this->Columns[k].second.resize(this->Names.size() - 1, std::nan("")); // the failed rows before
      this->Columns[k].second.push_back(measures[k].value);
    }
  }
  void AddFailedRow(const std::string& name)
  {
    this->Names.push_back(name);
    this->Failed.push_back(1.0);
  }
  void WriteTo(vtkTable* table)
  {
    vtkNew<vtkStringArray> muscleColumn;
    muscleColumn->SetName("Muscle");
    for (const std::string& name : this->Names)
    {
      muscleColumn->InsertNextValue(name);
    }
    table->AddColumn(muscleColumn);
    this->Columns.emplace_back(mdvtk::FailedArrayName, this->Failed);
    for (auto& [name, values] : this->Columns)
    {
      values.resize(this->Names.size(), std::nan("")); // the failed rows after the last deformed one
      vtkNew<vtkDoubleArray> column;
      column->SetName(name.c_str());
      for (double value : values)
      {
        column->InsertNextValue(value);
      }
      table->AddColumn(column);
    }
  }

private:
  std::vector<std::string> Names;
  std::vector<double> Failed;
  std::vector<std::pair<std::string, std::vector<double>>> Columns;
};
}

vtkInterpolatedMuscleDeformation::vtkInterpolatedMuscleDeformation()
  : Computed(std::make_unique<Cache>())
  , KeptRest(std::make_unique<md::RestMappingCache>())
  , KeptFibres(std::make_unique<mdvtk::FibreKeeper>())
{
  this->SetNumberOfInputPorts(kPorts);
  this->SetNumberOfOutputPorts(5);
  const md::InterpolationParameters method;
  this->NumberOfSteps = method.numberOfSteps;
  this->ResolvedNumberOfSteps = method.numberOfSteps;
  this->MaximumStepDisplacement = method.maximumStepDisplacement;
  this->BoneInterpolationMode = static_cast<int>(method.interpolationMode);
  this->DeformationMesh = method.settleOnSurface ? MUSCLE_SURFACE : HULL;
  this->HullMode = static_cast<int>(method.hullMode);
  this->MatchingTolerance = md::kDefaultMatchingTolerance;
  this->DeformableShare = method.staticResolve.deformableShare;
  this->MaximumNumberOfIterations = method.deformation.maximumIterations;
  this->ConvergenceTolerance = method.deformation.convergenceTolerance;
  this->PreserveVolume = method.deformation.preserveVolume;
  this->BoneContactWeight = method.deformation.contactWeight;
  this->HullTargetNumberOfPoints = method.hull.targetNumberOfPoints;
  this->RefitRegularisation = method.refitRegularisation;
  this->NumberOfFibres = md::FibreParameters().count;
}

int vtkInterpolatedMuscleDeformation::GetHullBuildCount() const
{
  return this->KeptRest->hullBuildCount;
}

int vtkInterpolatedMuscleDeformation::GetFibreBuildCount() const
{
  return this->KeptFibres->Builds();
}

int vtkInterpolatedMuscleDeformation::GetSurfaceEnergyBuildCount() const
{
  return this->KeptRest->energyBuildCount;
}

int vtkInterpolatedMuscleDeformation::FillOutputPortInformation(int port, vtkInformation* info)
{
  if (port == kTablePort)
  {
    info->Set(vtkDataObject::DATA_TYPE_NAME(), "vtkTable");
    return 1;
  }
  if (port == kFibresPort)
  {
    info->Set(vtkDataObject::DATA_TYPE_NAME(), "vtkMultiBlockDataSet");
    return 1;
  }
  return this->Superclass::FillOutputPortInformation(port, info);
}

int vtkInterpolatedMuscleDeformation::RequestDataObject(
  vtkInformation*, vtkInformationVector** inputVector, vtkInformationVector* outputVector)
{
  // Each output has the type of the input it follows: muscles, bones, action lines; then the table.
  mdvtk::OutputsFollowInputs(inputVector, outputVector, { 0, 1, 3 }, kTablePort);
  if (!vtkMultiBlockDataSet::GetData(outputVector, kFibresPort))
  {
    vtkNew<vtkMultiBlockDataSet> fibres;
    outputVector->GetInformationObject(kFibresPort)->Set(vtkDataObject::DATA_OBJECT(), fibres);
  }
  return 1;
}

vtkInterpolatedMuscleDeformation::~vtkInterpolatedMuscleDeformation()
{
  this->SetAttachmentFileName(nullptr);
}

int vtkInterpolatedMuscleDeformation::FillInputPortInformation(int port, vtkInformation* info)
{
  if (port == kAttachmentsPort)
  {
    mdvtk::OptionalLandmarkInput(info);
    return 1;
  }
  mdvtk::AcceptPolyDataOrMultiBlock(info);
  return 1;
}

const char* vtkInterpolatedMuscleDeformation::GetAttachmentReport() const
{
  return this->AttachmentReport.c_str();
}

int vtkInterpolatedMuscleDeformation::RequestInformation(
  vtkInformation*, vtkInformationVector** inputVector, vtkInformationVector* outputVector)
{
  auto automatic = [&](int& steps) {
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
    mdvtk::CallCore(
      this, "", [&] { steps = md::ResolveNumberOfSteps(bones, parameters); }, result);
    return result;
  };
  return mdvtk::AdvertiseSteps(
    this, outputVector, this->NumberOfSteps, { 1, 2 }, automatic, this->ResolvedNumberOfSteps);
}

int vtkInterpolatedMuscleDeformation::RequestUpdateExtent(
  vtkInformation*, vtkInformationVector** inputVector, vtkInformationVector* outputVector)
{
  mdvtk::ClearOutputs(outputVector);
  mdvtk::InputsAtTheirOwnTime(inputVector, kPorts); // our time is the interpolation step
  return 1;
}

int vtkInterpolatedMuscleDeformation::RequestData(
  vtkInformation* request, vtkInformationVector** inputVector, vtkInformationVector* outputVector)
{
  vtkDataObject* inputs[kPorts];
  vtkMTimeType inputsTime = 0;
  for (int port = 0; port < kPorts; ++port)
  {
    inputs[port] = vtkDataObject::GetData(inputVector[port], 0);
    inputsTime = std::max(inputsTime, inputs[port] ? inputs[port]->GetMTime() : 0);
  }
  std::vector<mdvtk::Leaf> muscles;
  std::string error;
  if (!mdvtk::CollectLeaves(inputs[0], PortNames[0], muscles, error))
  {
    vtkErrorMacro(<< error);
    return 0;
  }
  const Cache& cache = *this->Computed;
  if (cache.result.points.empty() || cache.inputsTime != inputsTime || cache.filterTime != this->GetMTime() ||
    cache.result.numberOfSteps != this->ResolvedNumberOfSteps)
  {
    if (const int result = this->Deform(inputs, muscles); !result || this->Computed->result.points.empty())
    {
      return result;
    }
    this->Computed->inputsTime = inputsTime;
    this->Computed->filterTime = this->GetMTime();
  }
  const int step = this->StepToShow(request, outputVector);
  this->WriteMuscles(inputs[0], muscles, step, outputVector);
  if (!this->WriteBonesAndLines(inputs, step, outputVector))
  {
    return 0;
  }
  this->WriteFibres(muscles, step, vtkMultiBlockDataSet::GetData(outputVector, kFibresPort));
  mdvtk::SetDataTime(outputVector, step);
  this->UpdateProgress(1.0);
  return 1;
}

int vtkInterpolatedMuscleDeformation::Deform(
  vtkDataObject* const inputs[kPorts], const std::vector<mdvtk::Leaf>& muscles)
{
  Cache& cache = *this->Computed;
  cache = Cache{};
  // Everything is read and checked before any work.
  Lines lines;
  std::vector<md::BoneMotion> bones;
  std::string error;
  if (!mdvtk::CollectLeaves(inputs[3], PortNames[3], lines.rest, error) ||
    !mdvtk::CollectLeaves(inputs[4], PortNames[4], lines.current, error) ||
    !mdvtk::PairLeaves(this, muscles, PortNames[0], lines.rest, PortNames[3], lines.restOf, error) ||
    !mdvtk::PairLeaves(this, lines.rest, PortNames[3], lines.current, PortNames[4], lines.currentOf, error) ||
    !mdvtk::ReadBones(this, inputs[1], PortNames[1], inputs[2], PortNames[2], bones, error, &cache.boneLeaf))
  {
    vtkErrorMacro(<< error);
    return 0;
  }
  // One muscle's fault is reported and that muscle left out; the others go on.
  std::vector<md::MuscleMotion> motions;
  for (size_t b = 0; b < muscles.size(); ++b)
  {
    if (!muscles[b].data)
    {
      continue; // an empty block
    }
    md::MuscleMotion motion;
    motion.name = mdvtk::NameOf(muscles[b]);
    if (!mdvtk::ReadMuscleSurface(muscles[b], motion.muscle, error))
    {
      mdvtk::FailBlock(this, cache.failedBlocks, b, error);
      continue;
    }
    motions.push_back(std::move(motion));
    cache.blockOf.push_back(b);
  }
  // Everything in the muscles' local frame from here on, the matching of the action lines
  // too: the same answer wherever the data sits and whatever its units.
  std::vector<md::Points> worldMuscles; // the rest pose as given: step 0 shows it exactly
  for (const md::MuscleMotion& motion : motions)
  {
    worldMuscles.push_back(motion.muscle.points);
  }
  std::vector<const md::Points*> restPoints;
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
  int result = 1;
  std::vector<size_t> kept;
  if (!this->MatchLines(muscles, lines, frame, motions, kept, result))
  {
    return result; // stopped by the user
  }
  restPoints.clear();
  for (size_t m : kept)
  {
    restPoints.push_back(&worldMuscles[m]);
  }
  if (motions.empty() && !cache.failedBlocks.empty())
  {
    cache = Cache{};
    return 0; // every muscle failed, each said why (no muscle at all is the core's error)
  }
  const md::InterpolationParameters parameters = this->Parameters(frame);
  if (!mdvtk::CallCore(
        this, "",
        [&] {
          this->Attach(inputs[kAttachmentsPort], frame, motions, bones);
          cache.result =
            md::DeformByInterpolation(motions, bones, parameters, mdvtk::ProgressOrCancel(this), this->KeptRest.get());
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
      mdvtk::FailBlock(
        this, cache.failedBlocks, cache.blockOf[m], muscles[cache.blockOf[m]].label + ": " + cache.result.failures[m]);
    }
  }
  cache.frame = frame;
  for (const md::BoneMotion& bone : bones)
  {
    cache.boneMotions.emplace_back(bone.rest.points, bone.current, parameters.interpolationMode);
  }
  this->MakeFibres(motions, bones);
  for (const std::string& warning : cache.result.warnings)
  {
    vtkWarningMacro(<< warning);
  }
  return 1;
}

void vtkInterpolatedMuscleDeformation::Attach(vtkDataObject* landmarks, const md::LocalFrame& frame,
  std::vector<md::MuscleMotion>& motions, const std::vector<md::BoneMotion>& bones)
{
  std::vector<md::LandmarkSet> sets;
  if (this->AttachmentAreas != mdvtk::ATTACHMENTS_OFF)
  {
    sets = mdvtk::ReadLandmarks(landmarks, this->AttachmentFileName ? this->AttachmentFileName : "");
  }
  for (md::LandmarkSet& set : sets)
  {
    frame.ToLocal(set.points); // the muscles and bones are in the local frame here
  }
  std::vector<std::string> muscleNames, boneNames;
  std::vector<md::TriangleMesh> surfaces, boneSurfaces;
  std::vector<std::vector<md::Points>> lines;
  for (const md::MuscleMotion& m : motions)
  {
    muscleNames.push_back(m.name);
    surfaces.push_back(m.muscle);
    lines.emplace_back();
    for (const md::MatchedLine& line : m.lines)
    {
      lines.back().push_back(line.rest);
    }
  }
  for (const md::BoneMotion& b : bones)
  {
    boneNames.push_back(b.name);
    boneSurfaces.push_back(b.rest);
  }
  std::vector<std::vector<md::Attachment>> areas;
  this->AttachmentReport = mdvtk::AttachAndReport(this, "InterpolatedMuscleDeformation", this->AttachmentAreas, sets,
    muscleNames, surfaces, lines, boneNames, boneSurfaces, areas, frame.LengthToWorld(1.0));
  bool attached = false;
  for (size_t m = 0; m < motions.size(); ++m)
  {
    motions[m].attachments = areas[m];
    attached = attached || !areas[m].empty();
  }
  if (attached && this->DeformationMesh == HULL)
  {
    vtkWarningMacro(<< "the attachment areas are honoured with DeformationMesh Muscle surface only: on the hull "
                       "the muscles move with their action lines alone");
  }
}

bool vtkInterpolatedMuscleDeformation::MatchLines(const std::vector<mdvtk::Leaf>& muscles, const Lines& lines,
  const md::LocalFrame& frame, std::vector<md::MuscleMotion>& motions, std::vector<size_t>& kept, int& result)
{
  Cache& cache = *this->Computed;
  std::vector<md::MuscleMotion> matched; // the muscles whose lines could be matched
  std::vector<size_t> matchedBlocks;
  for (size_t m = 0; m < motions.size(); ++m)
  {
    md::MuscleMotion& motion = motions[m];
    const size_t b = cache.blockOf[m];
    frame.ToLocal(motion.muscle.points);
    const mdvtk::Leaf& restLeaf = lines.rest[lines.restOf[b]];
    const mdvtk::Leaf& currentLeaf = lines.current[lines.currentOf[lines.restOf[b]]];
    std::vector<md::Points> rest = restLeaf.data ? mdvtk::ToPolylines(restLeaf.data) : std::vector<md::Points>{};
    std::vector<md::Points> current =
      currentLeaf.data ? mdvtk::ToPolylines(currentLeaf.data) : std::vector<md::Points>{};
    for (auto* poses : { &rest, &current })
    {
      for (md::Points& line : *poses)
      {
        frame.ToLocal(line);
      }
    }
    if (rest.empty())
    {
      mdvtk::FailBlock(this, cache.failedBlocks, b,
        restLeaf.label + " has no polylines" + mdvtk::UpstreamFailure(restLeaf.data) + ": muscle " + muscles[b].label +
          " needs its action lines, or nothing says where it goes");
      continue;
    }
    if (rest.size() != current.size())
    {
      mdvtk::FailBlock(this, cache.failedBlocks, b,
        restLeaf.label + " has " + std::to_string(rest.size()) + " action lines but " + currentLeaf.label + " has " +
          std::to_string(current.size()) + ": the lines of a muscle pair by order");
      continue;
    }
    std::string failure;
    if (!mdvtk::CallCore(
          this, "an action line of " + restLeaf.label + " or " + currentLeaf.label + ": ",
          [&] {
            std::vector<std::string> notes;
            motion.lines =
              md::MatchMuscleLines(rest, current, this->MatchingTolerance, notes, mdvtk::ToKnots(restLeaf.data));
            for (const std::string& note : notes)
            {
              vtkWarningMacro(<< restLeaf.label << ": " << note);
            }
          },
          result, &failure))
    {
      if (failure.empty())
      {
        return false; // stopped by the user
      }
      mdvtk::FailBlock(this, cache.failedBlocks, b, failure, true);
      continue;
    }
    cache.lineMotions.emplace_back();
    for (const md::MatchedLine& line : motion.lines)
    {
      cache.lineMotions.back().emplace_back(
        line.rest, line.current, static_cast<md::InterpolationMode>(this->BoneInterpolationMode));
    }
    cache.lineLeaf.push_back(lines.restOf[b]);
    matched.push_back(std::move(motion));
    matchedBlocks.push_back(b);
    kept.push_back(m);
  }
  motions = std::move(matched);
  cache.blockOf = std::move(matchedBlocks);
  return true;
}

md::InterpolationParameters vtkInterpolatedMuscleDeformation::Parameters(const md::LocalFrame& frame)
{
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
  return parameters;
}

int vtkInterpolatedMuscleDeformation::StepToShow(vtkInformation* request, vtkInformationVector* outputVector)
{
  const int steps = this->Computed->result.numberOfSteps;
  // The time asked for on the port whose request this is: all three outputs show that step.
  int port = request->Has(vtkDemandDrivenPipeline::FROM_OUTPUT_PORT())
    ? request->Get(vtkDemandDrivenPipeline::FROM_OUTPUT_PORT())
    : 0;
  port = port < 0 || port >= this->GetNumberOfOutputPorts() ? 0 : port;
  const int step = mdvtk::StepAsked(outputVector->GetInformationObject(port), steps, steps);
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
  return step;
}

void vtkInterpolatedMuscleDeformation::WriteMuscles(
  vtkDataObject* input, const std::vector<mdvtk::Leaf>& muscles, int step, vtkInformationVector* outputVector)
{
  const Cache& cache = *this->Computed;
  const md::InterpolationResult& r = cache.result;
  std::vector<vtkSmartPointer<vtkPolyData>> outputs(muscles.size());
  MeasuresTable table;
  std::map<size_t, size_t> muscleOfBlock;
  for (size_t m = 0; m < cache.blockOf.size(); ++m)
  {
    muscleOfBlock[cache.blockOf[m]] = m; // failedBlocks has the core's failures too: they go first
  }
  for (size_t b = 0; b < muscles.size(); ++b)
  {
    const auto failed = cache.failedBlocks.find(b);
    const auto found = muscleOfBlock.find(b);
    if (failed != cache.failedBlocks.end())
    {
      outputs[b] = mdvtk::FailedMuscle(muscles[b].data, failed->second);
      table.AddFailedRow(mdvtk::NameOf(muscles[b]));
      continue;
    }
    if (found == muscleOfBlock.end())
    {
      continue; // an empty block
    }
    const size_t m = found->second;
    const md::Points& points = r.points[step][m];
    const md::MuscleStepMeasures& s = r.measures[step][m];
    outputs[b] = mdvtk::MovedMuscle(muscles[b].data, points, points - r.points[0][m]);
    // No static move at step 0: zeros.
    outputs[b]->GetPointData()->AddArray(mdvtk::ToVtkArray(mdvtk::StaticShiftArrayName,
      s.staticShift.rows() ? s.staticShift : md::Points(md::Points::Zero(points.rows(), 3))));
    double hullSeconds = r.restHullSeconds[m];
    for (int j = 1; j <= step; ++j)
    {
      hullSeconds += r.measures[j][m].hullSeconds;
    }
    // Each measure goes to the muscle's field data and to its row of the Measures table.
    std::vector<mdvtk::Measure> measures = mdvtk::StepMeasures(s, s.iterations, true);
    measures.push_back({ mdvtk::array::PointsFrozenInObstacles, static_cast<double>(s.pointsFrozenInObstacles), true });
    measures.push_back({ mdvtk::array::InterpolationStep, static_cast<double>(step), true });
    measures.push_back({ mdvtk::array::NumberOfSteps, static_cast<double>(r.numberOfSteps), true });
    measures.push_back({ mdvtk::array::HullSeconds, hullSeconds });
    measures.push_back({ mdvtk::array::StepSeconds, r.stepSeconds[step] });
    measures.push_back({ mdvtk::array::ElapsedSeconds, r.totalSeconds });
    mdvtk::AddMeasures(outputs[b]->GetFieldData(), measures);
    table.AddRow(mdvtk::NameOf(muscles[b]), measures);
  }
  mdvtk::AssignLeaves(input, vtkDataObject::GetData(outputVector, 0), outputs, mdvtk::Role::Muscle);
  // Output 3: the same measures as a table, one row per muscle, for a spreadsheet view.
  table.WriteTo(vtkTable::GetData(outputVector, 3));
}

bool vtkInterpolatedMuscleDeformation::WriteBonesAndLines(
  vtkDataObject* const inputs[5], int step, vtkInformationVector* outputVector)
{
  // Outputs 1 and 2: the bones and the matched action lines at the same step, as the method
  // moved them, so that the muscles are never shown against bones of another step.
  const Cache& cache = *this->Computed;
  const int steps = cache.result.numberOfSteps;
  std::vector<mdvtk::Leaf> boneLeaves, lineLeaves;
  std::string error;
  if (!mdvtk::CollectLeaves(inputs[1], PortNames[1], boneLeaves, error) ||
    !mdvtk::CollectLeaves(inputs[3], PortNames[3], lineLeaves, error))
  {
    vtkErrorMacro(<< error);
    return false;
  }
  std::vector<vtkSmartPointer<vtkPolyData>> boneOutputs(boneLeaves.size());
  for (size_t k = 0; k < cache.boneMotions.size(); ++k)
  {
    md::Points points = cache.boneMotions[k].AtStep(step, steps);
    cache.frame.ToWorld(points);
    boneOutputs[cache.boneLeaf[k]] = mdvtk::MovedCopy(boneLeaves[cache.boneLeaf[k]].data, points);
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
  return true;
}

void vtkInterpolatedMuscleDeformation::MakeFibres(
  const std::vector<md::MuscleMotion>& motions, const std::vector<md::BoneMotion>& bones)
{
  Cache& cache = *this->Computed;
  std::vector<md::MotionDeformation::Muscle> muscles;
  std::vector<char> failed;
  for (size_t m = 0; m < motions.size(); ++m)
  {
    md::MotionDeformation::Muscle muscle{ motions[m].name, motions[m].muscle, {}, motions[m].attachments };
    for (const md::MatchedLine& line : motions[m].lines)
    {
      muscle.restLines.push_back(line.rest);
    }
    muscles.push_back(std::move(muscle));
    failed.push_back(cache.result.failures[m].empty() ? 0 : 1);
  }
  std::vector<md::MotionDeformation::Bone> restBones;
  for (const md::BoneMotion& bone : bones)
  {
    restBones.push_back({ bone.name, bone.rest });
  }
  cache.fibres = this->KeptFibres->KeepOrMake(
    this, "InterpolatedMuscleDeformation", this->NumberOfFibres, muscles, restBones, failed);
}

void vtkInterpolatedMuscleDeformation::WriteFibres(
  const std::vector<mdvtk::Leaf>& muscles, int step, vtkMultiBlockDataSet* output) const
{
  const Cache& cache = *this->Computed;
  output->Initialize();
  if (!cache.fibres)
  {
    return;
  }
  std::vector<md::FibreObstacle> obstacles;
  const std::vector<md::TriangleTree>& boneTrees = cache.fibres->boneTrees;
  std::vector<std::unique_ptr<md::TriangleTree>> moved(boneTrees.size());
  for (size_t k = 0; k < boneTrees.size(); ++k)
  {
    obstacles.push_back(
      mdvtk::BoneWhereItIs(boneTrees[k], moved[k], cache.boneMotions[k].AtStep(step, cache.result.numberOfSteps)));
  }
  for (size_t m = 0; m < cache.blockOf.size(); ++m)
  {
    if (!cache.fibres->ofMuscle[m] || cache.result.points[step][m].rows() == 0)
    {
      continue;
    }
    md::Points surface = cache.result.points[step][m];
    cache.frame.ToLocal(surface);
    md::Points fibres = cache.fibres->ofMuscle[m]->At(surface, obstacles);
    std::vector<double> lengths = cache.fibres->ofMuscle[m]->Lengths(fibres);
    for (double& length : lengths)
    {
      length = cache.frame.LengthToWorld(length);
    }
    cache.frame.ToWorld(fibres);
    const unsigned block = output->GetNumberOfBlocks();
    output->SetBlock(block, mdvtk::FibrePolylines(fibres, cache.fibres->ofMuscle[m]->PointsPerFibre(), lengths));
    output->GetMetaData(block)->Set(vtkCompositeDataSet::NAME(), mdvtk::NameOf(muscles[cache.blockOf[m]]).c_str());
  }
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
  os << indent << "NumberOfFibres: " << this->NumberOfFibres << "\n";
  os << indent << "AttachmentAreas: " << this->AttachmentAreas << "\n";
  os << indent << "AttachmentFileName: " << (this->AttachmentFileName ? this->AttachmentFileName : "") << "\n";
  os << indent << "ResolvedNumberOfSteps: " << this->ResolvedNumberOfSteps << "\n";
  os << indent << "HullBuildCount: " << this->GetHullBuildCount() << "\n";
  os << indent << "SurfaceEnergyBuildCount: " << this->GetSurfaceEnergyBuildCount() << "\n";
  os << indent << "FibreBuildCount: " << this->GetFibreBuildCount() << "\n";
}
