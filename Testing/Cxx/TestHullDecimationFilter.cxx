// SPDX-License-Identifier: BSD-3-Clause
#include "FilterTestUtilities.h"

#include "vtkHullDecimation.h"
#include "vtkMusculoskeletalPhantom.h"

#include <vtkDataArray.h>
#include <vtkExecutive.h>
#include <vtkFieldData.h>

#include <gtest/gtest.h>

namespace
{
double Field(vtkPolyData* data, const char* name)
{
  vtkDataArray* array = data->GetFieldData()->GetArray(name);
  return array ? array->GetTuple1(0) : -1;
}

/// A closed box of 8 points as 6 quadrilaterals.
vtkSmartPointer<vtkPolyData> QuadBox()
{
  auto box = vtkSmartPointer<vtkPolyData>::New();
  vtkNew<vtkPoints> points;
  vtkNew<vtkCellArray> quads;
  for (int i = 0; i < 8; ++i)
  {
    points->InsertNextPoint(i & 1 ? 1 : 0, i & 2 ? 1 : 0, i & 4 ? 1 : 0);
  }
  const vtkIdType faces[6][4] = { { 0, 2, 3, 1 }, { 4, 5, 7, 6 }, { 0, 1, 5, 4 }, { 2, 6, 7, 3 }, { 0, 4, 6, 2 },
    { 1, 3, 7, 5 } };
  for (const auto& face : faces)
  {
    quads->InsertNextCell(4, face);
  }
  box->SetPoints(points);
  box->SetPolys(quads);
  return box;
}
}

TEST(HullDecimation, HullsOfThePhantomMusclesKeepBlocksAndReport)
{
  vtkNew<vtkMusculoskeletalPhantom> phantom;
  vtkNew<vtkHullDecimation> hulls;
  hulls->SetInputConnection(phantom->GetOutputPort(0));
  hulls->SetTargetNumberOfPoints(150);
  CapturedMessages messages;
  hulls->Update();
  EXPECT_EQ(messages.Text(), "") << "clean phantom muscles need no repair";
  auto* output = vtkMultiBlockDataSet::SafeDownCast(hulls->GetOutputDataObject(0));
  ASSERT_NE(output, nullptr);
  ASSERT_EQ(output->GetNumberOfBlocks(), 3u);
  for (unsigned int b = 0; b < 3; ++b)
  {
    auto* hull = vtkPolyData::SafeDownCast(output->GetBlock(b));
    ASSERT_NE(hull, nullptr);
    EXPECT_EQ(hull->GetNumberOfPoints(), 150);
    EXPECT_EQ(Field(hull, "PointsOutsideHull"), 0);
    EXPECT_EQ(Field(hull, "HullSelfIntersections"), 0);
    EXPECT_GE(Field(hull, "HullVolumeRatio"), 1.0);
    EXPECT_LT(Field(hull, "HullVolumeRatio"), 1.15);
    EXPECT_GT(Field(hull, "NumberOfCollapses"), 100);
  }
  EXPECT_EQ(BlockName(output, 2), "RectusFemoris");
}

TEST(HullDecimation, TriangulatesPolygonsAndSaysSo)
{
  vtkNew<vtkHullDecimation> hull;
  hull->SetInputData(QuadBox());
  hull->SetTargetNumberOfPoints(6);
  CapturedMessages messages;
  hull->Update();
  EXPECT_TRUE(messages.Contains("triangulated 6 polygons or strips")) << messages.Text();
  auto* output = vtkPolyData::SafeDownCast(hull->GetOutputDataObject(0));
  ASSERT_NE(output, nullptr);
  EXPECT_EQ(Field(output, "PointsOutsideHull"), 0);
}

TEST(HullDecimation, BadInputGivesAClearErrorAndNoCrash)
{
  vtkNew<vtkMusculoskeletalPhantom> phantom;
  phantom->Update();
  vtkSmartPointer<vtkPolyData> muscle =
    vtkPolyData::SafeDownCast(vtkMultiBlockDataSet::SafeDownCast(phantom->GetOutputDataObject(0))->GetBlock(0));
  auto open = vtkSmartPointer<vtkPolyData>::New();
  open->DeepCopy(muscle);
  open->GetPolys()->ReplaceCellAtId(0, { 0, 0, 0 }); // a degenerate triangle: its hole stays
  auto flat = QuadBox();
  for (vtkIdType i = 0; i < flat->GetNumberOfPoints(); ++i)
  {
    double p[3];
    flat->GetPoint(i, p);
    flat->GetPoints()->SetPoint(i, p[0], p[1], 0.0);
  }
  auto lines = MakePolylines({ { 0, 0, 0, 1, 0, 0 } });
  struct Case
  {
    const char* what;
    vtkSmartPointer<vtkDataObject> input;
    int target;
    std::string expected;
  };
  const std::vector<Case> cases = {
    { "open muscle", MakeBlocks({ { "Iliopsoas", open } }), 250,
      "Input block 'Iliopsoas': the surface is open: 3 edges belong to a single triangle" },
    { "empty input", vtkSmartPointer<vtkPolyData>::New(), 250, "Input has no surface" },
    { "no polygons", lines, 250, "Input has no surface" },
    { "target larger than the input", muscle, 5000, "larger than the surface's 1130 points" },
    { "flat mesh", flat, 6, "flat or degenerate" },
  };
  for (const Case& c : cases)
  {
    CapturedMessages messages;
    vtkNew<vtkHullDecimation> hull;
    hull->SetInputData(c.input);
    hull->SetTargetNumberOfPoints(c.target);
    EXPECT_EQ(hull->GetExecutive()->Update(), 0) << c.what;
    EXPECT_TRUE(messages.Contains(c.expected)) << c.what << ": got " << messages.Text();
  }
}
