// SPDX-License-Identifier: BSD-3-Clause
// The filters that attach scans to an OpenSim model, on the phantom (no data needed):
// ActionLineGrouping gives each path to the muscle that holds it, MoveWithBodies moves each
// surface with its body.
#include "FilterTestUtilities.h"
#include "vtkActionLineGrouping.h"
#include "vtkMoveWithBodies.h"
#include "vtkMusculoskeletalPhantom.h"

#include <vtkDoubleArray.h>
#include <vtkFieldData.h>
#include <vtkStringArray.h>
#include <vtkTable.h>

#include <gtest/gtest.h>

#include <cmath>

namespace
{
vtkPolyData* BlockOf(vtkDataObject* data, unsigned int index)
{
  return vtkPolyData::SafeDownCast(vtkMultiBlockDataSet::SafeDownCast(data)->GetBlock(index));
}

/// Each rest-pose action line of the phantom's muscles as a path of its own, named after it.
vtkSmartPointer<vtkMultiBlockDataSet> PhantomPaths(vtkMusculoskeletalPhantom* phantom)
{
  std::vector<std::pair<std::string, vtkSmartPointer<vtkPolyData>>> paths;
  auto* lines = vtkMultiBlockDataSet::SafeDownCast(phantom->GetOutputDataObject(3));
  for (unsigned int m = 0; m < lines->GetNumberOfBlocks(); ++m)
  {
    vtkPolyData* muscle = BlockOf(lines, m);
    vtkCellArray* cells = muscle->GetLines();
    cells->InitTraversal();
    vtkIdType count = 0;
    const vtkIdType* ids = nullptr;
    for (int l = 0; cells->GetNextCell(count, ids); ++l)
    {
      std::vector<double> flat;
      for (vtkIdType k = 0; k < count; ++k)
      {
        const double* p = muscle->GetPoint(ids[k]);
        flat.insert(flat.end(), p, p + 3);
      }
      paths.emplace_back(BlockName(lines, m) + "_" + std::to_string(l), MakePolylines({ flat }));
    }
  }
  return MakeBlocks(paths);
}

std::vector<std::string> Strings(vtkFieldData* fieldData, const char* name)
{
  std::vector<std::string> values;
  auto* array = vtkStringArray::SafeDownCast(fieldData->GetAbstractArray(name));
  for (vtkIdType k = 0; array && k < array->GetNumberOfValues(); ++k)
  {
    values.push_back(array->GetValue(k));
  }
  return values;
}
}

TEST(ActionLineGrouping, EachPathGoesToTheMuscleThatHoldsItUnlessTheUserSaysOtherwise)
{
  vtkNew<vtkMusculoskeletalPhantom> phantom;
  phantom->Update();
  vtkSmartPointer<vtkMultiBlockDataSet> paths = PhantomPaths(phantom);
  ASSERT_GE(paths->GetNumberOfBlocks(), 3u); // every line of the three phantom muscles
  CapturedMessages messages;
  vtkNew<vtkActionLineGrouping> grouping;
  grouping->SetInputConnection(0, phantom->GetOutputPort(0));
  grouping->SetInputData(1, paths);
  grouping->Update();
  auto* grouped = vtkMultiBlockDataSet::SafeDownCast(grouping->GetOutputDataObject(0));
  ASSERT_EQ(grouped->GetNumberOfBlocks(), 3u) << messages.Text();
  for (unsigned int m = 0; m < 3; ++m)
  {
    // The muscle's block holds its own lines, most of each one's length inside it.
    const std::string muscle = BlockName(grouped, m);
    std::vector<std::string> own;
    for (unsigned int p = 0; p < paths->GetNumberOfBlocks(); ++p)
    {
      if (BlockName(paths, p).rfind(muscle + "_", 0) == 0)
      {
        own.push_back(BlockName(paths, p));
      }
    }
    ASSERT_FALSE(own.empty()) << muscle;
    EXPECT_EQ(Strings(BlockOf(grouped, m)->GetFieldData(), "ActionLinePaths"), own);
    auto* share = vtkDoubleArray::SafeDownCast(BlockOf(grouped, m)->GetFieldData()->GetArray("PathInsideFraction"));
    ASSERT_NE(share, nullptr);
    for (vtkIdType l = 0; l < share->GetNumberOfValues(); ++l)
    {
      EXPECT_GT(share->GetValue(l), 0.5) << muscle << " line " << l;
    }
    EXPECT_NE(grouping->GetDecision().find(own[0] + " -> " + muscle), std::string::npos) << grouping->GetDecision();
  }
  // Given by hand: the gluteus maximus's lines to the rectus femoris as well; the gluteus keeps
  // none of its own then, which is an error naming it.
  std::string gluteusLines;
  for (unsigned int p = 0; p < paths->GetNumberOfBlocks(); ++p)
  {
    if (BlockName(paths, p).rfind("GluteusMaximus_", 0) == 0)
    {
      gluteusLines += "," + BlockName(paths, p);
    }
  }
  grouping->SetPathsOfMuscle(("RectusFemoris=RectusFemoris_0" + gluteusLines).c_str());
  grouping->Update();
  EXPECT_TRUE(messages.Contains("GluteusMaximus': no path runs inside this muscle")) << messages.Text();
  grouping->SetPathsOfMuscle("RectusFemoris=Nowhere_0");
  grouping->Update();
  EXPECT_TRUE(messages.Contains("'Nowhere_0' (given for muscle 'RectusFemoris') is not one of the paths"))
    << messages.Text();
}

