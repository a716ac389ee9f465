// SPDX-License-Identifier: BSD-3-Clause
#include "vtkMotionMuscleDeformation.h"

#include "Anatomy/MuscleFibres.h"
#include "Anatomy/TendonExcursion.h"
#include "Geometry/Polyline.h"
#include "MDAttachments.h"
#include "MDBlocks.h"
#include "MDConvert.h"
#include "MDFibres.h"
#include "MDReport.h"
#include "MDTime.h"
#include "Method/InterpolatedDeformation.h"
#include "Method/MotionDeformation.h"

#include <vtkCompositeDataSet.h>
#include <vtkDemandDrivenPipeline.h>
#include <vtkDoubleArray.h>
#include <vtkExecutive.h>
#include <vtkFieldData.h>
#include <vtkInformation.h>
#include <vtkInformationVector.h>
#include <vtkMultiBlockDataSet.h>
#include <vtkObjectFactory.h>
#include <vtkPointData.h>
#include <vtkPolyData.h>
#include <vtkStreamingDemandDrivenPipeline.h>
#include <vtkTable.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <map>

vtkStandardNewMacro(vtkMotionMuscleDeformation);

namespace
{
using SDDP = vtkStreamingDemandDrivenPipeline;
const char* const PortNames[] = { "Input", "BonesRest", "BonesMotion", "ActionLinesRest", "ActionLinesMotion" };
constexpr int kMotionPorts[] = { 2, 4 };
constexpr int kAttachmentsPort = 5;
constexpr int kTablePort = 3, kFibresPort = 4, kMomentArmsPort = 5;
}

/// What the frames were computed from: when any of it changes, the motion starts again.
struct vtkMotionMuscleDeformation::Signature
{
  vtkMTimeType restInputs = 0;     ///< the rest-pose inputs' data
  vtkMTimeType motionPipeline = 0; ///< the time-varying inputs' pipelines (their sources' settings)
  std::vector<double> times;
  int numberOfSteps = 0;
  double maximumStepDisplacement = 0;
  int interpolationMode = 0;
  double deformableShare = 0;
  bool preserveVolume = true;
  int attachmentAreas = 1;
  std::string attachmentFile;
  int numberOfFibres = 0;
  bool operator==(const Signature& o) const
  {
    return restInputs == o.restInputs && motionPipeline == o.motionPipeline && times == o.times &&
      numberOfSteps == o.numberOfSteps && maximumStepDisplacement == o.maximumStepDisplacement &&
      interpolationMode == o.interpolationMode && deformableShare == o.deformableShare &&
      preserveVolume == o.preserveVolume && attachmentAreas == o.attachmentAreas &&
      attachmentFile == o.attachmentFile && numberOfFibres == o.numberOfFibres;
  }
};

namespace
{
/// The time steps advertised on an input (none: empty).

double Bytes(const md::Points& p)
{
  return static_cast<double>(p.size()) * sizeof(double);
}
}

/// One frame computed: the muscles, the pose that drove them and where the motion stood.
struct FrameKept
{
  std::vector<md::Points> points; ///< [muscle given to the core]
  std::vector<md::Points> fibres; ///< [muscle given]: its fibres' points (empty: none)
  md::MotionPose pose;            ///< in the data's coordinates
  std::shared_ptr<const md::MotionDeformation::State> state;
  double bytes = 0;
};

/// The measures of one frame (kept for every frame computed, whatever the cache drops).
struct FrameMeasures
{
  std::vector<md::MuscleStepMeasures> measures; ///< staticShift dropped
  std::vector<double> secondDifference;         ///< per muscle; NaN before the third frame
  std::vector<double> smoothnessRatio;
  int steps = 0;
  double seconds = 0;
  std::vector<std::vector<double>> fibreLengths; ///< [muscle given][fibre]
  std::vector<std::vector<double>> lineLengths;  ///< [muscle given][action line]
  std::vector<double> coordinates;               ///< the pose's (Internals::coordinates), radians or as given
  std::vector<mdvtk::SteppedLengths> stepped;    ///< at the frame's stepped poses (MomentArmStep)

  /// Muscle `m`'s measures, as written to its field data.
  std::vector<mdvtk::Measure> Of(size_t m) const
  {
    std::vector<mdvtk::Measure> all = mdvtk::StepMeasures(this->measures[m], this->measures[m].stepIterations, false);
    all.push_back({ mdvtk::array::SecondDifference, this->secondDifference[m] });
    all.push_back({ mdvtk::array::SmoothnessRatio, this->smoothnessRatio[m] });
    return all;
  }
};

struct vtkMotionMuscleDeformation::Internals
{
  Signature signature;
  std::string attachmentReport; ///< GetAttachmentReport
  std::unique_ptr<md::MotionDeformation> deformation;
  md::RestMappingCache kept;
  std::vector<size_t> blockOf;                              // muscle block of each muscle given to the core
  std::map<size_t, std::string> failedBlocks;               // muscle blocks left out, and why
  std::vector<size_t> boneLeaf;                             // BonesRest leaf of each bone
  std::vector<md::Points> restPoints;                       // [muscle given]: as given, in the data's coordinates
  std::vector<std::vector<md::Points>> restLines;           // [muscle given]
  std::shared_ptr<const mdvtk::MadeFibres> fibres;          // [muscle given] and the bones' rest trees
  mdvtk::FibreKeeper keptFibres;                            // across restarts
  std::vector<std::unique_ptr<md::TriangleTree>> boneMoved; // a bone's refitted to a frame's, where not rigid
  mdvtk::PoseCoordinates coordinates;                       // named at the first frame
  std::map<int, FrameKept> frames;
  std::map<int, FrameMeasures> measures;
  int gather = -1;      ///< the frame the time-varying inputs are asked for; -1: none
  bool looping = false; ///< RequestData asked the executive to go on (CONTINUE_EXECUTING)
  int target = 0;       ///< the frame asked for
  double upstreamTime = 0;
  bool upstreamAsked = false;
  int framesComputed = 0;
  bool steppedMissingSaid = false; ///< a pose stepped for moment arms lacked a block's points (said once)
  mdvtk::InputCheck checked[5];    ///< per input port, the rest pose's

