// SPDX-License-Identifier: BSD-3-Clause
#include "vtkMuscleDeformation.h"

#include "Common/Clock.h"
#include "Deformation/MuscleDeformer.h"
#include "Geometry/LocalFrame.h"
#include "Geometry/MeanValueCoordinates.h"
#include "Geometry/MeshChecks.h"
#include "Hull/ProgressiveHull.h"
#include "MDBlocks.h"
#include "MDConvert.h"
#include "MDReport.h"
#include "Settle/SurfacePass.h"

#include <vtkCellArray.h>
#include <vtkDataArray.h>
#include <vtkDoubleArray.h>
#include <vtkFieldData.h>
#include <vtkInformation.h>
#include <vtkInformationVector.h>
#include <vtkObjectFactory.h>
#include <vtkPointData.h>
#include <vtkPolyData.h>

#include <algorithm>
#include <functional>
#include <map>
#include <memory>

vtkStandardNewMacro(vtkMuscleDeformation);

namespace
{
/// The action lines of one block: each polyline's points and their
/// CurrentPosition (from ActionLineMatching), lines of too many points cut down (said in
/// `notes`). Fails with a message.
bool ReadMatchedLines(
  const mdvtk::Leaf& leaf, std::vector<md::MatchedLine>& lines, std::vector<std::string>& notes, std::string& error)
{
  vtkPolyData* data = leaf.data;
  if (!data || !data->GetLines() || data->GetLines()->GetNumberOfCells() == 0)
  {
    error = leaf.label + " has no polylines" + mdvtk::UpstreamFailure(data) + ": each muscle needs its action lines";
    return false;
  }
  vtkDataArray* current = data->GetPointData()->GetArray(mdvtk::CurrentPositionArrayName);
  if (!current || current->GetNumberOfComponents() != 3)
  {
    error = leaf.label + " has no point array CurrentPosition (3 components): connect output 0 of ActionLineMatching";
    return false;
  }
  const md::Points currentPositions = mdvtk::ToPoints(current);
  const std::vector<md::Points> rest = mdvtk::ToPolylines(data);
  const std::vector<md::Points> moved = mdvtk::ToPolylines(data, &currentPositions);
  const std::vector<md::Knots> knots = mdvtk::ToKnots(data);
  for (size_t l = 0; l < rest.size(); ++l)
  {
    lines.push_back({ rest[l], moved[l], l < knots.size() ? knots[l] : md::Knots() });
  }
  notes = md::LimitActionLinePoints(lines);
  return true;
}
}

namespace
{
/// One muscle's rest-pose work on the hull: its hull (built or given) and the mean value
/// coordinates of its points in it, all in the local frame, with what they were made from.
struct KeptMuscle
{
  md::TriangleMesh surface;
  md::LocalFrame frame;
  bool hullGiven = false;
  int target = 0;
  md::TriangleMesh hull;
  md::WeightMatrix weights;
  std::string repairs; ///< what the repair before the hull changed, said again on every run

  bool Holds(const md::TriangleMesh& muscle, const md::LocalFrame& now, bool given, const md::TriangleMesh* givenHull,
    int targetNumberOfPoints) const
  {
    return this->weights.size() > 0 && this->hullGiven == given && md::SameMesh(this->surface, muscle) &&
      this->frame.origin == now.origin && this->frame.unit == now.unit &&
      (given ? md::SameMesh(this->hull, *givenHull) : this->target == targetNumberOfPoints);
  }
};

/// Forgets what blocks no longer among `blocks` kept.
template<class Entry>
void EraseOthers(std::map<size_t, Entry>& byBlock, const std::vector<size_t>& blocks)
{
  for (auto entry = byBlock.begin(); entry != byBlock.end();)
  {
    entry =
      std::find(blocks.begin(), blocks.end(), entry->first) == blocks.end() ? byBlock.erase(entry) : std::next(entry);
  }
}
}

/// What one muscle's pass gives, on either mesh (in the local frame).
struct vtkMuscleDeformation::PassOutcome
{
  md::Points points;
  double volumeChangePercent = 0;
  int iterations = 0;
  bool converged = false;
  std::int64_t flippedTriangles = 0;
  double restSeconds = 0; ///< the hull and its mapping, or the full-mesh energy
  double deformationSeconds = 0;
  std::vector<std::string> warnings;
  std::function<void(vtkFieldData*)> addOwnMeasures; ///< the measures only one mesh has
};

