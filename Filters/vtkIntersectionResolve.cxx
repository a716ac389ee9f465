// SPDX-License-Identifier: BSD-3-Clause
#include "vtkIntersectionResolve.h"

#include "LocalFrame.h"
#include "MDBlocks.h"
#include "MeshChecks.h"
#include "MuscleDeformer.h"
#include "StaticIntersections.h"

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

int vtkIntersectionResolve::RequestData(
  vtkInformation*, vtkInformationVector** inputVector, vtkInformationVector* outputVector)
{
  vtkDataObject* input = vtkDataObject::GetData(inputVector[0], 0);
  std::vector<mdvtk::Leaf> leaves;
  std::vector<md::TriangleMesh> meshes;
  std::vector<std::string> obstacleNames, restObstacleNames;
  std::vector<md::TriangleMesh> obstacles, restObstacles;
  std::string error;
  std::map<size_t, std::string> failedBlocks; // one muscle's fault leaves the others to be resolved
  if (!mdvtk::CollectLeaves(input, "Input", leaves, error) || !ReadLeafMeshes(leaves, meshes, error, &failedBlocks) ||
    !mdvtk::ReadMeshes(inputVector[1], "Obstacles", obstacleNames, obstacles, error) ||
    !mdvtk::ReadMeshes(inputVector[3], "ObstaclesRest", restObstacleNames, restObstacles, error))
  {
    vtkErrorMacro(<< error);
    return 0;
  }
  if (inputVector[1]->GetNumberOfInformationObjects() == 0)
  {
    vtkWarningMacro(<< "no Obstacles are connected: only the Input's meshes are kept out of one another, "
                       "nothing keeps them out of the bones; connect the bones in the current pose as Obstacles");
  }
  const bool restGiven = inputVector[2]->GetNumberOfInformationObjects() > 0;
  if (!restGiven && !restObstacles.empty())
  {
    vtkWarningMacro(<< "ObstaclesRest is connected but InputRest is not: all penetration is resolved");
  }
  if (restGiven && !restObstacles.empty())
  {
    if (restObstacles.size() != obstacles.size())
    {
      vtkErrorMacro(<< "ObstaclesRest has " << restObstacles.size() << " meshes but Obstacles has " << obstacles.size()
                    << ": connect the same obstacles in both poses, in the same order");
      return 0;
    }
    for (size_t o = 0; o < obstacles.size(); ++o)
    {
      if (restObstacles[o].points.rows() != obstacles[o].points.rows())
      {
        vtkErrorMacro(<< "obstacle '" << obstacleNames[o] << "' has " << obstacles[o].points.rows()
                      << " points but its rest pose '" << restObstacleNames[o] << "' has "
                      << restObstacles[o].points.rows() << ": both poses must have the same points");
        return 0;
      }
    }
  }

  // Only the leaves with data take part; `used[k]` is the leaf of mesh k.
  std::vector<md::TriangleMesh> deformable, deformableRest;
  std::vector<size_t> used;
  std::vector<mdvtk::Leaf> restLeaves;
  std::vector<size_t> restOf;
  std::vector<md::TriangleMesh> restMeshes;
  if (restGiven &&
    (!mdvtk::CollectLeaves(vtkDataObject::GetData(inputVector[2], 0), "InputRest", restLeaves, error) ||
      !mdvtk::PairLeaves(this, leaves, "Input", restLeaves, "InputRest", restOf, error) ||
      !ReadLeafMeshes(restLeaves, restMeshes, error)))
  {
    vtkErrorMacro(<< error);
    return 0;
  }
  for (size_t b = 0; b < leaves.size(); ++b)
  {
    if (!leaves[b].data || failedBlocks.count(b))
    {
      continue;
    }
    if (restGiven)
    {
      const md::TriangleMesh& rest = restMeshes[restOf[b]];
      if (rest.points.rows() != meshes[b].points.rows())
      {
        failedBlocks[b] = restLeaves[restOf[b]].label + " has " + std::to_string(rest.points.rows()) + " points but " +
          leaves[b].label + " has " + std::to_string(meshes[b].points.rows()) +
          ": InputRest must be the Input in the rest pose, with the same points";
        continue;
      }
      deformableRest.push_back({ rest.points, meshes[b].triangles });
    }
    deformable.push_back(meshes[b]);
    used.push_back(b);
  }
  for (const auto& [b, message] : failedBlocks)
  {
    vtkErrorMacro(<< message);
  }
  if (used.empty() && !failedBlocks.empty())
  {
    return 0; // nothing left to resolve, each failure said
  }

  // In the local frame of the meshes to resolve: the same answer wherever they sit, whatever
  // their units.
  std::vector<const md::Points*> parts;
  for (const md::TriangleMesh& mesh : deformable)
  {
    parts.push_back(&mesh.points);
  }
  const md::LocalFrame frame = md::LocalFrame::Around(parts);
  for (auto* list : { &deformable, &deformableRest, &obstacles, &restObstacles })
  {
    for (md::TriangleMesh& mesh : *list)
    {
      frame.ToLocal(mesh.points);
    }
  }

  md::OverlapMasks existing;
  std::vector<md::Obstacle> trees, restTrees;
  auto fixedOf = [](const std::vector<md::Obstacle>& list) {
    std::vector<md::FixedObstacle> fixed;
    for (const md::Obstacle& o : list)
    {
      fixed.push_back({ o.name, o.tree.get() });
    }
    return fixed;
  };
  md::StaticResolveResult resolved;
  std::vector<md::Penetration> left;
  int result = 1;
  if (!mdvtk::CallCore(
        this, "",
        [&] {
          trees = md::BuildObstacles(obstacleNames, obstacles);
          this->UpdateProgress(0.2);
          if (restGiven)
          {
            restTrees = restObstacles.empty() ? trees : md::BuildObstacles(restObstacleNames, restObstacles);
            existing = md::FindOverlaps(deformableRest, fixedOf(restTrees));
          }
          this->UpdateProgress(0.4);
          md::StaticResolveParameters parameters;
          parameters.deformableShare = this->DeformableShare;
          const std::vector<md::FixedObstacle> fixed = fixedOf(trees);
          resolved = md::ResolveStaticIntersections(deformable, fixed, restGiven ? &existing : nullptr, parameters);
          this->UpdateProgress(0.8);
          std::vector<md::TriangleMesh> after = deformable;
          for (size_t k = 0; k < after.size(); ++k)
          {
            after[k].points = resolved.points[k];
          }
          left = md::MeasureNewPenetration(after, fixed, restGiven ? &existing : nullptr);
        },
        result))
  {
    return result;
  }

  std::vector<vtkSmartPointer<vtkPolyData>> outputs(leaves.size());
  for (size_t k = 0; k < used.size(); ++k)
  {
    const size_t b = used[k];
    md::Points points = resolved.points[k];
    frame.ToWorld(points);
    md::Points shifts = resolved.shift[k];
    frame.VectorsToWorld(shifts);
    auto output = vtkSmartPointer<vtkPolyData>::New();
    output->ShallowCopy(leaves[b].data);
    output->SetPoints(mdvtk::ToVtkPoints(points));
    output->GetPointData()->AddArray(mdvtk::ToVtkArray(mdvtk::StaticShiftArrayName, shifts));
    // Field data describes this output only: the upstream measures (a deformation's volume
    // change, iterations, ...) no longer hold once points have moved.
    vtkNew<vtkFieldData> fieldData;
    const md::StaticResolveReport& r = resolved.reports[k];
    const md::TriangleMesh& reference = restGiven ? deformableRest[k] : deformable[k];
    const double referenceVolume = md::SignedVolume(reference.points, reference.triangles);
    const double volume = md::SignedVolume(resolved.points[k], deformable[k].triangles);
    mdvtk::AddFieldValue(fieldData, mdvtk::VolumeChangeArrayName, 100.0 * (volume - referenceVolume) / referenceVolume);
    mdvtk::AddFieldValue(fieldData, "PenetratingPointCount", r.penetratingPoints);
    mdvtk::AddFieldValue(fieldData, "PenetratingGroupCount", r.groups);
    mdvtk::AddFieldValue(fieldData, "MaxPenetrationDepth", frame.LengthToWorld(r.maxDepth));
    mdvtk::AddFieldValue(fieldData, "MaxStaticShift", frame.LengthToWorld(r.maxShift));
    mdvtk::AddFieldValue(fieldData, "NewPenetrationCount", left[k].count);
    mdvtk::AddFieldValue(fieldData, "MaxNewPenetrationDepth", frame.LengthToWorld(left[k].maxDepth));
    output->SetFieldData(fieldData);
    outputs[b] = output;
  }
  for (const auto& [b, message] : failedBlocks)
  {
    outputs[b] = mdvtk::FailedMuscle(leaves[b].data, message);
  }
  mdvtk::AssignLeaves(input, vtkDataObject::GetData(outputVector, 0), outputs, mdvtk::Role::Muscle);
  this->UpdateProgress(1.0);
  return 1;
}

void vtkIntersectionResolve::PrintSelf(ostream& os, vtkIndent indent)
{
  this->Superclass::PrintSelf(os, indent);
  os << indent << "DeformableShare: " << this->DeformableShare << "\n";
}