  void Restart()
  {
    this->deformation.reset();
    this->blockOf.clear();
    this->failedBlocks.clear();
    this->boneLeaf.clear();
    this->restPoints.clear();
    this->restLines.clear();
    this->fibres.reset();
    this->boneMoved.clear();
    this->coordinates = {};
    this->steppedMissingSaid = false;
    this->frames.clear();
    this->measures.clear();
  }
  double CacheBytes() const
  {
    double bytes = 0;
    for (const auto& entry : this->frames)
    {
      bytes += entry.second.bytes;
    }
    return bytes;
  }
  /// Within `megabytes`: drops the frames farthest from the one asked for (never it, nor `last`,
  /// the last computed, from which the motion goes on).
  void Evict(double megabytes, int last)
  {
    while (this->CacheBytes() > megabytes * 1024.0 * 1024.0 && this->frames.size() > 2)
    {
      auto farthest = this->frames.end();
      for (auto it = this->frames.begin(); it != this->frames.end(); ++it)
      {
        if (it->first != last && it->first != this->target &&
          (farthest == this->frames.end() ||
            std::abs(it->first - this->target) > std::abs(farthest->first - this->target)))
        {
          farthest = it;
        }
      }
      if (farthest == this->frames.end())
      {
        break;
      }
      this->frames.erase(farthest);
    }
  }
  /// The muscles not failed, by their block.
  std::map<size_t, size_t> MuscleOfBlock() const
  {
    std::map<size_t, size_t> muscleOfBlock;
    for (size_t m = 0; m < this->blockOf.size(); ++m)
    {
      if (this->deformation->Failures()[m].empty())
      {
        muscleOfBlock[this->blockOf[m]] = m;
      }
    }
    return muscleOfBlock;
  }
  /// Keeps frame `k`: the muscles where `advanced` left them, the pose that drove them, where the
  /// motion stands, and the frame's measures, with how smoothly the muscles follow what drives
  /// them over the last three frames.
  void Keep(int k, md::MotionPose pose, std::vector<double> coordinates, const md::MotionFrameResult& advanced)
  {
    FrameKept kept;
    kept.state = this->deformation->Save();
    kept.points.resize(this->blockOf.size());
    FrameMeasures measures;
    measures.steps = advanced.steps;
    measures.seconds = advanced.seconds;
    measures.coordinates = std::move(coordinates);
    this->CarryFibres(pose, advanced.points, kept, measures);
    const auto before = this->frames.find(k - 1);
    const auto older = this->frames.find(k - 2);
    const bool threeFrames = k >= 2 && before != this->frames.end() && older != this->frames.end();
    // What drives the muscles (the bones' points and the lines), once for all muscles.
    const double driven =
      threeFrames ? md::LargestSecondDifference(older->second.pose, before->second.pose, pose) : 0.0;
    // A frame computed again (after the cache dropped it) is the same to the bit: where the two
    // frames before it were dropped too, its smoothness stays as first measured.
    const auto measuredBefore = this->measures.find(k);
    for (size_t m = 0; m < this->blockOf.size(); ++m)
    {
      kept.points[m] = advanced.points[m];
      md::MuscleStepMeasures s = advanced.measures[m];
      s.staticShift = md::Points(0, 3);
      measures.measures.push_back(s);
      double second = std::nan(""), ratio = std::nan("");
      if (threeFrames && kept.points[m].rows() > 0)
      {
        second = md::LargestSecondDifference(older->second.points[m], before->second.points[m], kept.points[m]);
        ratio = driven > 0 ? second / driven : std::nan("");
      }
      else if (!threeFrames && measuredBefore != this->measures.end())
      {
        second = measuredBefore->second.secondDifference[m];
        ratio = measuredBefore->second.smoothnessRatio[m];
      }
      measures.secondDifference.push_back(second);
      measures.smoothnessRatio.push_back(ratio);
      kept.bytes += Bytes(kept.points[m]);
    }
    for (const md::Points& p : pose.bones)
    {
      kept.bytes += Bytes(p);
    }
    kept.bytes += static_cast<double>(md::MotionDeformation::StateBytes(*kept.state));
    kept.pose = std::move(pose);
    this->frames[k] = std::move(kept);
    this->measures[k] = std::move(measures);
  }
  /// The fibres where the frame's muscles are (kept inside them and out of the bones), their
  /// lengths, and the action lines' lengths.
  void CarryFibres(
    const md::MotionPose& pose, const std::vector<md::Points>& points, FrameKept& kept, FrameMeasures& measures)
  {
    kept.fibres = this->FibresAt(pose, points, measures.fibreLengths, measures.lineLengths);
    for (const md::Points& f : kept.fibres)
    {
      kept.bytes += Bytes(f);
    }
  }
  /// The fibres of muscles at `points` in `pose` ([muscle]; empty: none), with their lengths and
  /// those of the pose's action lines.
  std::vector<md::Points> FibresAt(const md::MotionPose& pose, const std::vector<md::Points>& points,
    std::vector<std::vector<double>>& fibreLengths, std::vector<std::vector<double>>& lineLengths)
  {
    std::vector<md::FibreObstacle> obstacles;
    for (size_t b = 0; b < this->fibres->boneTrees.size(); ++b)
    {
      obstacles.push_back(mdvtk::BoneWhereItIs(this->fibres->boneTrees[b], this->boneMoved[b], pose.bones[b]));
    }
    std::vector<md::Points> fibrePoints(this->blockOf.size());
    fibreLengths.assign(this->blockOf.size(), {});
    lineLengths.assign(this->blockOf.size(), {});
    for (size_t m = 0; m < this->blockOf.size(); ++m)
    {
      for (const md::Points& line : pose.lines[m])
      {
        lineLengths[m].push_back(md::PolylineLength(line));
      }
      if (this->fibres->ofMuscle[m] && points[m].rows() > 0)
      {
        fibrePoints[m] = this->fibres->ofMuscle[m]->At(points[m], obstacles);
        fibreLengths[m] = this->fibres->ofMuscle[m]->Lengths(fibrePoints[m]);
      }
    }
    return fibrePoints;
  }
  /// The frame to compute first for `target`: after the last one kept before it.
  int FirstMissing(int target) const
  {
    auto kept = this->frames.lower_bound(target);
    if (kept != this->frames.end() && kept->first == target)
    {
      return -1;
    }
    return kept == this->frames.begin() ? 0 : std::prev(kept)->first + 1;
  }
};

