#include "vtkMuscleDeformation.h"

#include "MDBlocks.h"
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

#include <chrono>
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
bool ReadMatchedLines(const mdvtk::Leaf& leaf, std::vector<md::MatchedLine>& lines, std::vector<std::string>& notes,
  std::string& error)
{
  vtkPolyData* data = leaf.data;
  if (!data || !data->GetLines() || data->GetLines()->GetNumberOfCells() == 0)
  {
    error = leaf.label + " has no polylines: each muscle needs its action lines";
    return false;
  }
  vtkDataArray* current = data->GetPointData()->GetArray("CurrentPosition");
  if (!current || current->GetNumberOfComponents() != 3)
  {
    error = leaf.label +
      " has no point array CurrentPosition (3 components): connect output 0 of ActionLineMatching";
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

vtkMuscleDeformation::vtkMuscleDeformation()
{
  this->SetNumberOfInputPorts(4);
}

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
    !mdvtk::PairLeaves(muscles, "Input", lineLeaves, "ActionLines", lineOf, error))
  {
    vtkErrorMacro(<< error);
    return 0;
  }
  const bool hullGiven = inputVector[3]->GetNumberOfInformationObjects() > 0;
  if (hullGiven &&
    (!mdvtk::CollectLeaves(vtkDataObject::GetData(inputVector[3], 0), "Hull", hullLeaves, error) ||
      !mdvtk::PairLeaves(muscles, "Input", hullLeaves, "Hull", hullOf, error)))
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
  for (size_t b = 0; b < count; ++b)
  {
    const mdvtk::Leaf& leaf = muscles[b];
    if (!leaf.data)
    {
      continue;
    }
    if (leaf.data->GetNumberOfPolys() + leaf.data->GetNumberOfStrips() == 0)
    {
      vtkErrorMacro(<< leaf.label << " has no surface (no polygons); a muscle must be a closed triangle surface");
      return 0;
    }
    mdvtk::ReadTriangles(leaf.data, surfaces[b]); // coordinates checked finite by CollectLeaves
    md::MuscleToDeform muscle;
    muscle.name = leaf.name.empty() ? leaf.label : leaf.name;
    muscle.muscle = &surfaces[b];
    std::vector<std::string> notes;
    if (!ReadMatchedLines(lineLeaves[lineOf[b]], muscle.lines, notes, error))
    {
      vtkErrorMacro(<< error << " (for " << leaf.label << ")");
      return 0;
    }
    for (const std::string& note : notes)
    {
      vtkWarningMacro(<< lineLeaves[lineOf[b]].label << ": " << note);
    }
    toDeform.push_back(std::move(muscle));
    blockOf.push_back(b);
  }

  // Obstacles: every block of every connection of port 2.
  std::vector<std::string> obstacleNames;
  std::vector<md::TriangleMesh> obstacleMeshes;
  if (!mdvtk::ReadMeshes(inputVector[2], "Obstacles", obstacleNames, obstacleMeshes, error))
  {
    vtkErrorMacro(<< error);
    return 0;
  }

  // Hulls: given (and checked to enclose the muscle), or built.
  for (size_t m = 0; m < toDeform.size(); ++m)
  {
    const size_t b = blockOf[m];
    const mdvtk::Leaf& leaf = muscles[b];
    this->UpdateProgress(0.3 * m / toDeform.size());
    const auto hullStart = Clock::now();
    if (hullGiven)
    {
      const mdvtk::Leaf& hullLeaf = hullLeaves[hullOf[b]];
      if (!hullLeaf.data || hullLeaf.data->GetNumberOfPolys() == 0)
      {
        vtkErrorMacro(<< hullLeaf.label << " has no surface");
        return 0;
      }
      mdvtk::ReadTriangles(hullLeaf.data, hulls[b]);
      if (!md::CheckEdges(hulls[b].triangles).IsClosedOrientedManifold() ||
        md::SignedVolume(hulls[b].points, hulls[b].triangles) <= 0)
      {
        vtkErrorMacro(<< hullLeaf.label
                      << " is not a closed, outward-oriented manifold surface: build it with HullDecimation");
        return 0;
      }
      const std::int64_t outside = md::CountPointsOutsideHull(hulls[b], surfaces[b]);
      if (outside > 0)
      {
        vtkErrorMacro(<< hullLeaf.label << " does not enclose " << leaf.label << ": " << outside << " of "
                      << md::UsedPoints(surfaces[b]).rows()
                      << " muscle points are outside it, where mean value coordinates extrapolate; build the "
                         "hull with HullDecimation or leave Hull empty");
        return 0;
      }
    }
    else
    {
      md::HullParameters parameters;
      parameters.targetNumberOfPoints = this->HullTargetNumberOfPoints;
      try
      {
        const md::MuscleHull built = md::BuildMuscleHull(surfaces[b], parameters);
        hulls[b] = built.result.hull;
        if (built.report.Changed())
        {
          vtkWarningMacro(<< leaf.label << " was repaired to build its hull: " << built.report.Describe()
                          << " (the muscle itself is deformed as given)");
        }
      }
      catch (const md::InputError& e)
      {
        vtkErrorMacro(<< leaf.label << ": " << e.what());
        return 0;
      }
    }
    toDeform[m].hull = &hulls[b];
    hullSeconds[b] = SecondsSince(hullStart);
  }

  md::DeformationParameters parameters;
  parameters.maximumIterations = this->MaximumNumberOfIterations;
  parameters.maximumCoarseIterations = this->MaximumCoarseIterations;
  parameters.convergenceTolerance = this->ConvergenceTolerance;
  parameters.stepLength = this->StepLength;
  parameters.samplesPerSegment = this->SamplesPerSegment;
  parameters.preserveVolume = this->PreserveVolume;
  parameters.dynamicIntersections = this->DynamicIntersections;
  std::vector<md::DeformationResult> results;
  try
  {
    const std::vector<md::Obstacle> obstacles = this->DynamicIntersections
      ? md::BuildObstacles(obstacleNames, obstacleMeshes)
      : std::vector<md::Obstacle>{};
    results = md::DeformMuscles(
      toDeform, obstacles, parameters, [this](double fraction) { this->UpdateProgress(0.3 + 0.7 * fraction); });
  }
  catch (const md::InputError& e)
  {
    vtkErrorMacro(<< e.what());
    return 0;
  }
  const double seconds = SecondsSince(start);

  std::vector<vtkSmartPointer<vtkPolyData>> outputs(count);
  for (size_t m = 0; m < results.size(); ++m)
  {
    const size_t b = blockOf[m];
    const md::DeformationResult& r = results[m];
    for (const std::string& warning : r.warnings)
    {
      vtkWarningMacro(<< warning);
    }
    auto output = vtkSmartPointer<vtkPolyData>::New();
    output->ShallowCopy(muscles[b].data);
    output->SetPoints(mdvtk::ToVtkPoints(r.points));
    vtkNew<vtkDoubleArray> displacement;
    displacement->SetName("Displacement");
    displacement->SetNumberOfComponents(3);
    displacement->SetNumberOfTuples(r.points.rows());
    for (Eigen::Index i = 0; i < r.points.rows(); ++i)
    {
      const Eigen::RowVector3d d = r.points.row(i) - surfaces[b].points.row(i);
      displacement->SetTuple(i, d.data());
    }
    output->GetPointData()->AddArray(displacement);
    vtkNew<vtkFieldData> fieldData;
    fieldData->DeepCopy(muscles[b].data->GetFieldData());
    mdvtk::AddFieldValue(fieldData, "VolumeChangePercent", r.volumeChangePercent);
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
  mdvtk::AssignLeaves(input, vtkDataObject::GetData(outputVector, 0), outputs);
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
}
