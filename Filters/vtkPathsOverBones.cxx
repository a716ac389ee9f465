// SPDX-License-Identifier: BSD-3-Clause
#include "vtkPathsOverBones.h"

#include "MDBlocks.h"
#include "MDConvert.h"
#include "MDReport.h"
#include "MDTime.h"
#include "Motion/PathOverBones.h"

#include <vtkCellArray.h>
#include <vtkCellArrayIterator.h>
#include <vtkCellData.h>
#include <vtkDataArray.h>
#include <vtkDemandDrivenPipeline.h>
#include <vtkFieldData.h>
#include <vtkInformation.h>
#include <vtkInformationVector.h>
#include <vtkNew.h>
#include <vtkObjectFactory.h>
#include <vtkPointData.h>
#include <vtkPolyData.h>
#include <vtkStreamingDemandDrivenPipeline.h>
#include <vtkStringArray.h>
#include <vtkUnsignedCharArray.h>

#include <algorithm>
#include <map>
#include <string>
#include <vector>

vtkStandardNewMacro(vtkPathsOverBones);

namespace
{
using SDDP = vtkStreamingDemandDrivenPipeline;

const char* const PortNames[2] = { "Input", "Bones" };

/// One path leaf: its polylines as the ids of their points.
struct PathLeaf
{
  std::vector<std::vector<vtkIdType>> polylines;
};

/// A frame's answer: per leaf, per polyline, the path at the frame's pose and at each stepped pose.
struct FrameAnswer
{
  std::vector<std::vector<md::PathOverBonesResult>> paths;
  std::map<std::string, std::vector<std::vector<md::Points>>> stepped;
};

/// The names of the stepped poses `data` carries (point arrays PointsAt(<pose>)).
std::vector<std::string> SteppedPoses(vtkPolyData* data)
{
  std::vector<std::string> poses;
  vtkPointData* pd = data ? data->GetPointData() : nullptr;
  for (int a = 0; pd && a < pd->GetNumberOfArrays(); ++a)
  {
    const std::string pose = mdvtk::PoseOfPointsAt(pd->GetArrayName(a) ? pd->GetArrayName(a) : "");
    if (!pose.empty())
    {
      poses.push_back(pose);
    }
  }
  return poses;
}
}

struct vtkPathsOverBones::Internals
{
  // What the kept frames were computed from: a change of any drops them.
  std::vector<double> times;
  vtkMTimeType pipeline = 0;
  int pointsPerSegment = 0;
  std::map<int, FrameAnswer> frames;

  int target = 0;  ///< the frame asked for
  int gather = -1; ///< the frame being computed; -1: none
  int asked = -1;  ///< the frame the inputs were last asked for
  bool looping = false;

  // The bones as last read, and their trees moved to the pose being computed.
  std::vector<md::TriangleMesh> boneMeshes;
  std::vector<std::unique_ptr<md::TriangleTree>> trees;
  std::vector<std::unique_ptr<md::TriangleTree>> steppedTrees; ///< moved to a stepped pose in turn

  /// The first frame from which the frames up to `frame` are to be computed (each from the one
  /// before it); -1 when `frame` is kept.
  int FirstMissing(int frame) const
  {
    if (this->frames.count(frame))
    {
      return -1;
    }
    int first = frame;
    while (first > 0 && !this->frames.count(first - 1))
    {
      --first;
    }
    return first;
  }
};

vtkPathsOverBones::vtkPathsOverBones()
  : PointsPerSegment(md::PathOverBonesParameters{}.pointsPerSegment)
  , In(std::make_unique<Internals>())
{
  this->SetNumberOfInputPorts(2);
}

vtkPathsOverBones::~vtkPathsOverBones() = default;

int vtkPathsOverBones::FillInputPortInformation(int, vtkInformation* info)
{
  mdvtk::AcceptPolyDataOrMultiBlock(info);
  return 1;
}

int vtkPathsOverBones::RequestInformation(
  vtkInformation*, vtkInformationVector** inputVector, vtkInformationVector* outputVector)
{
  mdvtk::CopyTimeSteps(inputVector[0]->GetInformationObject(0), outputVector->GetInformationObject(0));
  return 1;
}

