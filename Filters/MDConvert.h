// SPDX-License-Identifier: BSD-3-Clause
// Geometry between VTK and the core's Eigen meshes: points, triangles, polylines, the moved copy
// of an input. Not part of the public API; the filters' inputs are read through MDBlocks.h, which
// builds on it.
#pragma once

#include "Common/MeshTypes.h"

#include <vtkSmartPointer.h>
#include <vtkType.h>

#include <string>
#include <vector>

class vtkDataArray;
class vtkDoubleArray;
class vtkPoints;
class vtkPolyData;

namespace mdvtk
{
using md::Knots;
using md::Points;
using md::TriangleMesh;

/// A copy of `input` at `points`: its cells and arrays shared, its field data its own (for the
/// measures a filter adds).
vtkSmartPointer<vtkPolyData> MovedCopy(vtkPolyData* input, const Points& points);
/// MovedCopy of a muscle, with point array Displacement (`displacement`, a row per point).
vtkSmartPointer<vtkPolyData> MovedMuscle(vtkPolyData* input, const Points& points, const Points& displacement);

/// Point coordinates in double precision.
Points ToPoints(vtkPoints* points);
/// The tuples of a 3-component array (such as CurrentPosition) in double precision.
Points ToPoints(vtkDataArray* array);
vtkSmartPointer<vtkPoints> ToVtkPoints(const Points& points);
/// A 3-component point array named `name` holding the rows of `values` (displacements, shifts).
vtkSmartPointer<vtkDoubleArray> ToVtkArray(const char* name, const Points& values);
vtkSmartPointer<vtkPolyData> ToPolyData(const TriangleMesh& mesh);
/// The polygons of `input` as triangles (polygons and strips triangulated),
/// with all of its points. Returns the number of cells that were not triangles.
vtkIdType ReadTriangles(vtkPolyData* input, TriangleMesh& mesh);
/// The polylines of a polydata, each as its point coordinates, or as the rows
/// of `values` (one per point of the polydata, e.g. a point array) when given.
std::vector<Points> ToPolylines(vtkPolyData* polyData, const Points* values = nullptr);
/// The point ids of each polyline of a polydata, in order (none without one).
std::vector<std::vector<vtkIdType>> PolylineIds(vtkPolyData* polyData);
/// The own points (array::PathOwnPoint) of each polyline of a polydata, ToPolylines' order; its
/// first and last point are always its own. None (every point its own) without the array.
std::vector<Knots> ToKnots(vtkPolyData* polyData);
/// A polydata with one polyline cell per entry of `lines`, their points in order.
vtkSmartPointer<vtkPolyData> ToPolyLines(const std::vector<Points>& lines);
}
