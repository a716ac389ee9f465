#include "vtkHullDecimation.h"

#include "MDBlocks.h"
#include "MeshChecks.h"
#include "ProgressiveHull.h"
#include "SurfaceRepair.h"

#include <vtkCellArray.h>
#include <vtkCellArrayIterator.h>
#include <vtkIdList.h>
#include <vtkFieldData.h>
#include <vtkIdTypeArray.h>
#include <vtkInformation.h>
#include <vtkInformationVector.h>
#include <vtkObjectFactory.h>
#include <vtkPolyData.h>
#include <vtkStringArray.h>
#include <vtkTriangleFilter.h>

#include <chrono>

vtkStandardNewMacro(vtkHullDecimation);

namespace
{
/// The polygons of `input` as triangles (polygons and strips triangulated).
/// Returns the number of cells that were not triangles.
vtkIdType ReadTriangles(vtkPolyData* input, md::TriangleMesh& mesh)
{
  vtkIdType converted = input->GetNumberOfStrips();
  vtkCellArray* polys = input->GetPolys();
  if (polys->IsHomogeneous() != 3)
  {
    auto it = vtk::TakeSmartPointer(polys->NewIterator());
    for (it->GoToFirstCell(); !it->IsDoneWithTraversal(); it->GoToNextCell())
    {
      converted += it->GetCurrentCell()->GetNumberOfIds() != 3 ? 1 : 0;
    }
  }
  vtkSmartPointer<vtkPolyData> triangles = input;
  if (converted > 0)
  {
    vtkNew<vtkTriangleFilter> triangulate;
    triangulate->SetInputData(input);
    triangulate->PassVertsOff();
    triangulate->PassLinesOff();
    triangulate->Update();
    triangles = triangulate->GetOutput();
  }
  mesh.points = mdvtk::ToPoints(triangles->GetPoints());
  vtkNew<vtkIdTypeArray> connectivity;
  connectivity->DeepCopy(triangles->GetPolys()->GetConnectivityArray());
  mesh.triangles.resize(triangles->GetNumberOfPolys(), 3);
  std::copy(connectivity->GetPointer(0), connectivity->GetPointer(0) + mesh.triangles.size(), mesh.triangles.data());
  return converted;
}

}

int vtkHullDecimation::FillInputPortInformation(int, vtkInformation* info)
{
  mdvtk::AcceptPolyDataOrMultiBlock(info);
  return 1;
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

  std::vector<vtkSmartPointer<vtkPolyData>> results(leaves.size());
  for (size_t b = 0; b < leaves.size(); ++b)
  {
    this->UpdateProgress(static_cast<double>(b) / leaves.size());
    const mdvtk::Leaf& leaf = leaves[b];
    if (!leaf.data)
    {
      continue;
    }
    if (leaf.data->GetNumberOfPolys() + leaf.data->GetNumberOfStrips() == 0)
    {
      vtkErrorMacro(<< leaf.label << " has no surface (no polygons); a muscle must be a closed triangle surface");
      return 0;
    }
    const auto start = std::chrono::steady_clock::now();
    md::TriangleMesh muscle;
    const vtkIdType converted = ReadTriangles(leaf.data, muscle);
    md::RepairReport report;
    md::TriangleMesh clean;
    md::HullResult hull;
    try
    {
      clean = md::RepairClosedSurface(muscle, report);
      hull = md::BuildProgressiveHull(clean, parameters, &report.pointsToEnclose);
    }
    catch (const md::InputError& e)
    {
      vtkErrorMacro(<< leaf.label << ": " << e.what());
      return 0;
    }
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
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
    const double hullVolume = md::SignedVolume(hull.hull.points, hull.hull.triangles);
    const double muscleVolume = md::SignedVolume(clean.points, clean.triangles);
    mdvtk::AddFieldValue(fieldData, "HullVolume", hullVolume);
    mdvtk::AddFieldValue(fieldData, "MuscleVolume", muscleVolume);
    mdvtk::AddFieldValue(fieldData, "HullVolumeRatio", hullVolume / muscleVolume);
    mdvtk::AddFieldValue(fieldData, "NumberOfCollapses", hull.collapses);
    mdvtk::AddFieldValue(fieldData, "ElapsedSeconds", seconds);
    if (report.Changed() || converted > 0)
    {
      vtkNew<vtkStringArray> repairs;
      repairs->SetName("Repairs");
      repairs->InsertNextValue(report.Describe());
      fieldData->AddArray(repairs);
    }
    if (this->VerifyEnclosure)
    {
      const double size = (muscle.points.colwise().maxCoeff() - muscle.points.colwise().minCoeff()).norm();
      const std::int64_t outside = md::CountOutside(hull.hull, md::UsedPoints(muscle), 1e-9 * size);
      const std::int64_t crossings = md::CountSelfIntersections(hull.hull);
      mdvtk::AddFieldValue(fieldData, "PointsOutsideHull", outside);
      mdvtk::AddFieldValue(fieldData, "HullSelfIntersections", crossings);
      if (outside > 0 || crossings > 0)
      {
        vtkWarningMacro(<< "the hull of " << leaf.label << " leaves " << outside << " muscle points outside and has "
                        << crossings << " self-intersecting triangle pairs");
      }
    }
    results[b] = output;
  }
  mdvtk::AssignLeaves(input, vtkDataObject::GetData(outputVector, 0), results);
  return 1;
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
