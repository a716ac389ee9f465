// SPDX-License-Identifier: BSD-3-Clause
#include "vtkIntersectionResolve.h"

#include "Deformation/MuscleDeformer.h"
#include "Geometry/LocalFrame.h"
#include "Geometry/MeshChecks.h"
#include "Intersections/StaticIntersections.h"
#include "MDBlocks.h"
#include "MDConvert.h"
#include "MDReport.h"

#include <vtkDoubleArray.h>
#include <vtkFieldData.h>
#include <vtkInformation.h>
#include <vtkInformationVector.h>
#include <vtkObjectFactory.h>
#include <vtkPointData.h>
#include <vtkPolyData.h>

#include <algorithm>
#include <map>

vtkStandardNewMacro(vtkIntersectionResolve);

vtkIntersectionResolve::vtkIntersectionResolve()
{
  this->SetNumberOfInputPorts(4);
  this->DeformableShare = md::StaticResolveParameters().deformableShare;
}

int vtkIntersectionResolve::FillInputPortInformation(int port, vtkInformation* info)
{
  mdvtk::AcceptPolyDataOrMultiBlock(info);
  if (port > 0)
  {
    info->Set(vtkAlgorithm::INPUT_IS_OPTIONAL(), 1);
  }
  if (port == 1 || port == 3)
  {
    info->Set(vtkAlgorithm::INPUT_IS_REPEATABLE(), 1);
  }
  return 1;
}

namespace
{
/// The meshes of the leaves (null leaves stay empty), checked. A leaf that is no usable surface
/// is an error, or with `failed` given, noted there (leaf -> why) while the others are read.
bool ReadLeafMeshes(const std::vector<mdvtk::Leaf>& leaves, std::vector<md::TriangleMesh>& meshes, std::string& error,
  std::map<size_t, std::string>* failed = nullptr)
{
  meshes.resize(leaves.size());
  for (size_t b = 0; b < leaves.size(); ++b)
  {
    if (!leaves[b].data)
    {
      continue;
    }
    mdvtk::ReadTriangles(leaves[b].data, meshes[b]);
    if (meshes[b].triangles.rows() == 0)
    {
      error = leaves[b].label + " is not a usable surface: it has no triangles";
      if (!failed)
      {
        return false;
      }
      (*failed)[b] = error;
    }
  }
  return true;
}
}

int vtkIntersectionResolve::RequestUpdateExtent(
  vtkInformation* request, vtkInformationVector** inputVector, vtkInformationVector* outputVector)
{
  mdvtk::ClearOutputs(outputVector); // no stale result if an input fails upstream
  return this->Superclass::RequestUpdateExtent(request, inputVector, outputVector);
}

/// What RequestData read: the meshes to resolve (`deformable`, at blocks `used`; `deformableRest`
/// their rest pose when InputRest is given), the obstacles in both poses, what failed.
struct vtkIntersectionResolve::Read
{
  std::vector<mdvtk::Leaf> leaves;
  std::vector<md::TriangleMesh> deformable, deformableRest;
  std::vector<size_t> used;
  bool restGiven = false;
  std::vector<std::string> obstacleNames, restObstacleNames;
  std::vector<md::TriangleMesh> obstacles, restObstacles;
  std::map<size_t, std::string> failedBlocks; // one muscle's fault leaves the others to be resolved
};