vtkMotionMuscleDeformation::vtkMotionMuscleDeformation()
  : In(std::make_unique<Internals>())
{
  this->SetNumberOfInputPorts(6);
  this->SetNumberOfOutputPorts(6);
  const md::InterpolationParameters method;
  this->MaximumStepDisplacement = method.maximumStepDisplacement;
  this->BoneInterpolationMode = static_cast<int>(method.interpolationMode);
  this->DeformableShare = method.staticResolve.deformableShare;
  this->PreserveVolume = method.deformation.preserveVolume;
}

vtkMotionMuscleDeformation::~vtkMotionMuscleDeformation()
{
  this->SetAttachmentFileName(nullptr);
}

const char* vtkMotionMuscleDeformation::GetAttachmentReport() const
{
  return this->In->attachmentReport.c_str();
}

int vtkMotionMuscleDeformation::GetFramesComputed() const
{
  return this->In->framesComputed;
}

int vtkMotionMuscleDeformation::GetFramesKept() const
{
  return static_cast<int>(this->In->frames.size());
}

double vtkMotionMuscleDeformation::GetCacheMegabytes() const
{
  return this->In->CacheBytes() / (1024.0 * 1024.0);
}

int vtkMotionMuscleDeformation::GetSurfaceEnergyBuildCount() const
{
  return this->In->kept.energyBuildCount;
}

int vtkMotionMuscleDeformation::GetFibreBuildCount() const
{
  return this->In->keptFibres.Builds();
}

int vtkMotionMuscleDeformation::FillInputPortInformation(int port, vtkInformation* info)
{
  if (port == kAttachmentsPort)
  {
    mdvtk::OptionalLandmarkInput(info);
    return 1;
  }
  mdvtk::AcceptPolyDataOrMultiBlock(info);
  return 1;
}