int vtkPathsOverBones::RequestUpdateExtent(
  vtkInformation*, vtkInformationVector** inputVector, vtkInformationVector* outputVector)
{
  Internals& in = *this->In;
  const std::vector<double> times = mdvtk::TimesOf(inputVector[0]->GetInformationObject(0));
  if (times.empty())
  {
    mdvtk::ClearOutputs(outputVector);
    return 1; // one pose: the inputs as they are
  }
  if (!in.looping)
  {
    mdvtk::ClearOutputs(outputVector);
    vtkInformation* outInfo = outputVector->GetInformationObject(0);
    in.target =
      outInfo->Has(SDDP::UPDATE_TIME_STEP()) ? mdvtk::NearestTime(times, outInfo->Get(SDDP::UPDATE_TIME_STEP())) : 0;
    in.gather = in.times == times ? in.FirstMissing(in.target) : 0;
  }
  // Both inputs at the frame to compute (or, with nothing to compute, at the frame asked for).
  in.asked = in.gather >= 0 ? in.gather : in.target;
  const double time = times[static_cast<size_t>(in.asked)];
  for (int port = 0; port < 2; ++port)
  {
    for (int i = 0; i < inputVector[port]->GetNumberOfInformationObjects(); ++i)
    {
      inputVector[port]->GetInformationObject(i)->Set(SDDP::UPDATE_TIME_STEP(), time);
    }
  }
  return 1;
}

