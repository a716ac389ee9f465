// SPDX-License-Identifier: BSD-3-Clause
#include "vtkHullDecimation.h"

#include "Common/Clock.h"
#include "Geometry/MeshChecks.h"
#include "Hull/ProgressiveHull.h"
#include "MDBlocks.h"
#include "MDConvert.h"
#include "MDReport.h"

#include <vtkFieldData.h>
#include <vtkInformation.h>
#include <vtkInformationVector.h>
#include <vtkObjectFactory.h>
#include <vtkPolyData.h>
#include <vtkStringArray.h>

vtkStandardNewMacro(vtkHullDecimation);

int vtkHullDecimation::FillInputPortInformation(int, vtkInformation* info)
{
  mdvtk::AcceptPolyDataOrMultiBlock(info);
  return 1;
}

vtkHullDecimation::vtkHullDecimation()
{
  const md::HullParameters hull;
  this->TargetNumberOfPoints = hull.targetNumberOfPoints;
  this->MinimumAngle = hull.minimumAngleDegrees;
  this->MaximumNormalDeviation = hull.maximumNormalDeviationDegrees;
  this->MaximumFoldAngle = hull.maximumFoldAngleDegrees;
}

int vtkHullDecimation::RequestUpdateExtent(
  vtkInformation* request, vtkInformationVector** inputVector, vtkInformationVector* outputVector)
{
  mdvtk::ClearOutputs(outputVector); // no stale result if an input fails upstream
  return this->Superclass::RequestUpdateExtent(request, inputVector, outputVector);
}

int vtkHullDecimation::RequestData(
  vtkInformation*, vtkInformationVector** inputVector, vtkInformationVector* outputVector)
{
  vtkDataObject* input = vtkDataObject::GetData(inputVector[0], 0);
  std::vector<mdvtk::Leaf> leaves;
  std::string error;
  if (!mdvtk::CollectLeaves(input, "Input", leaves, error))
  {
    vtkErrorMacro(<< error);
    return 0;
  }
  md::HullParameters parameters;
  parameters.targetNumberOfPoints = this->TargetNumberOfPoints;
  parameters.minimumAngleDegrees = this->MinimumAngle;
  parameters.maximumNormalDeviationDegrees = this->MaximumNormalDeviation;
  parameters.maximumFoldAngleDegrees = this->MaximumFoldAngle;
  parameters.cancelled = mdvtk::AbortRequested(this);

  std::vector<vtkSmartPointer<vtkPolyData>> results(leaves.size());
  size_t muscleCount = 0, failedCount = 0;
  for (size_t b = 0; b < leaves.size(); ++b)
  {
    if (mdvtk::ProgressOrStop(this, static_cast<double>(b) / leaves.size()))
    {
      return 1;
    }
    const mdvtk::Leaf& leaf = leaves[b];
    if (!leaf.data)
    {
      continue;
    }
    ++muscleCount;
    const auto start = md::Clock::now();
    md::TriangleMesh muscle;
    vtkIdType converted = 0;
    std::string message;
    if (!mdvtk::ReadMuscleSurface(leaf, muscle, message, &converted))
    {
      vtkErrorMacro(<< message);
      results[b] = mdvtk::FailedMuscle(leaf.data, message); // the other muscles go on
      ++failedCount;
      continue;
    }
    md::MuscleHull built;
    int result = 1;
    std::string failure;
    if (!mdvtk::CallCore(
          this, leaf.label + ": ", [&] { built = md::BuildMuscleHull(muscle, parameters); }, result, &failure))
    {
      if (failure.empty())
      {
        return result; // stopped by the user
      }
      results[b] = mdvtk::FailedMuscle(leaf.data, failure); // the other muscles go on
      ++failedCount;
      continue;
    }
    const double seconds = md::SecondsSince(start);
    results[b] = this->HullOutput(leaf, built, converted, seconds);
  }
  mdvtk::AssignLeaves(input, vtkDataObject::GetData(outputVector, 0), results, mdvtk::Role::Hull);
  return muscleCount > 0 && failedCount == muscleCount ? 0 : 1; // each failure was reported
}

vtkSmartPointer<vtkPolyData> vtkHullDecimation::HullOutput(
  const mdvtk::Leaf& leaf, const md::MuscleHull& built, vtkIdType converted, double seconds)
{
  const md::RepairReport& report = built.report;
  const md::HullResult& hull = built.result;
  if (converted > 0 || report.Changed())
  {
    vtkWarningMacro(<< leaf.label << " was repaired before building its hull: "
                    << (converted > 0 ? "triangulated " + std::to_string(converted) + " polygons or strips" : "")
                    << (converted > 0 && report.Changed() ? ", " : "") << report.Describe());
  }
  if (!hull.reachedTarget)
  {
    vtkWarningMacro(<< "the hull of " << leaf.label << " has " << hull.hull.points.rows()
                    << " points: no further collapse kept it enclosing, manifold and free of folds and "
                       "self-intersections (target "
                    << this->TargetNumberOfPoints << ")");
  }
  auto output = mdvtk::ToPolyData(hull.hull);
  vtkFieldData* fieldData = output->GetFieldData();
  mdvtk::AddFieldValue(fieldData, "HullVolume", built.hullVolume);
  mdvtk::AddFieldValue(fieldData, "MuscleVolume", built.cleanVolume);
  mdvtk::AddFieldValue(fieldData, "HullVolumeRatio", built.hullVolume / built.cleanVolume);
  mdvtk::AddFieldValue(fieldData, "NumberOfCollapses", hull.collapses);
  mdvtk::AddFieldValue(fieldData, mdvtk::array::ElapsedSeconds, seconds);
  if (report.Changed() || converted > 0)
  {
    vtkNew<vtkStringArray> repairs;
    repairs->SetName("Repairs");
    repairs->InsertNextValue(report.Describe());
    fieldData->AddArray(repairs);
  }
  if (this->VerifyEnclosure)
  {
    // BuildMuscleHull has checked that every muscle point is inside: none is left outside.
    const std::int64_t crossings = md::CountSelfIntersections(hull.hull);
    mdvtk::AddFieldValue(fieldData, "PointsOutsideHull", std::int64_t{ 0 });
    mdvtk::AddFieldValue(fieldData, "HullSelfIntersections", crossings);
    if (crossings > 0)
    {
      vtkWarningMacro(<< "the hull of " << leaf.label << " has " << crossings << " self-intersecting triangle pairs");
    }
  }
  return output;
}

void vtkHullDecimation::PrintSelf(ostream& os, vtkIndent indent)
{
  this->Superclass::PrintSelf(os, indent);
  os << indent << "TargetNumberOfPoints: " << this->TargetNumberOfPoints << "\n";
  os << indent << "MinimumAngle: " << this->MinimumAngle << "\n";
  os << indent << "MaximumNormalDeviation: " << this->MaximumNormalDeviation << "\n";
  os << indent << "MaximumFoldAngle: " << this->MaximumFoldAngle << "\n";
  os << indent << "VerifyEnclosure: " << this->VerifyEnclosure << "\n";
}
