// Finding and reading the real data sets (../shared/data) for tests and benchmarks.
#pragma once

#include "MeshTypes.h"

#include <vtkCellArray.h>
#include <vtkIdTypeArray.h>
#include <vtkNew.h>
#include <vtkPolyData.h>
#include <vtkPolyDataReader.h>
#include <vtkSTLReader.h>
#include <vtkTriangleFilter.h>

#include <cstdlib>
#include <fstream>
#include <string>

/// `folder`/`relative` (folder: the argument, else $MUSCLEDEFORMATION_DATA_DIR),
/// or "" when there is no such file.
inline std::string RealDataFile(const std::string& relative, const std::string& folder = "")
{
  const char* fromEnvironment = std::getenv("MUSCLEDEFORMATION_DATA_DIR");
  const std::string base = !folder.empty() ? folder : (fromEnvironment ? fromEnvironment : "");
  const std::string path = base + "/" + relative;
  return std::ifstream(path).good() ? path : std::string();
}

/// The triangles of a legacy .vtk or an .stl surface (polygons and strips triangulated).
inline md::TriangleMesh ReadSurface(const std::string& path)
{
  vtkNew<vtkTriangleFilter> triangles;
  if (path.size() > 4 && path.substr(path.size() - 4) == ".stl")
  {
    vtkNew<vtkSTLReader> reader;
    reader->SetFileName(path.c_str());
    triangles->SetInputConnection(reader->GetOutputPort());
  }
  else
  {
    vtkNew<vtkPolyDataReader> reader;
    reader->SetFileName(path.c_str());
    triangles->SetInputConnection(reader->GetOutputPort());
  }
  triangles->PassVertsOff();
  triangles->PassLinesOff();
  triangles->Update();
  vtkPolyData* data = triangles->GetOutput();
  md::TriangleMesh mesh;
  mesh.points.resize(data->GetNumberOfPoints(), 3);
  for (vtkIdType i = 0; i < data->GetNumberOfPoints(); ++i)
  {
    data->GetPoint(i, mesh.points.row(i).data());
  }
  vtkNew<vtkIdTypeArray> connectivity;
  connectivity->DeepCopy(data->GetPolys()->GetConnectivityArray());
  mesh.triangles.resize(data->GetNumberOfPolys(), 3);
  std::copy(connectivity->GetPointer(0), connectivity->GetPointer(0) + mesh.triangles.size(), mesh.triangles.data());
  return mesh;
}