int vtkPathsOverBones::RequestData(
  vtkInformation* request, vtkInformationVector** inputVector, vtkInformationVector* outputVector)
{
  Internals& in = *this->In;
  const auto stop = [&](int result) {
    in.gather = -1;
    in.looping = false;
    request->Remove(SDDP::CONTINUE_EXECUTING());
    return result;
  };
  vtkDataObject* input = vtkDataObject::GetData(inputVector[0], 0);
  vtkDataObject* bonesInput = vtkDataObject::GetData(inputVector[1], 0);
  std::vector<mdvtk::Leaf> paths, bones;
  std::string error;
  if (!mdvtk::CollectLeaves(input, PortNames[0], paths, error) ||
    !mdvtk::CollectLeaves(bonesInput, PortNames[1], bones, error))
  {
    vtkErrorMacro(<< error);
    return stop(0);
  }
  // The bones: each a closed surface; its trees moved to the pose when only its points changed.
  const bool sameBones = bones.size() == in.boneMeshes.size();
  std::vector<std::string> boneNames, boneBodies; // what the points on each bone are named
  in.boneMeshes.resize(bones.size());
  if (!sameBones)
  {
    in.trees.clear();
    in.trees.resize(bones.size());
  }
  for (size_t b = 0; b < bones.size(); ++b)
  {
    md::TriangleMesh mesh;
    if (!bones[b].data || mdvtk::ReadTriangles(bones[b].data, mesh) < 0 || mesh.triangles.rows() == 0)
    {
      vtkErrorMacro(<< bones[b].label << " has no triangles: the bones must be closed surfaces");
      return stop(0);
    }
    boneNames.push_back(mdvtk::NameOf(bones[b]));
    auto* body = vtkStringArray::SafeDownCast(bones[b].data->GetFieldData()->GetAbstractArray(mdvtk::array::Body));
    boneBodies.push_back(body && body->GetNumberOfValues() > 0 ? body->GetValue(0) : std::string());
    if (!in.trees[b] || in.boneMeshes[b].triangles.rows() != mesh.triangles.rows() ||
      in.boneMeshes[b].points.rows() != mesh.points.rows() || in.boneMeshes[b].triangles != mesh.triangles)
    {
      in.trees[b] = std::make_unique<md::TriangleTree>(mesh);
    }
    else if (in.boneMeshes[b].points != mesh.points)
    {
      in.trees[b]->Refit(mesh.points);
    }
    in.boneMeshes[b] = std::move(mesh);
  }
  std::vector<PathLeaf> leaves(paths.size());
  for (size_t p = 0; p < paths.size(); ++p)
  {
    leaves[p].polylines = mdvtk::PolylineIds(paths[p].data);
    for (const std::vector<vtkIdType>& ids : leaves[p].polylines)
    {
      if (ids.size() < 2)
      {
        vtkErrorMacro(<< paths[p].label << " has a polyline of " << ids.size()
                      << " point: a path needs two points or more");
        return stop(0);
      }
    }
  }
  // What the kept frames were computed from.
  const std::vector<double> times = mdvtk::TimesOf(inputVector[0]->GetInformationObject(0));
  vtkMTimeType pipeline = this->GetMTime();
  for (int port = 0; port < 2; ++port)
  {
    if (auto* executive = vtkDemandDrivenPipeline::SafeDownCast(this->GetInputExecutive(port, 0)))
    {
      pipeline = std::max(pipeline, executive->GetPipelineMTime());
    }
  }
  if (times != in.times || pipeline != in.pipeline || this->PointsPerSegment != in.pointsPerSegment)
  {
    in.frames.clear();
    in.times = times;
    in.pipeline = pipeline;
    in.pointsPerSegment = this->PointsPerSegment;
    in.gather = -1;
  }
  md::PathOverBonesParameters parameters;
  parameters.pointsPerSegment = this->PointsPerSegment;
  // One frame: the paths at the inputs' pose and at their stepped poses, each started from
  // `last` (the frame before; null: from the straight paths).
  const auto compute = [&](const FrameAnswer* last, FrameAnswer& answer) {
    std::vector<const md::TriangleTree*> trees;
    for (const auto& tree : in.trees)
    {
      trees.push_back(tree.get());
    }
    answer.paths.assign(paths.size(), {});
    for (size_t p = 0; p < paths.size(); ++p)
    {
      if (leaves[p].polylines.empty())
      {
        continue; // no path in this block
      }
      const std::vector<md::Points> polylines = mdvtk::ToPolylines(paths[p].data);
      for (size_t l = 0; l < polylines.size(); ++l)
      {
        const bool before = last && last->paths.size() == paths.size() && last->paths[p].size() > l;
        const md::Points* start = before ? &last->paths[p][l].points : nullptr;
        answer.paths[p].push_back(md::PathOverBones(polylines[l], trees, parameters, start));
      }
    }
    // The stepped poses the paths and the bones carry, each from the frame's answer.
    std::vector<std::string> poses = paths.empty() ? std::vector<std::string>{} : SteppedPoses(paths[0].data);
    // (SteppedPoses of a missing block is none.)
    for (const std::string& pose : poses)
    {
      const std::string name = mdvtk::PointsAt(pose);
      bool everywhere = true;
      for (const std::vector<mdvtk::Leaf>* group : { &bones, &paths })
      {
        for (const mdvtk::Leaf& leaf : *group)
        {
          vtkDataArray* array = leaf.data ? leaf.data->GetPointData()->GetArray(name.c_str()) : nullptr;
          everywhere = everywhere && leaf.data && array && array->GetNumberOfComponents() == 3 &&
            array->GetNumberOfTuples() == leaf.data->GetNumberOfPoints();
        }
      }
      if (!everywhere)
      {
        continue; // said by the filters that read stepped poses, which find it missing
      }
      std::vector<const md::TriangleTree*> steppedTrees;
      in.steppedTrees.resize(bones.size());
      for (size_t b = 0; b < bones.size(); ++b)
      {
        const md::Points at = mdvtk::ToPoints(bones[b].data->GetPointData()->GetArray(name.c_str()));
        if (at == in.boneMeshes[b].points)
        {
          steppedTrees.push_back(in.trees[b].get());
          continue;
        }
        if (!in.steppedTrees[b] || in.steppedTrees[b]->Mesh().triangles.rows() != in.boneMeshes[b].triangles.rows() ||
          in.steppedTrees[b]->Mesh().triangles != in.boneMeshes[b].triangles)
        {
          in.steppedTrees[b] = std::make_unique<md::TriangleTree>(*in.trees[b]);
        }
        in.steppedTrees[b]->Refit(at);
        steppedTrees.push_back(in.steppedTrees[b].get());
      }
      auto& stepped = answer.stepped[pose];
      stepped.assign(paths.size(), {});
      for (size_t p = 0; p < paths.size(); ++p)
      {
        if (leaves[p].polylines.empty())
        {
          continue;
        }
        const md::Points values = mdvtk::ToPoints(paths[p].data->GetPointData()->GetArray(name.c_str()));
        const std::vector<md::Points> polylines = mdvtk::ToPolylines(paths[p].data, &values);
        for (size_t l = 0; l < polylines.size(); ++l)
        {
          stepped[p].push_back(
            md::PathOverBones(polylines[l], steppedTrees, parameters, &answer.paths[p][l].points).points);
        }
      }
    }
  };
  FrameAnswer single;
  const FrameAnswer* answer = &single;
  int result = 1;
  if (times.empty())
  {
    if (!mdvtk::CallCore(
          this, "", [&] { compute(nullptr, single); }, result))
    {
      return stop(result);
    }
    ++this->FramesComputed;
  }
  else
  {
    if (in.gather < 0)
    {
      in.gather = in.FirstMissing(in.target);
    }
    if (in.gather >= 0 && in.asked != in.gather)
    {
      in.looping = true; // this pass's inputs are of another frame: ask for the one to compute
      request->Set(SDDP::CONTINUE_EXECUTING(), 1);
      return 1;
    }
    if (in.gather >= 0)
    {
      // This pass's inputs hold frame `gather`: compute it from the frame before.
      const auto before = in.frames.find(in.gather - 1);
      FrameAnswer computed;
      if (!mdvtk::CallCore(
            this, "", [&] { compute(before == in.frames.end() ? nullptr : &before->second, computed); }, result))
      {
        return stop(result);
      }
      in.frames[in.gather] = std::move(computed);
      ++this->FramesComputed;
      if (in.gather < in.target)
      {
        ++in.gather;
        in.looping = true;
        request->Set(SDDP::CONTINUE_EXECUTING(), 1);
        return 1;
      }
      stop(1);
    }
    answer = &in.frames.at(in.target);
  }
  // The output: each path leaf with its points over the bones.
  std::vector<vtkSmartPointer<vtkPolyData>> results;
  for (size_t p = 0; p < paths.size(); ++p)
  {
    vtkPolyData* source = paths[p].data;
    auto out = vtkSmartPointer<vtkPolyData>::New();
    if (leaves[p].polylines.empty())
    {
      results.push_back(out); // a block without a path stays empty
      continue;
    }
    std::vector<vtkIdType> from; // per output point: its input point, or -1 between them
    std::vector<double> weight;  // between two input points: the share of the second
    std::vector<vtkIdType> to;   // the second
    std::vector<int> boneOf;     // the bone it lies on, -1 for none
    md::Points points(0, 3);
    vtkNew<vtkCellArray> cells;
    double length = 0, straight = 0;
    for (size_t l = 0; l < leaves[p].polylines.size(); ++l)
    {
      const std::vector<vtkIdType>& ids = leaves[p].polylines[l];
      const md::PathOverBonesResult& r = answer->paths[p][l];
      const auto first = points.rows();
      points.conservativeResize(first + r.points.rows(), 3);
      points.bottomRows(r.points.rows()) = r.points;
      cells->InsertNextCell(static_cast<vtkIdType>(r.points.rows()));
      const int per = this->PointsPerSegment + 1;
      for (Eigen::Index i = 0; i < r.points.rows(); ++i)
      {
        cells->InsertCellPoint(first + i);
        const auto s = static_cast<size_t>(i / per), k = static_cast<size_t>(i % per);
        from.push_back(k == 0 ? ids[s] : -1);
        to.push_back(k == 0 ? ids[s] : ids[s + 1]);
        weight.push_back(static_cast<double>(k) / per);
        boneOf.push_back(r.boneOfPoint[static_cast<size_t>(i)]);
      }
      length += r.length;
      straight += r.straightLength;
    }
    out->SetPoints(mdvtk::ToVtkPoints(points));
    out->SetLines(cells);
    if (source->GetNumberOfCells() == static_cast<vtkIdType>(leaves[p].polylines.size()))
    {
      out->GetCellData()->ShallowCopy(source->GetCellData());
    }
    out->GetFieldData()->ShallowCopy(source->GetFieldData());
    vtkPointData* pd = source->GetPointData();
    for (int a = 0; a < pd->GetNumberOfArrays(); ++a)
    {
      vtkAbstractArray* array = pd->GetAbstractArray(a);
      const std::string name = array->GetName() ? array->GetName() : "";
      if (name.rfind("PointsAt(", 0) == 0 || name.empty() || name == mdvtk::array::PathOwnPoint)
      {
        continue; // written below from the answers
      }
      if (auto* strings = vtkStringArray::SafeDownCast(array))
      {
        // A point between takes the bone it lies on: its name, or its body for a body array.
        const bool body = name.find("Body") != std::string::npos;
        vtkNew<vtkStringArray> copy;
        copy->SetName(name.c_str());
        for (size_t i = 0; i < from.size(); ++i)
        {
          const int b = boneOf[i];
          copy->InsertNextValue(from[i] >= 0 ? strings->GetValue(from[i])
              : b < 0                        ? std::string()
              : body                         ? boneBodies[static_cast<size_t>(b)]
                                             : boneNames[static_cast<size_t>(b)]);
        }
        out->GetPointData()->AddArray(copy);
      }
      else if (auto* numbers = vtkDataArray::SafeDownCast(array))
      {
        // Numbers go linearly between the path's own points.
        vtkSmartPointer<vtkDataArray> copy = vtk::TakeSmartPointer(numbers->NewInstance());
        copy->SetName(name.c_str());
        copy->SetNumberOfComponents(numbers->GetNumberOfComponents());
        copy->SetNumberOfTuples(static_cast<vtkIdType>(from.size()));
        for (size_t i = 0; i < from.size(); ++i)
        {
          const vtkIdType at = from[i] >= 0 ? from[i] : to[i] - 1;
          copy->InterpolateTuple(
            static_cast<vtkIdType>(i), at, numbers, to[i], numbers, from[i] >= 0 ? 0.0 : weight[i]);
        }
        out->GetPointData()->AddArray(copy);
      }
    }
    for (const auto& [pose, stepped] : answer->stepped)
    {
      const std::vector<md::Points>& lines = stepped[p];
      md::Points all(0, 3);
      for (const md::Points& line : lines)
      {
        all.conservativeResize(all.rows() + line.rows(), 3);
        all.bottomRows(line.rows()) = line;
      }
      vtkSmartPointer<vtkDataArray> array = mdvtk::ToVtkPoints(all)->GetData();
      array->SetName(mdvtk::PointsAt(pose).c_str());
      out->GetPointData()->AddArray(array);
    }
    vtkNew<vtkUnsignedCharArray> own;
    own->SetName(mdvtk::array::PathOwnPoint);
    for (const vtkIdType input : from)
    {
      own->InsertNextValue(input >= 0 ? 1 : 0);
    }
    out->GetPointData()->AddArray(own);
    mdvtk::AddFieldValue(out->GetFieldData(), "PathLength", length);
    mdvtk::AddFieldValue(out->GetFieldData(), "StraightPathLength", straight);
    results.push_back(out);
  }
  mdvtk::AssignLeaves(input, vtkDataObject::GetData(outputVector, 0), results, mdvtk::Role::AsGiven);
  if (!times.empty())
  {
    mdvtk::SetDataTime(outputVector, times[static_cast<size_t>(in.target)]);
  }
  return 1;
}

void vtkPathsOverBones::PrintSelf(ostream& os, vtkIndent indent)
{
  this->Superclass::PrintSelf(os, indent);
  os << indent << "PointsPerSegment: " << this->PointsPerSegment << "\n";
}