/// Everything RequestData read, in the local frame: the muscles to deform (`blockOf` their input
/// blocks) and the obstacles.
struct vtkMuscleDeformation::PassInput
{
  std::vector<md::MuscleToDeform>& toDeform;
  const std::vector<size_t>& blockOf;
  const std::vector<md::TriangleMesh>& surfaces;
  const std::vector<mdvtk::Leaf>& muscles;
  const std::vector<std::string>& obstacleNames;
  const std::vector<md::TriangleMesh>& obstacleMeshes;
  const md::LocalFrame& frame;
};

/// What RequestData read, per muscle block (muscles, lines, hulls) or per muscle to deform
/// (`toDeform`, at blocks `blockOf`), what failed, the obstacles, and the outputs.
struct vtkMuscleDeformation::Read
{
  std::vector<mdvtk::Leaf> muscles, lineLeaves, hullLeaves;
  std::vector<size_t> lineOf, hullOf;
  bool hullGiven = false;
  std::vector<md::TriangleMesh> surfaces, hulls;
  std::vector<md::MuscleToDeform> toDeform;
  std::vector<size_t> blockOf;
  std::map<size_t, std::string> failedBlocks;
  std::vector<std::string> failures; ///< per muscle to deform
  std::vector<std::string> obstacleNames;
  std::vector<md::TriangleMesh> obstacleMeshes;
  std::vector<vtkSmartPointer<vtkPolyData>> outputs;
};

struct vtkMuscleDeformation::RestPoseCache
{
  std::map<size_t, KeptMuscle> hulls;
  /// Compared in the local frame: the same muscle and lines placed elsewhere keep their energy.
  std::map<size_t, md::KeptSurfaceEnergy> energies;
};

bool vtkMuscleDeformation::PassOnSurface(const PassInput& in, std::vector<std::string>& failures,
  std::vector<std::string>& reportedBefore, std::vector<PassOutcome>& outcomes, int& result)
{
  md::SettleParameters parameters;
  parameters.samplesPerSegment = this->SamplesPerSegment;
  std::vector<md::MuscleToSettle> toSettle(in.toDeform.size());
  for (size_t m = 0; m < in.toDeform.size(); ++m)
  {
    const size_t b = in.blockOf[m];
    if (mdvtk::ProgressOrStop(this, 0.3 * m / in.toDeform.size()))
    {
      result = 1;
      return false;
    }
    toSettle[m] = { in.toDeform[m].name, &in.surfaces[b], in.toDeform[m].lines, nullptr };
    if (!failures[m].empty())
    {
      continue;
    }
    const auto energyStart = md::Clock::now();
    const std::vector<md::MatchedLine> restLines = md::StillLines(in.toDeform[m].lines);
    md::KeptSurfaceEnergy& entry = this->Kept->energies[b];
    if (!entry.Holds(in.surfaces[b], restLines, parameters))
    {
      entry = md::KeptSurfaceEnergy{};
      std::string failure;
      if (!mdvtk::CallCore(
            this, in.muscles[b].label + ": ",
            [&] {
              entry.Keep(std::make_shared<const md::SurfaceEnergy>(in.surfaces[b], restLines, parameters),
                in.surfaces[b], restLines, parameters);
              ++this->SurfaceEnergyBuildCount;
            },
            result, &failure))
      {
        if (failure.empty())
        {
          return false; // stopped by the user
        }
        failures[m] = failure; // reported
        continue;
      }
    }
    if (const std::string warning = entry.energy->UndrivenWarning(in.toDeform[m].name); !warning.empty())
    {
      vtkWarningMacro(<< warning);
    }
    toSettle[m].energy = entry.energy.get();
    outcomes[m].restSeconds = md::SecondsSince(energyStart);
  }
  reportedBefore = failures;
  std::vector<md::SurfacePassResult> settled;
  if (!mdvtk::CallCore(
        this, "",
        [&] {
          const std::vector<md::Obstacle> obstacles = md::BuildObstacles(in.obstacleNames, in.obstacleMeshes);
          settled = md::SettleInOnePassThatCan(
            toSettle, md::FixedObstacles(obstacles), parameters, failures, mdvtk::ProgressOrCancel(this, 0.3, 0.7));
        },
        result))
  {
    return false;
  }
  for (size_t m = 0; m < settled.size(); ++m)
  {
    if (!failures[m].empty())
    {
      continue;
    }
    md::SurfacePassResult& r = settled[m];
    PassOutcome& out = outcomes[m];
    out.points = std::move(r.points);
    out.volumeChangePercent = r.volumeChangePercent;
    out.iterations = r.report.iterations;
    out.converged = r.report.converged;
    out.flippedTriangles = r.flippedTriangles;
    out.deformationSeconds = r.report.seconds;
    out.warnings = std::move(r.warnings);
    const std::int64_t inContact = r.report.pointsInContact;
    out.addOwnMeasures = [inContact](vtkFieldData* fieldData) {
      mdvtk::AddFieldValue(fieldData, "PointsInContact", inContact);
    };
  }
  return true;
}