TEST(MoveWithBodies, EachSurfaceMovesWithItsBodyNamedOrGiven)
{
  vtkNew<vtkMusculoskeletalPhantom> phantom;
  phantom->Update();
  auto* bones = vtkMultiBlockDataSet::SafeDownCast(phantom->GetOutputDataObject(1));
  // A transforms table as OpenSimModelReader writes it: the femur turned 90 degrees about z and
  // moved, the pelvis still.
  vtkNew<vtkTable> table;
  vtkNew<vtkStringArray> body;
  body->SetName("Body");
  body->InsertNextValue("Pelvis");
  body->InsertNextValue("Femur");
  table->AddColumn(body);
  const double femur[12] = { 0, -1, 0, 1, 0, 0, 0, 0, 1, 1, 2, 3 };
  const double still[12] = { 1, 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0 };
  const char* names[12] = { "R00", "R01", "R02", "R10", "R11", "R12", "R20", "R21", "R22", "Tx", "Ty", "Tz" };
  for (int c = 0; c < 12; ++c)
  {
    vtkNew<vtkDoubleArray> column;
    column->SetName(names[c]);
    column->InsertNextValue(still[c]);
    column->InsertNextValue(femur[c]);
    table->AddColumn(column);
  }
  // The femur by its name; a second pelvis surface named otherwise, given to the femur by hand.
  auto surfaces = MakeBlocks(
    { { "Femur", BlockOf(bones, 1) }, { "Pelvis", BlockOf(bones, 0) }, { "iliac_scan.vtk", BlockOf(bones, 0) } });
  CapturedMessages messages;
  vtkNew<vtkMoveWithBodies> move;
  move->SetInputData(0, surfaces);
  move->SetInputData(1, table);
  move->Update();
  EXPECT_TRUE(messages.Contains("iliac_scan.vtk': no body of the model is named after")) << messages.Text();
  move->SetBodyOfSurface("iliac_scan=Femur");
  move->Update();
  auto* moved = vtkMultiBlockDataSet::SafeDownCast(move->GetOutputDataObject(0));
  ASSERT_EQ(moved->GetNumberOfBlocks(), 3u) << messages.Text();
  for (unsigned int b = 0; b < 3; ++b)
  {
    const bool onFemur = b != 1;
    EXPECT_EQ(
      Strings(BlockOf(moved, b)->GetFieldData(), "Body"), std::vector<std::string>{ onFemur ? "Femur" : "Pelvis" });
    vtkPolyData* before = BlockOf(surfaces, b);
    vtkPolyData* after = BlockOf(moved, b);
    ASSERT_EQ(after->GetNumberOfPoints(), before->GetNumberOfPoints());
    for (vtkIdType i = 0; i < before->GetNumberOfPoints(); i += 97)
    {
      const double* x = before->GetPoint(i);
      const double expected[3] = { onFemur ? -x[1] + 1 : x[0], onFemur ? x[0] + 2 : x[1], onFemur ? x[2] + 3 : x[2] };
      const double* y = after->GetPoint(i);
      for (int k = 0; k < 3; ++k)
      {
        EXPECT_NEAR(y[k], expected[k], 1e-9) << "block " << b << " point " << i;
      }
    }
  }
}
