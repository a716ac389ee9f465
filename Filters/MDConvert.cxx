// SPDX-License-Identifier: BSD-3-Clause
#include "MDConvert.h"

#include "MDArrays.h"

#include <vtkAOSDataArrayTemplate.h>
#include <vtkAbstractArray.h>
#include <vtkCellArray.h>
#include <vtkCellArrayIterator.h>
#include <vtkCellData.h>
#include <vtkCompositeDataSet.h>
#include <vtkDataObjectTreeIterator.h>
#include <vtkDoubleArray.h>
#include <vtkFieldData.h>
#include <vtkIdList.h>
#include <vtkIdTypeArray.h>
#include <vtkInformation.h>
#include <vtkInformationVector.h>
#include <vtkMultiBlockDataSet.h>
#include <vtkPointData.h>
#include <vtkPoints.h>
#include <vtkPolyData.h>
#include <vtkTriangleFilter.h>

#include <algorithm>

namespace mdvtk
{
using md::Points;
using md::TriangleMesh;

vtkSmartPointer<vtkPolyData> MovedCopy(vtkPolyData* input, const Points& points)
{
  auto output = vtkSmartPointer<vtkPolyData>::New();
  output->ShallowCopy(input);
  vtkNew<vtkFieldData> fieldData;
  fieldData->DeepCopy(input->GetFieldData());
  output->SetFieldData(fieldData);
  output->SetPoints(ToVtkPoints(points));
  return output;
}

vtkSmartPointer<vtkPolyData> MovedMuscle(vtkPolyData* input, const Points& points, const Points& displacement)
{
  vtkSmartPointer<vtkPolyData> output = MovedCopy(input, points);
  output->GetPointData()->AddArray(ToVtkArray(DisplacementArrayName, displacement));
  return output;
}

Points ToPoints(vtkDataArray* array)
{
  const vtkIdType n = array ? array->GetNumberOfTuples() : 0;
  Points out(n, 3);
  if (n == 0)
  {
    return out;
  }
  // One call into VTK per array rather than per point: VTK here is built -O0. Scans are usually
  // float: read from its memory directly (a DeepCopy into doubles goes value by value).
  if (auto* floats = vtkAOSDataArrayTemplate<float>::FastDownCast(array))
  {
    if (floats->GetNumberOfComponents() == 3)
    {
      const float* values = floats->GetPointer(0);
      std::copy(values, values + 3 * n, out.data());
      return out;
    }
  }
  vtkSmartPointer<vtkDoubleArray> doubles = vtkDoubleArray::SafeDownCast(array);
  if (!doubles)
  {
    doubles = vtkSmartPointer<vtkDoubleArray>::New();
    doubles->DeepCopy(array);
  }
  std::copy(doubles->GetPointer(0), doubles->GetPointer(0) + 3 * n, out.data());
  return out;
}

Points ToPoints(vtkPoints* points)
{
  return ToPoints(points ? points->GetData() : nullptr);
}

vtkSmartPointer<vtkPoints> ToVtkPoints(const Points& points)
{
  auto out = vtkSmartPointer<vtkPoints>::New();
  out->SetData(ToVtkArray(nullptr, points));
  return out;
}

vtkSmartPointer<vtkDoubleArray> ToVtkArray(const char* name, const Points& values)
{
  auto array = vtkSmartPointer<vtkDoubleArray>::New();
  array->SetName(name);
  array->SetNumberOfComponents(3);
  array->SetNumberOfTuples(values.rows());
  std::copy(values.data(), values.data() + values.size(), array->GetPointer(0));
  return array;
}

vtkSmartPointer<vtkPolyData> ToPolyData(const TriangleMesh& mesh)
{
  auto polyData = vtkSmartPointer<vtkPolyData>::New();
  polyData->SetPoints(ToVtkPoints(mesh.points));
  vtkNew<vtkIdTypeArray> connectivity;
  connectivity->SetNumberOfValues(mesh.triangles.size());
  std::copy(mesh.triangles.data(), mesh.triangles.data() + mesh.triangles.size(), connectivity->GetPointer(0));
  vtkNew<vtkCellArray> polys;
  polys->SetData(3, connectivity);
  polyData->SetPolys(polys);
  return polyData;
}

vtkSmartPointer<vtkPolyData> ToPolyLines(const std::vector<Points>& lines)
{
  Eigen::Index total = 0;
  for (const Points& line : lines)
  {
    total += line.rows();
  }
  Points all(total, 3);
  vtkNew<vtkCellArray> cells;
  vtkIdType next = 0;
  for (const Points& line : lines)
  {
    const auto n = static_cast<vtkIdType>(line.rows());
    all.middleRows(next, n) = line;
    cells->InsertNextCell(n);
    for (vtkIdType k = 0; k < n; ++k)
    {
      cells->InsertCellPoint(next + k);
    }
    next += n;
  }
  auto output = vtkSmartPointer<vtkPolyData>::New();
  output->SetPoints(ToVtkPoints(all));
  output->SetLines(cells);
  return output;
}

std::vector<std::vector<vtkIdType>> PolylineIds(vtkPolyData* polyData)
{
  std::vector<std::vector<vtkIdType>> polylines;
  vtkCellArray* cells = polyData ? polyData->GetLines() : nullptr;
  if (!cells)
  {
    return polylines;
  }
  auto it = vtk::TakeSmartPointer(cells->NewIterator());
  for (it->GoToFirstCell(); !it->IsDoneWithTraversal(); it->GoToNextCell())
  {
    vtkIdType size;
    const vtkIdType* ids;
    it->GetCurrentCell(size, ids);
    polylines.emplace_back(ids, ids + size);
  }
  return polylines;
}

std::vector<Knots> ToKnots(vtkPolyData* polyData)
{
  vtkDataArray* own = polyData ? polyData->GetPointData()->GetArray(array::PathOwnPoint) : nullptr;
  std::vector<Knots> knots;
  if (!own || own->GetNumberOfTuples() != polyData->GetNumberOfPoints())
  {
    return knots;
  }
  for (const std::vector<vtkIdType>& ids : PolylineIds(polyData))
  {
    Knots line;
    for (size_t k = 0; k < ids.size(); ++k)
    {
      if (k == 0 || k + 1 == ids.size() || own->GetComponent(ids[k], 0) != 0)
      {
        line.push_back(static_cast<Eigen::Index>(k));
      }
    }
    knots.push_back(std::move(line));
  }
  return knots;
}

std::vector<Points> ToPolylines(vtkPolyData* polyData, const Points* values)
{
  std::vector<Points> lines;
  const std::vector<std::vector<vtkIdType>> polylines = PolylineIds(polyData);
  if (polylines.empty())
  {
    return lines;
  }
  const Points all = values ? Points() : ToPoints(polyData->GetPoints());
  const Points& source = values ? *values : all;
  for (const std::vector<vtkIdType>& ids : polylines)
  {
    Points line(static_cast<Eigen::Index>(ids.size()), 3);
    for (size_t k = 0; k < ids.size(); ++k)
    {
      line.row(static_cast<Eigen::Index>(k)) = source.row(ids[k]);
    }
    lines.push_back(std::move(line));
  }
  return lines;
}

/// The polygons of `input` as triangles (polygons and strips triangulated).
/// Returns the number of cells that were not triangles.
vtkIdType ReadTriangles(vtkPolyData* input, TriangleMesh& mesh)
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
  mesh.points = ToPoints(triangles->GetPoints());
  vtkCellArray* cells = triangles->GetPolys();
  if (cells->GetNumberOfConnectivityIds() == 3 * cells->GetNumberOfCells())
  {
    vtkNew<vtkIdTypeArray> connectivity;
    connectivity->DeepCopy(cells->GetConnectivityArray());
    mesh.triangles.resize(cells->GetNumberOfCells(), 3);
    std::copy(connectivity->GetPointer(0), connectivity->GetPointer(0) + mesh.triangles.size(), mesh.triangles.data());
    return converted;
  }
  // Cells the triangulation left as they were (polygons of one or two points): not triangles.
  std::vector<std::int64_t> ids;
  auto it = vtk::TakeSmartPointer(cells->NewIterator());
  for (it->GoToFirstCell(); !it->IsDoneWithTraversal(); it->GoToNextCell())
  {
    vtkIdType size;
    const vtkIdType* cell;
    it->GetCurrentCell(size, cell);
    if (size == 3)
    {
      ids.insert(ids.end(), cell, cell + 3);
    }
  }
  mesh.triangles.resize(static_cast<Eigen::Index>(ids.size() / 3), 3);
  std::copy(ids.begin(), ids.end(), mesh.triangles.data());
  return converted;
}

}