vtkMuscleDeformation::HullReady vtkMuscleDeformation::KeepHull(const PassInput& in, size_t m,
  const md::TriangleMesh* givenHull, const std::string& hullLabel, std::string& failure, int& result)
{
  const size_t b = in.blockOf[m];
  const mdvtk::Leaf& leaf = in.muscles[b];
  KeptMuscle& entry = this->Kept->hulls[b];
  if (entry.Holds(in.surfaces[b], in.frame, givenHull != nullptr, givenHull, this->HullTargetNumberOfPoints))
  {
    return HullReady::Yes;
  }
  entry = KeptMuscle{};
  if (givenHull &&
    !mdvtk::CallCore(
      this, "", [&] { md::CheckGivenHull(*givenHull, hullLabel, in.surfaces[b], leaf.label, in.frame.rounding); },
      result, &failure))
  {
    return failure.empty() ? HullReady::Stopped : HullReady::No;
  }
  md::HullParameters parameters;
  parameters.targetNumberOfPoints = this->HullTargetNumberOfPoints;
  parameters.cancelled = mdvtk::AbortRequested(this);
  if (!mdvtk::CallCore(
        this, leaf.label + ": ",
        [&] {
          if (givenHull)
          {
            entry.hull = *givenHull;
          }
          else
          {
            const md::MuscleHull built = md::BuildMuscleHull(in.surfaces[b], parameters);
            ++this->HullBuildCount;
            entry.hull = built.result.hull;
            if (built.report.Changed())
            {
              entry.repairs = built.report.Describe();
            }
          }
          entry.weights = md::MeanValueCoordinates(entry.hull, in.surfaces[b].points);
        },
        result, &failure))
  {
    entry = KeptMuscle{}; // a hull without its weights is not kept
    return failure.empty() ? HullReady::Stopped : HullReady::No;
  }
  entry.surface = in.surfaces[b];
  entry.frame = in.frame;
  entry.hullGiven = givenHull != nullptr;
  entry.target = this->HullTargetNumberOfPoints;
  return HullReady::Yes;
}