int vtkMotionMuscleDeformation::FillOutputPortInformation(int port, vtkInformation* info)
{
  if (port == kTablePort || port == kMomentArmsPort)
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

int vtkMotionMuscleDeformation::RequestDataObject(
  vtkInformation*, vtkInformationVector** inputVector, vtkInformationVector* outputVector)
{
  // Each output has the type of the input it follows: muscles, bones, action lines; then the table.
  mdvtk::OutputsFollowInputs(inputVector, outputVector, { 0, 1, 3 }, kTablePort);
  if (!vtkMultiBlockDataSet::GetData(outputVector, kFibresPort))
  {
    vtkNew<vtkMultiBlockDataSet> fibres;
    outputVector->GetInformationObject(kFibresPort)->Set(vtkDataObject::DATA_OBJECT(), fibres);
  }
  if (!vtkTable::GetData(outputVector, kMomentArmsPort))
  {
    vtkNew<vtkTable> table;
    outputVector->GetInformationObject(kMomentArmsPort)->Set(vtkDataObject::DATA_OBJECT(), table);
  }
  return 1;
}

int vtkMotionMuscleDeformation::RequestInformation(
  vtkInformation*, vtkInformationVector** inputVector, vtkInformationVector* outputVector)
{
  const std::vector<double> bones = mdvtk::TimesOf(inputVector[2]->GetInformationObject(0));
  const std::vector<double> lines = mdvtk::TimesOf(inputVector[4]->GetInformationObject(0));
  mdvtk::AdvertiseTimes(outputVector, {});
  if (bones.empty() || lines.empty())
  {
    vtkErrorMacro(<< (bones.empty() ? PortNames[2] : PortNames[4])
                  << " has no time steps: connect a time-varying source (OpenSimModelReader with PlayMotion on, "
                     "and MoveWithBodies and ActionLineGrouping after it); for one pose use "
                     "InterpolatedMuscleDeformation");
    return 0;
  }
  for (const auto& [port, times] : { std::make_pair(2, &bones), std::make_pair(4, &lines) })
  {
    const auto back = std::adjacent_find(times->begin(), times->end(), std::greater_equal<double>());
    if (back != times->end())
    {
      vtkErrorMacro(<< PortNames[port] << "'s time steps do not increase (" << *back << " then " << *(back + 1)
                    << "): a motion's frames must come in the order of their times");
      return 0;
    }
  }
  const double scale = std::max(std::abs(bones.front()), std::abs(bones.back())) + 1.0;
  bool agree = bones.size() == lines.size();
  for (size_t k = 0; agree && k < bones.size(); ++k)
  {
    agree = std::abs(bones[k] - lines[k]) <= 1e-9 * scale;
  }
  if (!agree)
  {
    vtkErrorMacro(<< PortNames[2] << " has " << bones.size() << " time steps (" << bones.front() << " to "
                  << bones.back() << ") but " << PortNames[4] << " has " << lines.size() << " (" << lines.front()
                  << " to " << lines.back()
                  << "): the bones and the action lines must come from the same motion, at the same times");
    return 0;
  }
  if (bones.size() < 2)
  {
    vtkErrorMacro(<< "the motion has one frame (time " << bones.front()
                  << "): a motion needs two frames or more; for one pose use InterpolatedMuscleDeformation");
    return 0;
  }
  mdvtk::AdvertiseTimes(outputVector, bones);
  return 1;
}

int vtkMotionMuscleDeformation::RequestUpdateExtent(
  vtkInformation*, vtkInformationVector** inputVector, vtkInformationVector* outputVector)
{
  Internals& in = *this->In;
  const std::vector<double> times = mdvtk::TimesOf(inputVector[2]->GetInformationObject(0));
  if (!in.looping && !times.empty())
  {
    mdvtk::ClearOutputs(outputVector);
    vtkInformation* outInfo = outputVector->GetInformationObject(0);
    in.target = outInfo->Has(SDDP::UPDATE_TIME_STEP())
      ? mdvtk::NearestTime(times, outInfo->Get(SDDP::UPDATE_TIME_STEP()))
      : static_cast<int>(times.size()) - 1;
    in.gather = in.signature.times == times ? in.FirstMissing(in.target) : 0;
  }
  // The time-varying inputs at the frame to compute; when none is to be computed, at the time
  // they were last asked for, so that their sources do not run again.
  if (in.gather >= 0 && in.gather < static_cast<int>(times.size()))
  {
    in.upstreamTime = times[in.gather];
    in.upstreamAsked = true;
  }
  else if (!in.upstreamAsked && !times.empty())
  {
    in.upstreamTime = times[std::min<size_t>(in.target, times.size() - 1)];
    in.upstreamAsked = true;
  }
  for (int port = 0; port < 5; ++port)
  {
    const bool motion = port == kMotionPorts[0] || port == kMotionPorts[1];
    for (int i = 0; i < inputVector[port]->GetNumberOfInformationObjects(); ++i)
    {
      vtkInformation* info = inputVector[port]->GetInformationObject(i);
      if (motion)
      {
        info->Set(SDDP::UPDATE_TIME_STEP(), in.upstreamTime);
      }
      else
      {
        info->Remove(SDDP::UPDATE_TIME_STEP());
      }
    }
  }
  return 1;
}

/// The leaves of the inputs, read and paired the same way at every frame.
struct vtkMotionMuscleDeformation::Leaves
{
  std::vector<mdvtk::Leaf> muscles, restLines, motionLines, restBones;
  std::vector<size_t> restLinesOf, motionLinesOf;
};

namespace
{
/// The rest-pose inputs are checked only where they were modified since they last passed
/// (`checked`, per port): a frame checks the time-varying inputs.
template<class Leaves>
bool CollectInputs(vtkMotionMuscleDeformation* self, vtkDataObject* const inputs[5], mdvtk::InputCheck checked[5],
  Leaves& leaves, std::string& error)
{
  return mdvtk::CollectLeaves(inputs[0], PortNames[0], leaves.muscles, error, checked[0]) &&
    mdvtk::CollectLeaves(inputs[3], PortNames[3], leaves.restLines, error, checked[3]) &&
    mdvtk::CollectLeaves(inputs[4], PortNames[4], leaves.motionLines, error) &&
    mdvtk::CollectLeaves(inputs[1], PortNames[1], leaves.restBones, error, checked[1]) &&
    mdvtk::PairLeaves(self, leaves.muscles, PortNames[0], leaves.restLines, PortNames[3], leaves.restLinesOf, error) &&
    mdvtk::PairLeaves(
      self, leaves.restLines, PortNames[3], leaves.motionLines, PortNames[4], leaves.motionLinesOf, error);
}

/// The columns of output 3 for each muscle, of the measures each frame keeps.
const char* const TableMeasures[] = { mdvtk::VolumeChangeArrayName, mdvtk::array::NewPenetrationCount,
  mdvtk::array::MaxNewBonePenetrationDepth, mdvtk::array::MaxStaticShift, mdvtk::array::SharpEdgeCount,
  mdvtk::array::FlippedTriangleCount, mdvtk::array::NumberOfIterations, mdvtk::array::Converged,
  mdvtk::array::SecondDifference, mdvtk::array::SmoothnessRatio };
}

int vtkMotionMuscleDeformation::RequestData(
  vtkInformation* request, vtkInformationVector** inputVector, vtkInformationVector* outputVector)
{
  Internals& in = *this->In;
  vtkDataObject* inputs[5];
  const Signature signature = this->SignatureOf(inputVector, inputs);
  if (signature.times.size() < 2)
  {
    return this->Stop(request, 0); // RequestInformation said why
  }
  Leaves leaves;
  std::string error;
  if (!CollectInputs(this, inputs, in.checked, leaves, error))
  {
    vtkErrorMacro(<< error);
    return this->Stop(request, 0);
  }
  if (!(signature == in.signature))
  {
    in.Restart();
    in.signature = signature;
    if (in.gather != 0)
    {
      in.gather = 0; // the inputs of this pass may be of another time: start from the first frame
      return this->GoOn(request);
    }
  }
  int result = 1;
  if (!in.deformation && !this->Start(leaves, vtkDataObject::GetData(inputVector[kAttachmentsPort], 0), result))
  {
    in.Restart();
    return this->Stop(request, result);
  }
  if (in.gather < 0 && in.FirstMissing(in.target) >= 0)
  {
    in.gather = in.FirstMissing(in.target); // dropped from the cache since the request was made
    return this->GoOn(request);
  }
  if (in.gather >= 0)
  {
    // This pass's time-varying inputs hold frame `gather`: read its pose and deform to it.
    if (!this->ComputeFrame(inputs[2], leaves, result))
    {
      return this->Stop(request, result);
    }
    if (in.gather < in.target)
    {
      ++in.gather;
      return this->GoOn(request);
    }
    this->Stop(request, 1);
  }
  // The frame asked for, from the cache (kept within a limit that may have been lowered).
  in.Evict(this->CacheMemoryLimit, in.target);
  this->WriteMuscles(inputs[0], leaves, vtkDataObject::GetData(outputVector, 0));
  this->WriteBonesAndLines(inputs, leaves, outputVector);
  this->WriteTable(leaves, vtkTable::GetData(outputVector, kTablePort));
  this->WriteFibres(leaves, vtkMultiBlockDataSet::GetData(outputVector, kFibresPort));
  this->WriteMomentArms(leaves, vtkTable::GetData(outputVector, kMomentArmsPort));
  mdvtk::SetDataTime(outputVector, in.signature.times[in.target]);
  this->UpdateProgress(1.0);
  return 1;
}

vtkMotionMuscleDeformation::Signature vtkMotionMuscleDeformation::SignatureOf(
  vtkInformationVector** inputVector, vtkDataObject* inputs[5])
{
  Signature signature;
  for (int port = 0; port < 5; ++port)
  {
    inputs[port] = vtkDataObject::GetData(inputVector[port], 0);
    if (port != kMotionPorts[0] && port != kMotionPorts[1])
    {
      signature.restInputs = std::max(signature.restInputs, mdvtk::DataMTime(inputs[port]));
    }
    else if (auto* executive = vtkDemandDrivenPipeline::SafeDownCast(this->GetInputExecutive(port, 0)))
    {
      signature.motionPipeline = std::max(signature.motionPipeline, executive->GetPipelineMTime());
    }
  }
  signature.times = mdvtk::TimesOf(inputVector[2]->GetInformationObject(0));
  signature.numberOfSteps = this->NumberOfSteps;
  signature.maximumStepDisplacement = this->MaximumStepDisplacement;
  signature.interpolationMode = this->BoneInterpolationMode;
  signature.deformableShare = this->DeformableShare;
  signature.preserveVolume = this->PreserveVolume;
  signature.attachmentAreas = this->AttachmentAreas;
  signature.attachmentFile = this->AttachmentFileName ? this->AttachmentFileName : "";
  signature.numberOfFibres = this->NumberOfFibres;
  signature.restInputs =
    std::max(signature.restInputs, mdvtk::DataMTime(vtkDataObject::GetData(inputVector[kAttachmentsPort], 0)));
  return signature;
}

int vtkMotionMuscleDeformation::Stop(vtkInformation* request, int result)
{
  this->In->gather = -1;
  this->In->looping = false;
  request->Remove(SDDP::CONTINUE_EXECUTING());
  return result;
}

int vtkMotionMuscleDeformation::GoOn(vtkInformation* request)
{
  request->Set(SDDP::CONTINUE_EXECUTING(), 1);
  this->In->looping = true;
  return 1;
}

namespace
{
/// The muscles' attachment areas as `mode` (AttachmentAreas) says, said in the output messages;
/// returns what was said.
std::string Attach(vtkAlgorithm* self, int mode, const char* file, vtkDataObject* landmarks,
  std::vector<md::MotionDeformation::Muscle>& muscles, const std::vector<md::MotionDeformation::Bone>& bones)
{
  std::vector<std::string> muscleNames, boneNames;
  std::vector<md::TriangleMesh> surfaces, boneSurfaces;
  std::vector<std::vector<md::Points>> lines;
  for (const md::MotionDeformation::Muscle& m : muscles)
  {
    muscleNames.push_back(m.name);
    surfaces.push_back(m.rest);
    lines.push_back(m.restLines);
  }
  for (const md::MotionDeformation::Bone& b : bones)
  {
    boneNames.push_back(b.name);
    boneSurfaces.push_back(b.rest);
  }
  const std::vector<md::LandmarkSet> sets =
    mode == mdvtk::ATTACHMENTS_OFF ? std::vector<md::LandmarkSet>{} : mdvtk::ReadLandmarks(landmarks, file ? file : "");
  std::vector<std::vector<md::Attachment>> areas;
  const std::string report = mdvtk::AttachAndReport(
    self, "MotionMuscleDeformation", mode, sets, muscleNames, surfaces, lines, boneNames, boneSurfaces, areas);
  for (size_t m = 0; m < muscles.size(); ++m)
  {
    muscles[m].attachments = areas[m];
  }
  return report;
}
}

bool vtkMotionMuscleDeformation::Start(const Leaves& leaves, vtkDataObject* landmarks, int& result)
{
  // The rest pose: muscles, their action lines, bones. One muscle's fault leaves it out.
  Internals& in = *this->In;
  std::vector<md::MotionDeformation::Muscle> muscles;
  std::string error;
  for (size_t b = 0; b < leaves.muscles.size(); ++b)
  {
    const mdvtk::Leaf& leaf = leaves.muscles[b];
    if (!leaf.data)
    {
      continue;
    }
    md::MotionDeformation::Muscle muscle;
    muscle.name = mdvtk::NameOf(leaf);
    const mdvtk::Leaf& lines = leaves.restLines[leaves.restLinesOf[b]];
    if (!mdvtk::ReadMuscleSurface(leaf, muscle.rest, error))
    {
      mdvtk::FailBlock(this, in.failedBlocks, b, error);
      continue;
    }
    muscle.restLines = lines.data ? mdvtk::ToPolylines(lines.data) : std::vector<md::Points>{};
    muscle.restKnots = mdvtk::ToKnots(lines.data);
    if (muscle.restLines.empty())
    {
      mdvtk::FailBlock(this, in.failedBlocks, b,
        lines.label + " has no polylines" + mdvtk::UpstreamFailure(lines.data) + ": muscle " + leaf.label +
          " needs its action lines, or nothing says where it goes");
      continue;
    }
    in.blockOf.push_back(b);
    in.restPoints.push_back(muscle.rest.points);
    in.restLines.push_back(muscle.restLines);
    muscles.push_back(std::move(muscle));
  }
  std::vector<md::MotionDeformation::Bone> bones;
  for (size_t b = 0; b < leaves.restBones.size(); ++b)
  {
    const mdvtk::Leaf& leaf = leaves.restBones[b];
    if (!leaf.data)
    {
      continue;
    }
    md::MotionDeformation::Bone bone;
    bone.name = mdvtk::NameOf(leaf);
    mdvtk::ReadTriangles(leaf.data, bone.rest);
    if (bone.rest.triangles.rows() == 0)
    {
      vtkErrorMacro(<< leaf.label << " has no surface (no polygons)");
      result = 0;
      return false;
    }
    bones.push_back(std::move(bone));
    in.boneLeaf.push_back(b);
  }
  if (muscles.empty())
  {
    if (in.failedBlocks.empty())
    {
      vtkErrorMacro(<< PortNames[0] << " has no muscle");
    }
    result = 0;
    return false;
  }
  md::InterpolationParameters parameters;
  parameters.numberOfSteps = this->NumberOfSteps;
  parameters.maximumStepDisplacement = this->MaximumStepDisplacement;
  parameters.interpolationMode = static_cast<md::InterpolationMode>(this->BoneInterpolationMode);
  parameters.staticResolve.deformableShare = this->DeformableShare;
  parameters.deformation.preserveVolume = this->PreserveVolume;
  if (!mdvtk::CallCore(
        this, "",
        [&] {
          in.attachmentReport =
            Attach(this, this->AttachmentAreas, this->AttachmentFileName, landmarks, muscles, bones);
          in.deformation = std::make_unique<md::MotionDeformation>(muscles, bones, parameters, &in.kept);
        },
        result))
  {
    return false;
  }
  std::vector<char> failed(muscles.size(), 0);
  for (size_t m = 0; m < muscles.size(); ++m)
  {
    if (const std::string& failure = in.deformation->Failures()[m]; !failure.empty())
    {
      mdvtk::FailBlock(this, in.failedBlocks, in.blockOf[m], leaves.muscles[in.blockOf[m]].label + ": " + failure);
      failed[m] = 1;
    }
  }
  in.fibres = in.keptFibres.KeepOrMake(this, "MotionMuscleDeformation", this->NumberOfFibres, muscles, bones, failed);
  in.boneMoved.resize(in.fibres->boneTrees.size());
  for (const std::string& warning : in.deformation->Warnings())
  {
    vtkWarningMacro(<< warning);
  }
  return true;
}

/// The moving bones of a frame (input port 2), each leaf paired with its rest leaf.
struct vtkMotionMuscleDeformation::MovingBones
{
  vtkDataObject* input = nullptr;
  std::vector<mdvtk::Leaf> leaves;
  std::vector<size_t> partner; ///< per rest bone leaf, its moving leaf
};

bool vtkMotionMuscleDeformation::ReadPose(
  const MovingBones& bones, const Leaves& leaves, md::MotionPose& pose, int& result, const std::string& stepped)
{
  Internals& in = *this->In;
  const double time = in.signature.times[in.gather];
  // The points of a leaf at the pose: its own, or its point array of the stepped pose.
  bool missing = false;
  const auto pointsOf = [&](vtkPolyData* data, const std::string& label) {
    if (stepped.empty())
    {
      return mdvtk::ToPoints(data->GetPoints());
    }
    vtkDataArray* at = data->GetPointData()->GetArray(mdvtk::PointsAt(stepped).c_str());
    if (!at || at->GetNumberOfComponents() != 3 || at->GetNumberOfTuples() != data->GetNumberOfPoints())
    {
      if (!missing && !in.steppedMissingSaid)
      {
        vtkWarningMacro(<< label << " has no point array " << mdvtk::PointsAt(stepped)
                        << " (its points at the pose stepped in a coordinate, as the bones have): the moment "
                           "arms come from differences between frames");
        in.steppedMissingSaid = true;
      }
      missing = true;
      return md::Points(0, 3);
    }
    return mdvtk::ToPoints(at);
  };
  for (size_t leaf : in.boneLeaf)
  {
    const mdvtk::Leaf& moving = bones.leaves[bones.partner[leaf]];
    pose.bones.push_back(moving.data ? pointsOf(moving.data, moving.label) : md::Points(0, 3));
    if (missing)
    {
      return false;
    }
    if (pose.bones.back().rows() != leaves.restBones[leaf].data->GetNumberOfPoints())
    {
      vtkErrorMacro(<< moving.label << " has " << pose.bones.back().rows() << " points at time " << time << " but "
                    << leaves.restBones[leaf].label << " has " << leaves.restBones[leaf].data->GetNumberOfPoints()
                    << ": a bone must keep its points through the motion");
      result = 0;
      return false;
    }
  }
  pose.lines.resize(in.blockOf.size());
  for (size_t m = 0; m < in.blockOf.size(); ++m)
  {
    if (!in.deformation->Failures()[m].empty())
    {
      continue;
    }
    const size_t restLeaf = leaves.restLinesOf[in.blockOf[m]];
    const mdvtk::Leaf& moving = leaves.motionLines[leaves.motionLinesOf[restLeaf]];
    const md::Points linePoints = moving.data ? pointsOf(moving.data, moving.label) : md::Points(0, 3);
    if (missing)
    {
      return false;
    }
    const std::vector<md::Points> lines =
      moving.data ? mdvtk::ToPolylines(moving.data, &linePoints) : std::vector<md::Points>{};
    if (lines.size() != in.restLines[m].size())
    {
      vtkErrorMacro(<< moving.label << " has " << lines.size() << " action lines at time " << time << " but "
                    << leaves.restLines[restLeaf].label << " has " << in.restLines[m].size()
                    << ": the lines of a muscle pair by order through the motion");
      result = 0;
      return false;
    }
    if (!mdvtk::CallCore(
          this, moving.label + " at time " + std::to_string(time) + ": ",
          [&] {
            for (size_t l = 0; l < lines.size(); ++l)
            {
              pose.lines[m].push_back(md::AtRestParameters(in.restLines[m][l], lines[l]));
            }
          },
          result))
    {
      return false;
    }
  }
  return true;
}

bool vtkMotionMuscleDeformation::ComputeFrame(vtkDataObject* motionBones, const Leaves& leaves, int& result)
{
  Internals& in = *this->In;
  const int k = in.gather;
  MovingBones bones;
  bones.input = motionBones;
  std::string error;
  if (!mdvtk::CollectLeaves(motionBones, PortNames[2], bones.leaves, error) ||
    !mdvtk::PairLeaves(this, leaves.restBones, PortNames[1], bones.leaves, PortNames[2], bones.partner, error))
  {
    vtkErrorMacro(<< "at time " << in.signature.times[k] << ": " << error);
    result = 0;
    return false;
  }
  md::MotionPose pose;
  if (!this->ReadPose(bones, leaves, pose, result))
  {
    return false;
  }
  // From the frame before (the rest pose before the first), wherever the motion stands now.
  const auto before = in.frames.find(k - 1);
  md::MotionFrameResult advanced;
  const int first = in.FirstMissing(in.target) < 0 ? k : std::min(k, in.FirstMissing(in.target));
  const double share = 1.0 / std::max(1, in.target - first + 1);
  if (!mdvtk::CallCore(
        this, "at time " + std::to_string(in.signature.times[k]) + ": ",
        [&] {
          if (k > 0 && before == in.frames.end())
          {
            throw md::ComputationError("frame " + std::to_string(k - 1) + " is not kept"); // not reached
          }
          in.deformation->Resume(k > 0 ? before->second.state : nullptr);
          advanced = in.deformation->Advance(pose, mdvtk::ProgressOrCancel(this, (k - first) * share, share));
        },
        result))
  {
    return false;
  }
  ++in.framesComputed;
  for (const std::string& warning : advanced.warnings)
  {
    vtkWarningMacro(<< "at time " << in.signature.times[k] << ": " << warning);
  }
  std::vector<double> coordinates = mdvtk::ReadCoordinates(motionBones, in.coordinates);
  in.Keep(k, std::move(pose), std::move(coordinates), advanced);
  if (!this->MeasureSteppedPoses(bones, leaves, result))
  {
    return false;
  }
  in.Evict(this->CacheMemoryLimit, k);
  return true;
}

bool vtkMotionMuscleDeformation::MeasureSteppedPoses(const MovingBones& bones, const Leaves& leaves, int& result)
{
  // Each stepped pose (OpenSimModelReader's MomentArmStep) is reached from the frame's own state
  // in the method's steps, its lengths measured, and the motion put back where the frame left it.
  Internals& in = *this->In;
  const int k = in.gather;
  if (in.boneLeaf.empty() || bones.leaves.empty())
  {
    return true;
  }
  const auto stepped = mdvtk::SteppedPosesOf(bones.input, bones.leaves.front().data, in.coordinates);
  const std::shared_ptr<const md::MotionDeformation::State> frame = in.frames.at(k).state;
  FrameMeasures& measures = in.measures.at(k);
  for (const auto& [name, lengths] : stepped)
  {
    if (lengths.coordinate < 0)
    {
      continue; // a coordinate the pose does not name: no moment arm about it
    }
    md::MotionPose pose;
    if (!this->ReadPose(bones, leaves, pose, result, name))
    {
      measures.stepped.clear();
      break; // said, or failed
    }
    md::MotionFrameResult advanced;
    if (!mdvtk::CallCore(
          this, "at time " + std::to_string(in.signature.times[k]) + ", pose " + name + ": ",
          [&] {
            in.deformation->Resume(frame);
            advanced = in.deformation->Advance(pose);
          },
          result))
    {
      in.deformation->Resume(frame);
      return false;
    }
    for (const std::string& warning : advanced.warnings)
    {
      vtkWarningMacro(<< "at time " << in.signature.times[k] << ", pose " << name << ": " << warning);
    }
    mdvtk::SteppedLengths measured = lengths;
    in.FibresAt(pose, advanced.points, measured.fibreLengths, measured.lineLengths);
    measures.stepped.push_back(std::move(measured));
  }
  in.deformation->Resume(frame);
  return result != 0;
}

void vtkMotionMuscleDeformation::WriteMuscles(vtkDataObject* input, const Leaves& leaves, vtkDataObject* output)
{
  const Internals& in = *this->In;
  const int k = in.target;
  const FrameKept& frame = in.frames.at(k);
  const FrameMeasures& measures = in.measures.at(k);
  std::vector<vtkSmartPointer<vtkPolyData>> outputs(leaves.muscles.size());
  for (const auto& [b, message] : in.failedBlocks)
  {
    outputs[b] = mdvtk::FailedMuscle(leaves.muscles[b].data, message);
  }
  for (const auto& [b, m] : in.MuscleOfBlock())
  {
    outputs[b] = mdvtk::MovedMuscle(leaves.muscles[b].data, frame.points[m], frame.points[m] - in.restPoints[m]);
    std::vector<mdvtk::Measure> written = measures.Of(m);
    written.push_back({ mdvtk::array::FrameSeconds, measures.seconds });
    written.push_back({ mdvtk::array::Frame, static_cast<double>(k), true });
    written.push_back({ mdvtk::array::Time, in.signature.times[k] });
    mdvtk::AddMeasures(outputs[b]->GetFieldData(), written);
  }
  mdvtk::AssignLeaves(input, output, outputs, mdvtk::Role::Muscle);
}

void vtkMotionMuscleDeformation::WriteBonesAndLines(
  vtkDataObject* const inputs[5], const Leaves& leaves, vtkInformationVector* outputVector)
{
  // Outputs 1 and 2: the bones and the action lines of this frame, as the method used them.
  const Internals& in = *this->In;
  const FrameKept& frame = in.frames.at(in.target);
  std::vector<vtkSmartPointer<vtkPolyData>> boneOutputs(leaves.restBones.size());
  for (size_t b = 0; b < in.boneLeaf.size(); ++b)
  {
    boneOutputs[in.boneLeaf[b]] = mdvtk::MovedCopy(leaves.restBones[in.boneLeaf[b]].data, frame.pose.bones[b]);
  }
  mdvtk::AssignLeaves(inputs[1], vtkDataObject::GetData(outputVector, 1), boneOutputs, mdvtk::Role::Bone);
  std::vector<vtkSmartPointer<vtkPolyData>> lineOutputs(leaves.restLines.size());
  for (size_t m = 0; m < in.blockOf.size(); ++m)
  {
    if (!frame.pose.lines[m].empty())
    {
      lineOutputs[leaves.restLinesOf[in.blockOf[m]]] = mdvtk::ToPolyLines(frame.pose.lines[m]);
    }
  }
  mdvtk::AssignLeaves(inputs[3], vtkDataObject::GetData(outputVector, 2), lineOutputs, mdvtk::Role::ActionLine);
}

void vtkMotionMuscleDeformation::WriteTable(const Leaves& leaves, vtkTable* table)
{
  // Output 3: the measures of every frame computed so far, one row per frame.
  const Internals& in = *this->In;
  const std::vector<double>& times = in.signature.times;
  auto column = [&](const std::string& name, auto value) {
    vtkNew<vtkDoubleArray> array;
    array->SetName(name.c_str());
    for (const auto& [frameIndex, frameMeasures] : in.measures)
    {
      array->InsertNextValue(value(frameIndex, frameMeasures));
    }
    table->AddColumn(array);
  };
  column(mdvtk::array::Time, [&](int f, const FrameMeasures&) { return times[f]; });
  column(mdvtk::array::Frame, [](int f, const FrameMeasures&) { return static_cast<double>(f); });
  column("Steps", [](int, const FrameMeasures& f) { return static_cast<double>(f.steps); });
  column(mdvtk::array::FrameSeconds, [](int, const FrameMeasures& f) { return f.seconds; });
  for (const auto& [b, m] : in.MuscleOfBlock())
  {
    // The muscle's measures at every frame, each found once; a column per measure of the table.
    std::vector<std::vector<mdvtk::Measure>> frames;
    for (const auto& entry : in.measures)
    {
      frames.push_back(entry.second.Of(m));
    }
    for (const char* name : TableMeasures)
    {
      vtkNew<vtkDoubleArray> array;
      array->SetName((std::string(name) + " (" + mdvtk::NameOf(leaves.muscles[b]) + ")").c_str());
      for (const std::vector<mdvtk::Measure>& frame : frames)
      {
        const auto found = std::find_if(
          frame.begin(), frame.end(), [&](const mdvtk::Measure& measure) { return std::string(measure.name) == name; });
        array->InsertNextValue(found != frame.end() ? found->value : std::nan(""));
      }
      table->AddColumn(array);
    }
  }
}

void vtkMotionMuscleDeformation::WriteFibres(const Leaves& leaves, vtkMultiBlockDataSet* output)
{
  // Output 4: each muscle's fibres at the frame asked for, a block per muscle with fibres.
  const Internals& in = *this->In;
  output->Initialize();
  if (!in.fibres)
  {
    return;
  }
  const FrameKept& frame = in.frames.at(in.target);
  const FrameMeasures& measures = in.measures.at(in.target);
  for (const auto& [b, m] : in.MuscleOfBlock())
  {
    if (in.fibres->ofMuscle[m] && frame.fibres[m].rows() > 0)
    {
      const unsigned block = output->GetNumberOfBlocks();
      output->SetBlock(block,
        mdvtk::FibrePolylines(frame.fibres[m], in.fibres->ofMuscle[m]->PointsPerFibre(), measures.fibreLengths[m]));
      output->GetMetaData(block)->Set(vtkCompositeDataSet::NAME(), mdvtk::NameOf(leaves.muscles[b]).c_str());
    }
  }
}

void vtkMotionMuscleDeformation::WriteMomentArms(const Leaves& leaves, vtkTable* table)
{
  // Output 5: lengths and moment arms of every frame computed so far (consecutive from frame 0).
  const Internals& in = *this->In;
  table->Initialize();
  std::vector<mdvtk::FrameLengths> frames;
  for (const auto& [k, measures] : in.measures)
  {
    if (k != static_cast<int>(frames.size()))
    {
      break;
    }
    frames.push_back(
      { in.signature.times[k], measures.coordinates, measures.fibreLengths, measures.lineLengths, measures.stepped });
  }
  std::vector<std::string> muscleNames;
  std::vector<std::vector<std::string>> lineNames;
  for (size_t m = 0; m < in.blockOf.size(); ++m)
  {
    const std::string muscle = mdvtk::NameOf(leaves.muscles[in.blockOf[m]]);
    muscleNames.push_back(in.deformation->Failures()[m].empty() ? muscle : std::string());
    lineNames.push_back(
      mdvtk::LineNames(leaves.restLines[leaves.restLinesOf[in.blockOf[m]]].data, muscle, in.restLines[m].size()));
  }
  // Failed muscles: no columns.
  for (size_t m = 0; m < muscleNames.size(); ++m)
  {
    if (muscleNames[m].empty())
    {
      lineNames[m].clear();
      for (mdvtk::FrameLengths& f : frames)
      {
        f.fibreLengths[m].clear();
        for (mdvtk::SteppedLengths& at : f.stepped)
        {
          at.fibreLengths[m].clear();
        }
      }
    }
  }
  mdvtk::WriteMomentArms(frames, in.coordinates, muscleNames, lineNames, table);
}

void vtkMotionMuscleDeformation::PrintSelf(ostream& os, vtkIndent indent)
{
  this->Superclass::PrintSelf(os, indent);
  os << indent << "NumberOfSteps: " << this->NumberOfSteps << "\n";
  os << indent << "MaximumStepDisplacement: " << this->MaximumStepDisplacement << "\n";
  os << indent << "BoneInterpolationMode: " << this->BoneInterpolationMode << "\n";
  os << indent << "DeformableShare: " << this->DeformableShare << "\n";
  os << indent << "PreserveVolume: " << this->PreserveVolume << "\n";
  os << indent << "CacheMemoryLimit: " << this->CacheMemoryLimit << "\n";
  os << indent << "AttachmentAreas: " << this->AttachmentAreas << "\n";
  os << indent << "AttachmentFileName: " << (this->AttachmentFileName ? this->AttachmentFileName : "") << "\n";
  os << indent << "NumberOfFibres: " << this->NumberOfFibres << "\n";
  os << indent << "FramesComputed: " << this->GetFramesComputed() << "\n";
  os << indent << "FramesKept: " << this->GetFramesKept() << "\n";
}
