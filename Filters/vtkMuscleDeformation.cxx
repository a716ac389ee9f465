// SPDX-License-Identifier: BSD-3-Clause
#include "vtkMuscleDeformation.h"

#include "LocalFrame.h"
#include "MDBlocks.h"
#include "MeanValueCoordinates.h"
#include "MeshChecks.h"
#include "MuscleDeformer.h"
#include "ProgressiveHull.h"

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
#include <chrono>
#include <map>
#include <memory>

vtkStandardNewMacro(vtkMuscleDeformation);

namespace
{
using Clock = std::chrono::steady_clock;

double SecondsSince(Clock::time_point start)
{
  return std::chrono::duration<double>(Clock::now() - start).count();
}

/// The action lines of one block: each polyline's points and their
/// CurrentPosition (from ActionLineMatching), lines of too many points cut down (said in
/// `notes`). Fails with a message.
bool ReadMatchedLines(
  const mdvtk::Leaf& leaf, std::vector<md::MatchedLine>& lines, std::vector<std::string>& notes, std::string& error)
{
  vtkPolyData* data = leaf.data;
  if (!data || !data->GetLines() || data->GetLines()->GetNumberOfCells() == 0)
  {
    error = leaf.label + " has no polylines: each muscle needs its action lines";
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
  for (size_t l = 0; l < rest.size(); ++l)
  {
    lines.push_back({ rest[l], moved[l] });
  }
  notes = md::LimitActionLinePoints(lines);
  return true;
}
}

namespace
{
/// One muscle's rest-pose work: its hull (built or given) and the mean value coordinates of its
/// points in it, all in the local frame, with what they were made from.
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
}

struct vtkMuscleDeformation::RestPoseCache
{
  std::map<size_t, KeptMuscle> byBlock;
};

vtkMuscleDeformation::vtkMuscleDeformation()
  : Kept(std::make_unique<RestPoseCache>())
{
  this->SetNumberOfInputPorts(4);
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
  const auto start = Clock::now();
  vtkDataObject* input = vtkDataObject::GetData(inputVector[0], 0);
  std::vector<mdvtk::Leaf> muscles, lineLeaves, hullLeaves;
  std::vector<size_t> lineOf, hullOf;
  std::string error;
  if (!mdvtk::CollectLeaves(input, "Input", muscles, error) ||
    !mdvtk::CollectLeaves(vtkDataObject::GetData(inputVector[1], 0), "ActionLines", lineLeaves, error) ||
    !mdvtk::PairLeaves(this, muscles, "Input", lineLeaves, "ActionLines", lineOf, error))
  {
    vtkErrorMacro(<< error);
    return 0;
  }
  const bool hullGiven = inputVector[3]->GetNumberOfInformationObjects() > 0;
  if (hullGiven &&
    (!mdvtk::CollectLeaves(vtkDataObject::GetData(inputVector[3], 0), "Hull", hullLeaves, error) ||
      !mdvtk::PairLeaves(this, muscles, "Input", hullLeaves, "Hull", hullOf, error)))
  {
    vtkErrorMacro(<< error);
    return 0;
  }

  // Everything is read first, so that bad input is reported before any work.
  const size_t count = muscles.size();
  std::vector<md::TriangleMesh> surfaces(count), hulls(count);
  std::vector<md::MuscleToDeform> toDeform;
  std::vector<size_t> blockOf;
  std::vector<double> hullSeconds(count, 0.0);
  // One muscle's fault is reported and that muscle left out; the others go on.
  std::map<size_t, std::string> failedBlocks;
  auto fail = [&](size_t block, const std::string& message) {
    vtkErrorMacro(<< message);
    failedBlocks[block] = message;
  };
  for (size_t b = 0; b < count; ++b)
  {
    const mdvtk::Leaf& leaf = muscles[b];
    if (!leaf.data)
    {
      continue;
    }
    if (leaf.data->GetNumberOfPolys() + leaf.data->GetNumberOfStrips() == 0)
    {
      fail(b, leaf.label + " has no surface (no polygons); a muscle must be a closed triangle surface");
      continue;
    }
    mdvtk::ReadTriangles(leaf.data, surfaces[b]); // coordinates checked finite by CollectLeaves
    md::MuscleToDeform muscle;
    muscle.name = leaf.name.empty() ? leaf.label : leaf.name;
    muscle.muscle = &surfaces[b];
    std::vector<std::string> notes;
    if (!ReadMatchedLines(lineLeaves[lineOf[b]], muscle.lines, notes, error))
    {
      fail(b, error + " (for " + leaf.label + ")");
      continue;
    }
    for (const std::string& note : notes)
    {
      vtkWarningMacro(<< lineLeaves[lineOf[b]].label << ": " << note);
    }
    toDeform.push_back(std::move(muscle));
    blockOf.push_back(b);
  }
  if (toDeform.empty() && !failedBlocks.empty())
  {
    return 0; // every muscle failed, each said why
  }
  // Failures from here on are per muscle to deform, reported as found.
  std::vector<std::string> failures(toDeform.size());
  auto failMuscle = [&](size_t m, const std::string& message) {
    vtkErrorMacro(<< message);
    failures[m] = message;
  };
  if (hullGiven)
  {
    for (size_t m = 0; m < toDeform.size(); ++m)
    {
      const mdvtk::Leaf& hullLeaf = hullLeaves[hullOf[blockOf[m]]];
      if (!hullLeaf.data || hullLeaf.data->GetNumberOfPolys() == 0)
      {
        failMuscle(m, hullLeaf.label + " has no surface");
        continue;
      }
      mdvtk::ReadTriangles(hullLeaf.data, hulls[blockOf[m]]);
    }
  }

  // Obstacles: every block of every connection of port 2.
  std::vector<std::string> obstacleNames;
  std::vector<md::TriangleMesh> obstacleMeshes;
  if (!mdvtk::ReadMeshes(inputVector[2], "Obstacles", obstacleNames, obstacleMeshes, error))
  {
    vtkErrorMacro(<< error);
    return 0;
  }

  // The computation runs in the muscles' local frame: the same answer wherever they sit and
  // whatever their units.
  std::vector<const md::Points*> muscleParts;
  for (size_t b : blockOf)
  {
    muscleParts.push_back(&surfaces[b].points);
  }
  const md::LocalFrame frame = md::LocalFrame::Around(muscleParts);
  for (size_t m = 0; m < toDeform.size(); ++m)
  {
    frame.ToLocal(surfaces[blockOf[m]].points);
    frame.ToLocal(hulls[blockOf[m]].points);
    for (md::MatchedLine& line : toDeform[m].lines)
    {
      frame.ToLocal(line.rest);
      frame.ToLocal(line.current);
    }
  }
  for (md::TriangleMesh& obstacle : obstacleMeshes)
  {
    frame.ToLocal(obstacle.points);
  }

  // Hulls and their mean value coordinates: kept from an earlier run when the muscle (and its
  // given hull, or the hull size) are the same, else checked (given) or built.
  RestPoseCache& kept = *this->Kept;
  for (auto entry = kept.byBlock.begin(); entry != kept.byBlock.end();)
  {
    entry = std::find(blockOf.begin(), blockOf.end(), entry->first) == blockOf.end() ? kept.byBlock.erase(entry)
                                                                                     : std::next(entry);
  }
  for (size_t m = 0; m < toDeform.size(); ++m)
  {
    const size_t b = blockOf[m];
    const mdvtk::Leaf& leaf = muscles[b];
    this->UpdateProgress(0.3 * m / toDeform.size());
    if (this->CheckAbort())
    {
      return 1; // stopped by the user: the executive empties the output
    }
    if (!failures[m].empty())
    {
      continue;
    }
    const auto hullStart = Clock::now();
    KeptMuscle& entry = kept.byBlock[b];
    if (!entry.Holds(surfaces[b], frame, hullGiven, hullGiven ? &hulls[b] : nullptr, this->HullTargetNumberOfPoints))
    {
      entry = KeptMuscle{};
      if (hullGiven)
      {
        const mdvtk::Leaf& hullLeaf = hullLeaves[hullOf[b]];
        if (!md::CheckEdges(hulls[b].triangles).IsClosedOrientedManifold() ||
          md::SignedVolume(hulls[b].points, hulls[b].triangles) <= 0)
        {
          failMuscle(
            m, hullLeaf.label + " is not a closed, outward-oriented manifold surface: build it with HullDecimation");
          continue;
        }
        const std::int64_t outside = md::CountPointsOutsideHull(hulls[b], surfaces[b], frame.rounding);
        if (outside > 0)
        {
          failMuscle(m,
            hullLeaf.label + " does not enclose " + leaf.label + ": " + std::to_string(outside) + " of " +
              std::to_string(md::UsedPoints(surfaces[b]).rows()) +
              " muscle points are outside it, where mean value coordinates extrapolate; build the "
              "hull with HullDecimation or leave Hull empty");
          continue;
        }
        entry.hull = hulls[b];
      }
      md::HullParameters parameters;
      parameters.targetNumberOfPoints = this->HullTargetNumberOfPoints;
      parameters.cancelled = mdvtk::AbortRequested(this);
      int result = 1;
      std::string failure;
      if (!mdvtk::CallCore(
            this, leaf.label + ": ",
            [&] {
              if (!hullGiven)
              {
                const md::MuscleHull built = md::BuildMuscleHull(surfaces[b], parameters);
                ++this->HullBuildCount;
                entry.hull = built.result.hull;
                if (built.report.Changed())
                {
                  entry.repairs = built.report.Describe();
                }
              }
              entry.weights = md::MeanValueCoordinates(entry.hull, surfaces[b].points);
            },
            result, &failure))
      {
        if (failure.empty())
        {
          return result; // stopped by the user
        }
        failures[m] = failure; // reported
        entry = KeptMuscle{};  // a hull without its weights is not kept
        continue;
      }
      entry.surface = surfaces[b];
      entry.frame = frame;
      entry.hullGiven = hullGiven;
      entry.target = this->HullTargetNumberOfPoints;
    }
    if (!entry.repairs.empty())
    {
      vtkWarningMacro(<< leaf.label << " was repaired to build its hull: " << entry.repairs
                      << " (the muscle itself is deformed as given)");
    }
    toDeform[m].hull = &entry.hull;
    toDeform[m].weights = &entry.weights;
    hullSeconds[b] = SecondsSince(hullStart);
  }

  md::DeformationParameters parameters;
  parameters.maximumIterations = this->MaximumNumberOfIterations;
  parameters.maximumCoarseIterations = this->MaximumCoarseIterations;
  parameters.convergenceTolerance = frame.LengthToLocal(this->ConvergenceTolerance);
  parameters.stepLength = this->StepLength;
  parameters.samplesPerSegment = this->SamplesPerSegment;
  parameters.preserveVolume = this->PreserveVolume;
  parameters.dynamicIntersections = this->DynamicIntersections;
  std::vector<md::DeformationResult> results;
  const std::vector<std::string> reportedBefore = failures;
  int result = 1;
  if (!mdvtk::CallCore(
        this, "",
        [&] {
          const std::vector<md::Obstacle> obstacles = this->DynamicIntersections
            ? md::BuildObstacles(obstacleNames, obstacleMeshes)
            : std::vector<md::Obstacle>{};
          results = md::DeformMusclesThatCan(
            toDeform, obstacles, parameters, failures, mdvtk::ProgressOrCancel(this, 0.3, 0.7));
        },
        result))
  {
    return result;
  }
  const double seconds = SecondsSince(start);

  std::vector<vtkSmartPointer<vtkPolyData>> outputs(count);
  for (size_t m = 0; m < results.size(); ++m)
  {
    const size_t b = blockOf[m];
    if (!failures[m].empty())
    {
      if (reportedBefore[m].empty()) // the deformation's own failure, not said yet
      {
        fail(b, muscles[b].label + ": " + failures[m]);
      }
      else
      {
        failedBlocks[b] = failures[m];
      }
      continue;
    }
    const md::DeformationResult& r = results[m];
    for (const std::string& warning : r.warnings)
    {
      vtkWarningMacro(<< warning);
    }
    md::Points displacement = r.points - surfaces[b].points;
    frame.VectorsToWorld(displacement);
    md::Points points = r.points;
    frame.ToWorld(points);
    auto output = vtkSmartPointer<vtkPolyData>::New();
    output->ShallowCopy(muscles[b].data);
    output->SetPoints(mdvtk::ToVtkPoints(points));
    output->GetPointData()->AddArray(mdvtk::ToVtkArray(mdvtk::DisplacementArrayName, displacement));
    vtkNew<vtkFieldData> fieldData;
    fieldData->DeepCopy(muscles[b].data->GetFieldData());
    mdvtk::AddFieldValue(fieldData, mdvtk::VolumeChangeArrayName, r.volumeChangePercent);
    mdvtk::AddFieldValue(fieldData, "NumberOfIterations", r.iterations);
    mdvtk::AddFieldValue(fieldData, "CoarseIterations", r.coarseIterations);
    mdvtk::AddFieldValue(fieldData, "Converged", r.converged ? 1 : 0);
    mdvtk::AddFieldValue(fieldData, "FlippedTriangleCount", r.flippedTriangles);
    mdvtk::AddFieldValue(fieldData, "PointsFrozenInObstacles", r.verticesFrozen);
    mdvtk::AddFieldValue(fieldData, "PointsStoppedAtObstacles", r.verticesStopped);
    mdvtk::AddFieldValue(fieldData, "RestActionLineSamplesInside", r.restSamplesInside);
    mdvtk::AddFieldValue(fieldData, "CurrentActionLineSamplesInside", r.currentSamplesInside);
    mdvtk::AddFieldValue(fieldData, "HullSeconds", hullSeconds[b]);
    mdvtk::AddFieldValue(fieldData, "DeformationSeconds", r.seconds);
    mdvtk::AddFieldValue(fieldData, "ElapsedSeconds", seconds);
    output->SetFieldData(fieldData);
    outputs[b] = output;
  }
  for (const auto& [b, message] : failedBlocks)
  {
    outputs[b] = mdvtk::FailedMuscle(muscles[b].data, message);
  }
  mdvtk::AssignLeaves(input, vtkDataObject::GetData(outputVector, 0), outputs, mdvtk::Role::Muscle);
  this->UpdateProgress(1.0);
  return 1;
}

void vtkMuscleDeformation::PrintSelf(ostream& os, vtkIndent indent)
{
  this->Superclass::PrintSelf(os, indent);
  os << indent << "MaximumNumberOfIterations: " << this->MaximumNumberOfIterations << "\n";
  os << indent << "MaximumCoarseIterations: " << this->MaximumCoarseIterations << "\n";
  os << indent << "ConvergenceTolerance: " << this->ConvergenceTolerance << "\n";
  os << indent << "StepLength: " << this->StepLength << "\n";
  os << indent << "SamplesPerSegment: " << this->SamplesPerSegment << "\n";
  os << indent << "PreserveVolume: " << this->PreserveVolume << "\n";
  os << indent << "DynamicIntersections: " << this->DynamicIntersections << "\n";
  os << indent << "HullTargetNumberOfPoints: " << this->HullTargetNumberOfPoints << "\n";
  os << indent << "HullBuildCount: " << this->HullBuildCount << "\n";
}