int vtkIntersectionResolve::RequestData(
  vtkInformation*, vtkInformationVector** inputVector, vtkInformationVector* outputVector)
{
  Read read;
  if (!this->ReadInputs(inputVector, read))
  {
    return 0;
  }
  for (const auto& [b, message] : read.failedBlocks)
  {
    vtkErrorMacro(<< message);
  }
  if (read.used.empty() && !read.failedBlocks.empty())
  {
    return 0; // nothing left to resolve, each failure said
  }
  // In the local frame of the meshes to resolve: the same answer wherever they sit, whatever
  // their units.
  std::vector<const md::Points*> parts;
  for (const md::TriangleMesh& mesh : read.deformable)
  {
    parts.push_back(&mesh.points);
  }
  const md::LocalFrame frame = md::LocalFrame::Around(parts);
  for (auto* list : { &read.deformable, &read.deformableRest, &read.obstacles, &read.restObstacles })
  {
    for (md::TriangleMesh& mesh : *list)
    {
      frame.ToLocal(mesh.points);
    }
  }
  md::StaticStep step;
  int result = 1;
  if (!mdvtk::CallCore(
        this, "",
        [&] {
          md::StaticResolveParameters parameters;
          parameters.deformableShare = this->DeformableShare;
          step =
            md::ResolveStatically(read.deformable, read.restGiven ? &read.deformableRest : nullptr, read.obstacleNames,
              read.obstacles, read.restObstacleNames, read.restObstacles, parameters, mdvtk::ProgressOrCancel(this));
        },
        result))
  {
    return result;
  }
  std::vector<vtkSmartPointer<vtkPolyData>> outputs(read.leaves.size());
  for (size_t k = 0; k < read.used.size(); ++k)
  {
    const size_t b = read.used[k];
    md::Points points = step.resolved.points[k];
    frame.ToWorld(points);
    md::Points shifts = step.resolved.shift[k];
    frame.VectorsToWorld(shifts);
    outputs[b] = mdvtk::MovedCopy(read.leaves[b].data, points);
    outputs[b]->GetPointData()->AddArray(mdvtk::ToVtkArray(mdvtk::StaticShiftArrayName, shifts));
    // Field data describes this output only: the upstream measures (a deformation's volume
    // change, iterations, ...) no longer hold once points have moved.
    vtkNew<vtkFieldData> fieldData;
    const md::StaticResolveReport& r = step.resolved.reports[k];
    mdvtk::AddMeasures(fieldData,
      { { mdvtk::VolumeChangeArrayName, step.volumeChangePercent[k] },
        { "PenetratingPointCount", static_cast<double>(r.penetratingPoints), true },
        { "PenetratingGroupCount", static_cast<double>(r.groups), true },
        { "MaxPenetrationDepth", frame.LengthToWorld(r.maxDepth) },
        { mdvtk::array::MaxStaticShift, frame.LengthToWorld(r.maxShift) },
        { mdvtk::array::NewPenetrationCount, static_cast<double>(step.left[k].count), true },
        { mdvtk::array::MaxNewPenetrationDepth, frame.LengthToWorld(step.left[k].maxDepth) } });
    outputs[b]->SetFieldData(fieldData);
  }
  for (const auto& [b, message] : read.failedBlocks)
  {
    outputs[b] = mdvtk::FailedMuscle(read.leaves[b].data, message);
  }
  mdvtk::AssignLeaves(
    vtkDataObject::GetData(inputVector[0], 0), vtkDataObject::GetData(outputVector, 0), outputs, mdvtk::Role::Muscle);
  this->UpdateProgress(1.0);
  return 1;
}