bool vtkMuscleDeformation::PassOnHull(const PassInput& in, bool hullGiven, std::vector<md::TriangleMesh>& hulls,
  const std::vector<mdvtk::Leaf>& hullLeaves, const std::vector<size_t>& hullOf, std::vector<std::string>& failures,
  std::vector<std::string>& reportedBefore, std::vector<PassOutcome>& outcomes, int& result)
{
  // Hulls and their mean value coordinates: kept from an earlier run when the muscle (and its
  // given hull, or the hull size) are the same, else checked (given) or built.
  for (size_t m = 0; m < in.toDeform.size(); ++m)
  {
    const size_t b = in.blockOf[m];
    if (mdvtk::ProgressOrStop(this, 0.3 * m / in.toDeform.size()))
    {
      result = 1;
      return false;
    }
    if (!failures[m].empty())
    {
      continue;
    }
    const auto hullStart = md::Clock::now();
    const HullReady ready = this->KeepHull(
      in, m, hullGiven ? &hulls[b] : nullptr, hullGiven ? hullLeaves[hullOf[b]].label : "", failures[m], result);
    if (ready == HullReady::Stopped)
    {
      return false;
    }
    if (ready == HullReady::No)
    {
      continue; // failures[m] says why, reported
    }
    const KeptMuscle& entry = this->Kept->hulls[b];
    if (!entry.repairs.empty())
    {
      vtkWarningMacro(<< in.muscles[b].label << " was repaired to build its hull: " << entry.repairs
                      << " (the muscle itself is deformed as given)");
    }
    in.toDeform[m].hull = &entry.hull;
    in.toDeform[m].weights = &entry.weights;
    outcomes[m].restSeconds = md::SecondsSince(hullStart);
  }

  md::DeformationParameters parameters;
  parameters.maximumIterations = this->MaximumNumberOfIterations;
  parameters.maximumCoarseIterations = this->MaximumCoarseIterations;
  parameters.convergenceTolerance = in.frame.LengthToLocal(this->ConvergenceTolerance);
  parameters.stepLength = this->StepLength;
  parameters.samplesPerSegment = this->SamplesPerSegment;
  parameters.preserveVolume = this->PreserveVolume;
  parameters.dynamicIntersections = this->DynamicIntersections;
  reportedBefore = failures;
  std::vector<md::DeformationResult> results;
  if (!mdvtk::CallCore(
        this, "",
        [&] {
          const std::vector<md::Obstacle> obstacles = this->DynamicIntersections
            ? md::BuildObstacles(in.obstacleNames, in.obstacleMeshes)
            : std::vector<md::Obstacle>{};
          results = md::DeformMusclesThatCan(
            in.toDeform, obstacles, parameters, failures, mdvtk::ProgressOrCancel(this, 0.3, 0.7));
        },
        result))
  {
    return false;
  }
  for (size_t m = 0; m < results.size(); ++m)
  {
    if (!failures[m].empty())
    {
      continue;
    }
    const md::DeformationResult& r = results[m];
    PassOutcome& out = outcomes[m];
    out.points = r.points;
    out.volumeChangePercent = r.volumeChangePercent;
    out.iterations = r.iterations;
    out.converged = r.converged;
    out.flippedTriangles = r.flippedTriangles;
    out.deformationSeconds = r.seconds;
    out.warnings = r.warnings;
    out.addOwnMeasures = [r](vtkFieldData* fieldData) {
      mdvtk::AddFieldValue(fieldData, "CoarseIterations", r.coarseIterations);
      mdvtk::AddFieldValue(fieldData, mdvtk::array::PointsFrozenInObstacles, r.verticesFrozen);
      mdvtk::AddFieldValue(fieldData, "PointsStoppedAtObstacles", r.verticesStopped);
      mdvtk::AddFieldValue(fieldData, "RestActionLineSamplesInside", r.restSamplesInside);
      mdvtk::AddFieldValue(fieldData, "CurrentActionLineSamplesInside", r.currentSamplesInside);
    };
  }
  return true;
}

vtkMuscleDeformation::vtkMuscleDeformation()
  : Kept(std::make_unique<RestPoseCache>())
{
  this->SetNumberOfInputPorts(4);
  const md::DeformationParameters deformation;
  this->MaximumNumberOfIterations = deformation.maximumIterations;
  this->MaximumCoarseIterations = deformation.maximumCoarseIterations;
  this->ConvergenceTolerance = deformation.convergenceTolerance;
  this->StepLength = deformation.stepLength;
  this->SamplesPerSegment = deformation.samplesPerSegment;
  this->PreserveVolume = deformation.preserveVolume;
  this->DynamicIntersections = deformation.dynamicIntersections;
  this->HullTargetNumberOfPoints = md::HullParameters().targetNumberOfPoints;
}

vtkMuscleDeformation::~vtkMuscleDeformation() = default;

int vtkMuscleDeformation::FillInputPortInformation(int port, vtkInformation* info)
{
  mdvtk::AcceptPolyDataOrMultiBlock(info);
  if (port == 2)
  {
    info->Set(vtkAlgorithm::INPUT_IS_REPEATABLE(), 1);
    info->Set(vtkAlgorithm::INPUT_IS_OPTIONAL(), 1);
  }
  if (port == 3)
  {
    info->Set(vtkAlgorithm::INPUT_IS_OPTIONAL(), 1);
  }
  return 1;
}

int vtkMuscleDeformation::RequestUpdateExtent(
  vtkInformation* request, vtkInformationVector** inputVector, vtkInformationVector* outputVector)
{
  mdvtk::ClearOutputs(outputVector); // no stale result if an input fails upstream
  return this->Superclass::RequestUpdateExtent(request, inputVector, outputVector);
}

