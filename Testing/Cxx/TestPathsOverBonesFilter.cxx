// SPDX-License-Identifier: BSD-3-Clause
// PathsOverBones as a pipeline drives it, data-free: the phantom's action lines and bones made
// time-varying by BoneInterpolation (the rest pose to 30 degrees of flexion), where the rectus
// femoris's line comes to cross the femur.
#include "FilterTestUtilities.h"
#include "Geometry/TriangleTree.h"
#include "MDConvert.h"

#include "vtkBoneInterpolation.h"
#include "vtkMusculoskeletalPhantom.h"
#include "vtkPathsOverBones.h"

#include <vtkDataArray.h>
#include <vtkFieldData.h>
#include <vtkInformation.h>
#include <vtkPointData.h>
#include <vtkStreamingDemandDrivenPipeline.h>
#include <vtkStringArray.h>

#include <gtest/gtest.h>

#include <map>

namespace
{
using SDDP = vtkStreamingDemandDrivenPipeline;

struct PhantomPaths
{
  vtkNew<vtkMusculoskeletalPhantom> phantom;
  vtkNew<vtkBoneInterpolation> bones, lines;
  vtkNew<vtkPathsOverBones> over;
  static constexpr int Frames = 15;
  PhantomPaths()
  {
    this->phantom->SetFlexion(30);
    this->bones->SetInputConnection(0, this->phantom->GetOutputPort(1));
    this->bones->SetInputConnection(1, this->phantom->GetOutputPort(2));
    this->bones->SetNumberOfSteps(Frames);
    this->lines->SetInputConnection(0, this->phantom->GetOutputPort(3));
    this->lines->SetInputConnection(1, this->phantom->GetOutputPort(4));
    this->lines->SetNumberOfSteps(Frames);
    this->over->SetInputConnection(0, this->lines->GetOutputPort());
    this->over->SetBonesConnection(this->bones->GetOutputPort());
  }
  vtkMultiBlockDataSet* At(vtkAlgorithm* filter, double time)
  {
    filter->UpdateInformation();
    filter->UpdateTimeStep(time);
    return vtkMultiBlockDataSet::SafeDownCast(filter->GetOutputDataObject(0));
  }
};

/// The points of every block of `tree`, by block name.
std::map<std::string, md::Points> PointsOf(vtkMultiBlockDataSet* tree)
{
  std::map<std::string, md::Points> points;
  for (unsigned int b = 0; b < tree->GetNumberOfBlocks(); ++b)
  {
    points[BlockName(tree, b)] = mdvtk::ToPoints(vtkPolyData::SafeDownCast(tree->GetBlock(b))->GetPoints());
  }
  return points;
}

double Field(vtkPolyData* block, const char* name)
{
  vtkDataArray* array = block->GetFieldData()->GetArray(name);
  return array ? array->GetComponent(0, 0) : -1;
}
}

TEST(PathsOverBones, NoPathEntersABoneFrameAfterFrameAndEachFrameIsTheSameInAnyOrder)
{
  PhantomPaths played;
  played.over->UpdateInformation();
  vtkInformation* info = played.over->GetOutputInformation(0);
  ASSERT_TRUE(info->Has(SDDP::TIME_STEPS()));
  ASSERT_EQ(info->Length(SDDP::TIME_STEPS()), PhantomPaths::Frames + 1);
  std::map<std::string, md::Points> last;
  double largestStep = 0, largestBoneStep = 0;
  md::Points lastFemur;
  bool wrapped = false;
  for (int k = 0; k <= PhantomPaths::Frames; ++k)
  {
    vtkMultiBlockDataSet* paths = played.At(played.over, k);
    auto* bones = vtkMultiBlockDataSet::SafeDownCast(played.bones->GetOutputDataObject(0));
    ASSERT_NE(paths, nullptr);
    ASSERT_EQ(paths->GetNumberOfBlocks(), 3u);
    std::vector<md::TriangleTree> trees;
    for (unsigned int b = 0; b < bones->GetNumberOfBlocks(); ++b)
    {
      md::TriangleMesh mesh;
      mdvtk::ReadTriangles(vtkPolyData::SafeDownCast(bones->GetBlock(b)), mesh);
      trees.emplace_back(mesh);
      if (BlockName(bones, b) == "Femur")
      {
        largestBoneStep =
          lastFemur.rows() ? std::max(largestBoneStep, (mesh.points - lastFemur).rowwise().norm().maxCoeff()) : 0.0;
        lastFemur = mesh.points;
      }
    }
    const std::map<std::string, md::Points> now = PointsOf(paths);
    for (unsigned int b = 0; b < paths->GetNumberOfBlocks(); ++b)
    {
      auto* block = vtkPolyData::SafeDownCast(paths->GetBlock(b));
      const std::vector<md::Points> polylines = mdvtk::ToPolylines(block);
      for (const md::Points& line : polylines)
      {
        ASSERT_EQ((line.rows() - 1) % 16, 0) << "15 points between each two of the path's own";
        // The points between two of a path's own that are outside a bone are outside it. (The
        // phantom's lines go linearly between the poses, so a via point can be in the femur.)
        for (Eigen::Index i = 0; i < line.rows(); ++i)
        {
          const Eigen::Index s = i / 16 * 16;
          for (const md::TriangleTree& tree : trees)
          {
            if (i % 16 != 0 && !tree.Inside(line.row(s).transpose()) && !tree.Inside(line.row(s + 16).transpose()))
            {
              EXPECT_FALSE(tree.Inside(line.row(i).transpose()))
                << BlockName(paths, b) << " frame " << k << " point " << i;
            }
          }
        }
      }
      EXPECT_GE(Field(block, "PathLength"), Field(block, "StraightPathLength") - 1e-9);
      wrapped = wrapped || Field(block, "PathLength") > Field(block, "StraightPathLength") + 1e-3;
      if (last.count(BlockName(paths, b)))
      {
        largestStep = std::max(
          largestStep, (now.at(BlockName(paths, b)) - last.at(BlockName(paths, b))).rowwise().norm().maxCoeff());
      }
    }
    last = now;
  }
  EXPECT_TRUE(wrapped) << "the rectus femoris's line crosses the femur as the hip flexes";
  EXPECT_LE(largestStep, 1.5 * largestBoneStep) << "no point jumps further than the bones move";
  // A filter asked for the last frame first computes the frames before it, and gives the same.
  PhantomPaths jumped;
  const std::map<std::string, md::Points> direct = PointsOf(jumped.At(jumped.over, PhantomPaths::Frames));
  EXPECT_EQ(jumped.over->GetFramesComputed(), PhantomPaths::Frames + 1);
  for (const auto& [name, points] : direct)
  {
    EXPECT_EQ(points, last.at(name)) << name;
  }
  jumped.At(jumped.over, 3);
  EXPECT_EQ(jumped.over->GetFramesComputed(), PhantomPaths::Frames + 1) << "kept frames are not computed again";
}