bool vtkIntersectionResolve::ReadInputs(vtkInformationVector** inputVector, Read& read)
{
  std::vector<md::TriangleMesh> meshes;
  std::string error;
  if (!mdvtk::CollectLeaves(vtkDataObject::GetData(inputVector[0], 0), "Input", read.leaves, error) ||
    !ReadLeafMeshes(read.leaves, meshes, error, &read.failedBlocks) ||
    !mdvtk::ReadMeshes(inputVector[1], "Obstacles", read.obstacleNames, read.obstacles, error) ||
    !mdvtk::ReadMeshes(inputVector[3], "ObstaclesRest", read.restObstacleNames, read.restObstacles, error))
  {
    vtkErrorMacro(<< error);
    return false;
  }
  if (inputVector[1]->GetNumberOfInformationObjects() == 0)
  {
    vtkWarningMacro(<< "no Obstacles are connected: only the Input's meshes are kept out of one another, "
                       "nothing keeps them out of the bones; connect the bones in the current pose as Obstacles");
  }
  read.restGiven = inputVector[2]->GetNumberOfInformationObjects() > 0;
  if (!read.restGiven && !read.restObstacles.empty())
  {
    vtkWarningMacro(<< "ObstaclesRest is connected but InputRest is not: all penetration is resolved");
  }
  if (read.restGiven && !this->ObstaclesPair(read))
  {
    return false;
  }
  // Only the leaves with data take part; `used[k]` is the leaf of mesh k.
  std::vector<mdvtk::Leaf> restLeaves;
  std::vector<size_t> restOf;
  std::vector<md::TriangleMesh> restMeshes;
  if (read.restGiven &&
    (!mdvtk::CollectLeaves(vtkDataObject::GetData(inputVector[2], 0), "InputRest", restLeaves, error) ||
      !mdvtk::PairLeaves(this, read.leaves, "Input", restLeaves, "InputRest", restOf, error) ||
      !ReadLeafMeshes(restLeaves, restMeshes, error)))
  {
    vtkErrorMacro(<< error);
    return false;
  }
  for (size_t b = 0; b < read.leaves.size(); ++b)
  {
    if (!read.leaves[b].data || read.failedBlocks.count(b))
    {
      continue;
    }
    if (read.restGiven)
    {
      const md::TriangleMesh& rest = restMeshes[restOf[b]];
      if (rest.points.rows() != meshes[b].points.rows())
      {
        read.failedBlocks[b] = restLeaves[restOf[b]].label + " has " + std::to_string(rest.points.rows()) +
          " points but " + read.leaves[b].label + " has " + std::to_string(meshes[b].points.rows()) +
          ": InputRest must be the Input in the rest pose, with the same points";
        continue;
      }
      read.deformableRest.push_back({ rest.points, meshes[b].triangles });
    }
    // The volume change is measured against this volume: a flat surface has none to keep.
    const md::Points& reference = read.restGiven ? read.deformableRest.back().points : meshes[b].points;
    const double size = md::BoxDiagonal(reference);
    if (!(std::abs(md::SignedVolume(reference, meshes[b].triangles)) > md::kDegenerateShare * size * size * size))
    {
      read.failedBlocks[b] = (read.restGiven ? restLeaves[restOf[b]].label : read.leaves[b].label) +
        " encloses no volume (it is flat or degenerate): a muscle must be a closed surface around its volume";
      if (read.restGiven)
      {
        read.deformableRest.pop_back();
      }
      continue;
    }
    read.deformable.push_back(meshes[b]);
    read.used.push_back(b);
  }
  return true;
}

bool vtkIntersectionResolve::ObstaclesPair(const Read& read)
{
  if (read.restObstacles.empty())
  {
    return true;
  }
  if (read.restObstacles.size() != read.obstacles.size())
  {
    vtkErrorMacro(<< "ObstaclesRest has " << read.restObstacles.size() << " meshes but Obstacles has "
                  << read.obstacles.size() << ": connect the same obstacles in both poses, in the same order");
    return false;
  }
  for (size_t o = 0; o < read.obstacles.size(); ++o)
  {
    if (read.restObstacles[o].points.rows() != read.obstacles[o].points.rows())
    {
      vtkErrorMacro(<< "obstacle '" << read.obstacleNames[o] << "' has " << read.obstacles[o].points.rows()
                    << " points but its rest pose '" << read.restObstacleNames[o] << "' has "
                    << read.restObstacles[o].points.rows() << ": both poses must have the same points");
      return false;
    }
  }
  return true;
}

void vtkIntersectionResolve::PrintSelf(ostream& os, vtkIndent indent)
{
  this->Superclass::PrintSelf(os, indent);
  os << indent << "DeformableShare: " << this->DeformableShare << "\n";
}