int vtkMuscleDeformation::RequestData(
  vtkInformation*, vtkInformationVector** inputVector, vtkInformationVector* outputVector)
{
  const auto start = md::Clock::now();
  // Everything is read first, so that bad input is reported before any work.
  Read read;
  if (!this->ReadMuscles(inputVector, read))
  {
    return 0;
  }
  if (read.toDeform.empty() && !read.failedBlocks.empty())
  {
    return 0; // every muscle failed, each said why
  }
  std::string error;
  if (!mdvtk::ReadMeshes(inputVector[2], "Obstacles", read.obstacleNames, read.obstacleMeshes, error))
  {
    vtkErrorMacro(<< error);
    return 0;
  }
  const md::LocalFrame frame = ToLocalFrame(read);
  // Only the muscles that are still in keep what their rest pose made.
  EraseOthers(this->Kept->hulls, read.blockOf);
  EraseOthers(this->Kept->energies, read.blockOf);

  const PassInput in{ read.toDeform, read.blockOf, read.surfaces, read.muscles, read.obstacleNames, read.obstacleMeshes,
    frame };
  std::vector<PassOutcome> outcomes(read.toDeform.size());
  std::vector<std::string> reportedBefore; // the failures said before the deformation
  int result = 1;
  if (this->DeformationMesh == MUSCLE_SURFACE)
  {
    if (read.hullGiven)
    {
      vtkWarningMacro(<< "the Hull input is not used with DeformationMesh Muscle surface (only with Hull (paper))");
    }
    if (!this->PassOnSurface(in, read.failures, reportedBefore, outcomes, result))
    {
      return result;
    }
  }
  else if (!this->PassOnHull(in, read.hullGiven, read.hulls, read.hullLeaves, read.hullOf, read.failures,
             reportedBefore, outcomes, result))
  {
    return result;
  }
  this->WriteMuscles(read, reportedBefore, frame, outcomes, md::SecondsSince(start));
  mdvtk::AssignLeaves(vtkDataObject::GetData(inputVector[0], 0), vtkDataObject::GetData(outputVector, 0), read.outputs,
    mdvtk::Role::Muscle);
  this->UpdateProgress(1.0);
  return 1;
}

bool vtkMuscleDeformation::ReadMuscles(vtkInformationVector** inputVector, Read& read)
{
  std::string error;
  if (!mdvtk::CollectLeaves(vtkDataObject::GetData(inputVector[0], 0), "Input", read.muscles, error) ||
    !mdvtk::CollectLeaves(vtkDataObject::GetData(inputVector[1], 0), "ActionLines", read.lineLeaves, error) ||
    !mdvtk::PairLeaves(this, read.muscles, "Input", read.lineLeaves, "ActionLines", read.lineOf, error))
  {
    vtkErrorMacro(<< error);
    return false;
  }
  read.hullGiven = inputVector[3]->GetNumberOfInformationObjects() > 0;
  if (read.hullGiven &&
    (!mdvtk::CollectLeaves(vtkDataObject::GetData(inputVector[3], 0), "Hull", read.hullLeaves, error) ||
      !mdvtk::PairLeaves(this, read.muscles, "Input", read.hullLeaves, "Hull", read.hullOf, error)))
  {
    vtkErrorMacro(<< error);
    return false;
  }
  const size_t count = read.muscles.size();
  read.surfaces.resize(count);
  read.hulls.resize(count);
  read.outputs.resize(count);
  // One muscle's fault is reported and that muscle left out; the others go on.
  for (size_t b = 0; b < count; ++b)
  {
    const mdvtk::Leaf& leaf = read.muscles[b];
    if (!leaf.data)
    {
      continue;
    }
    if (!mdvtk::ReadMuscleSurface(leaf, read.surfaces[b], error)) // coordinates checked by CollectLeaves
    {
      mdvtk::FailBlock(this, read.failedBlocks, b, error);
      continue;
    }
    md::MuscleToDeform muscle;
    muscle.name = mdvtk::NameOf(leaf);
    muscle.muscle = &read.surfaces[b];
    std::vector<std::string> notes;
    if (!ReadMatchedLines(read.lineLeaves[read.lineOf[b]], muscle.lines, notes, error))
    {
      mdvtk::FailBlock(this, read.failedBlocks, b, error + " (for " + leaf.label + ")");
      continue;
    }
    for (const std::string& note : notes)
    {
      vtkWarningMacro(<< read.lineLeaves[read.lineOf[b]].label << ": " << note);
    }
    read.toDeform.push_back(std::move(muscle));
    read.blockOf.push_back(b);
  }
  // Failures from here on are per muscle to deform, reported as found.
  read.failures.resize(read.toDeform.size());
  for (size_t m = 0; read.hullGiven && m < read.toDeform.size(); ++m)
  {
    const mdvtk::Leaf& hullLeaf = read.hullLeaves[read.hullOf[read.blockOf[m]]];
    if (!hullLeaf.data || hullLeaf.data->GetNumberOfPolys() == 0)
    {
      read.failures[m] = hullLeaf.label + " has no surface";
      vtkErrorMacro(<< read.failures[m]);
      continue;
    }
    mdvtk::ReadTriangles(hullLeaf.data, read.hulls[read.blockOf[m]]);
  }
  return true;
}