TEST(PathsOverBones, PointsOnABoneAreNamedAfterItAndBadPathsAreRefused)
{
  // One pose (no time): a path from above a box to below it, through it.
  auto box = MakeBlocks({ { "Block", vtkSmartPointer<vtkPolyData>() } });
  {
    md::TriangleMesh mesh;
    mesh.points.resize(8, 3);
    for (int i = 0; i < 8; ++i)
    {
      mesh.points.row(i) << (i & 1 ? 1 : -1), (i & 2 ? 1 : -1), (i & 4 ? 1 : -1);
    }
    mesh.triangles.resize(12, 3);
    mesh.triangles << 0, 2, 1, 1, 2, 3, 4, 5, 6, 5, 7, 6, 0, 1, 4, 1, 5, 4, 2, 6, 3, 3, 6, 7, 0, 4, 2, 2, 4, 6, 1, 3, 5,
      3, 7, 5;
    box->SetBlock(0, mdvtk::ToPolyData(mesh));
  }
  auto path = MakePolylines({ { -3, 0.2, 0.1, 3, 0.3, 0.1 } });
  vtkNew<vtkStringArray> names;
  names->SetName("PathPointName");
  names->InsertNextValue("origin");
  names->InsertNextValue("insertion");
  path->GetPointData()->AddArray(names);
  vtkNew<vtkPathsOverBones> over;
  over->SetInputData(0, MakeBlocks({ { "m", path } }));
  over->SetInputData(1, box);
  over->SetPointsPerSegment(9);
  over->Update();
  auto* out = vtkPolyData::SafeDownCast(vtkMultiBlockDataSet::SafeDownCast(over->GetOutputDataObject(0))->GetBlock(0));
  ASSERT_NE(out, nullptr);
  ASSERT_EQ(out->GetNumberOfPoints(), 11);
  auto* named = vtkStringArray::SafeDownCast(out->GetPointData()->GetAbstractArray("PathPointName"));
  ASSERT_NE(named, nullptr);
  EXPECT_EQ(named->GetValue(0), "origin");
  EXPECT_EQ(named->GetValue(10), "insertion");
  EXPECT_EQ(named->GetValue(5), "Block");                                      // over the box's top face
  EXPECT_GT(Field(out, "PathLength"), Field(out, "StraightPathLength") + 0.2); // round the box's side

  CapturedMessages messages;
  over->SetInputData(0, MakeBlocks({ { "m", MakePolylines({ { 0, 0, 0 } }) } }));
  over->Update();
  EXPECT_TRUE(messages.Contains("Input block 'm' has a polyline of 1 point")) << messages.Text();
  over->SetInputData(0, MakeBlocks({ { "m", path } }));
  over->SetInputData(1, MakeBlocks({ { "Lines", MakePolylines({ { 0, 0, 0, 1, 0, 0 } }) } }));
  over->Update();
  EXPECT_TRUE(messages.Contains("Bones block 'Lines' has no triangles")) << messages.Text();
}