md::LocalFrame vtkMuscleDeformation::ToLocalFrame(Read& read)
{
  // The computation runs in the muscles' local frame: the same answer wherever they sit and
  // whatever their units.
  std::vector<const md::Points*> muscleParts;
  for (size_t b : read.blockOf)
  {
    muscleParts.push_back(&read.surfaces[b].points);
  }
  const md::LocalFrame frame = md::LocalFrame::Around(muscleParts);
  for (size_t m = 0; m < read.toDeform.size(); ++m)
  {
    frame.ToLocal(read.surfaces[read.blockOf[m]].points);
    frame.ToLocal(read.hulls[read.blockOf[m]].points);
    for (md::MatchedLine& line : read.toDeform[m].lines)
    {
      frame.ToLocal(line.rest);
      frame.ToLocal(line.current);
    }
  }
  for (md::TriangleMesh& obstacle : read.obstacleMeshes)
  {
    frame.ToLocal(obstacle.points);
  }
  return frame;
}

void vtkMuscleDeformation::WriteMuscles(Read& read, const std::vector<std::string>& reportedBefore,
  const md::LocalFrame& frame, std::vector<PassOutcome>& outcomes, double seconds)
{
  for (size_t m = 0; m < outcomes.size(); ++m)
  {
    const size_t b = read.blockOf[m];
    if (!read.failures[m].empty())
    {
      // The deformation's own failure is said here; the earlier ones were said as found.
      mdvtk::FailBlock(this, read.failedBlocks, b,
        reportedBefore[m].empty() ? read.muscles[b].label + ": " + read.failures[m] : read.failures[m],
        !reportedBefore[m].empty());
      continue;
    }
    PassOutcome& r = outcomes[m];
    for (const std::string& warning : r.warnings)
    {
      vtkWarningMacro(<< warning);
    }
    md::Points displacement = r.points - read.surfaces[b].points;
    frame.VectorsToWorld(displacement);
    frame.ToWorld(r.points);
    read.outputs[b] = mdvtk::MovedMuscle(read.muscles[b].data, r.points, displacement);
    vtkFieldData* fieldData = read.outputs[b]->GetFieldData();
    mdvtk::AddFieldValue(fieldData, mdvtk::VolumeChangeArrayName, r.volumeChangePercent);
    mdvtk::AddFieldValue(fieldData, mdvtk::array::NumberOfIterations, r.iterations);
    mdvtk::AddFieldValue(fieldData, mdvtk::array::Converged, r.converged ? 1 : 0);
    mdvtk::AddFieldValue(fieldData, mdvtk::array::FlippedTriangleCount, r.flippedTriangles);
    r.addOwnMeasures(fieldData);
    mdvtk::AddFieldValue(fieldData, mdvtk::array::HullSeconds, r.restSeconds);
    mdvtk::AddFieldValue(fieldData, "DeformationSeconds", r.deformationSeconds);
    mdvtk::AddFieldValue(fieldData, mdvtk::array::ElapsedSeconds, seconds);
  }
  for (const auto& [b, message] : read.failedBlocks)
  {
    read.outputs[b] = mdvtk::FailedMuscle(read.muscles[b].data, message);
  }
}

void vtkMuscleDeformation::PrintSelf(ostream& os, vtkIndent indent)
{
  this->Superclass::PrintSelf(os, indent);
  os << indent << "DeformationMesh: " << (this->DeformationMesh == HULL ? "Hull (paper)" : "Muscle surface") << "\n";
  os << indent << "MaximumNumberOfIterations: " << this->MaximumNumberOfIterations << "\n";
  os << indent << "MaximumCoarseIterations: " << this->MaximumCoarseIterations << "\n";
  os << indent << "ConvergenceTolerance: " << this->ConvergenceTolerance << "\n";
  os << indent << "StepLength: " << this->StepLength << "\n";
  os << indent << "SamplesPerSegment: " << this->SamplesPerSegment << "\n";
  os << indent << "PreserveVolume: " << this->PreserveVolume << "\n";
  os << indent << "DynamicIntersections: " << this->DynamicIntersections << "\n";
  os << indent << "HullTargetNumberOfPoints: " << this->HullTargetNumberOfPoints << "\n";
  os << indent << "HullBuildCount: " << this->HullBuildCount << "\n";
  os << indent << "SurfaceEnergyBuildCount: " << this->SurfaceEnergyBuildCount << "\n";
}
