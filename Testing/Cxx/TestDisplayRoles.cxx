// SPDX-License-Identifier: BSD-3-Clause
// The cell array Role that the filters write, which the plugin's colour map turns into bone,
// muscle, action-line and hull colours (issue: bones and muscles shared colours by port).
#include "vtkActionLineMatching.h"
#include "vtkBoneInterpolation.h"
#include "vtkHullDecimation.h"
#include "vtkInterpolatedMuscleDeformation.h"
#include "vtkMuscleDeformation.h"
#include "vtkMusculoskeletalPhantom.h"

#include <vtkCellData.h>
#include <vtkDataArray.h>
#include <vtkDataObjectTreeIterator.h>
#include <vtkDoubleArray.h>
#include <vtkMultiBlockDataSet.h>
#include <vtkNew.h>
#include <vtkPointData.h>
#include <vtkPolyData.h>
#include <vtkSmartPointer.h>

#include <gtest/gtest.h>

#include <vector>

namespace
{
/// The Role value of every leaf (its first cell's), -1 where a leaf has none or its cells differ;
/// `active` says whether Role is each leaf's active cell scalars.
std::vector<int> Roles(vtkDataObject* data, std::vector<bool>* active = nullptr)
{
  std::vector<int> roles;
  vtkSmartPointer<vtkDataObjectTreeIterator> it;
  it.TakeReference(vtkMultiBlockDataSet::SafeDownCast(data)->NewTreeIterator());
  it->VisitOnlyLeavesOn();
  for (it->InitTraversal(); !it->IsDoneWithTraversal(); it->GoToNextItem())
  {
    auto* leaf = vtkPolyData::SafeDownCast(it->GetCurrentDataObject());
    vtkDataArray* role = leaf ? leaf->GetCellData()->GetArray("Role") : nullptr;
    int value = -1;
    if (role && role->GetNumberOfTuples() == leaf->GetNumberOfCells() && leaf->GetNumberOfCells() > 0)
    {
      const double* range = role->GetRange();
      value = range[0] == range[1] ? static_cast<int>(range[0]) : -1;
    }
    roles.push_back(value);
    if (active)
    {
      active->push_back(leaf && leaf->GetCellData()->GetScalars() == role && role);
    }
  }
  return roles;
}

constexpr int Bone = 0, Line = 9, Hull = 10;

struct Hip
{
  vtkNew<vtkMusculoskeletalPhantom> phantom;
  Hip() { this->phantom->SetResolution(12); }
  vtkDataObject* Output(int port)
  {
    this->phantom->Update();
    return this->phantom->GetOutputDataObject(port);
  }
};
}

TEST(DisplayRoles, EveryOutputSaysWhatItIsAndMusclesTakeShadesInTurn)
{
  Hip hip;
  std::vector<bool> active;
  EXPECT_EQ(Roles(hip.Output(vtkMusculoskeletalPhantom::MUSCLES), &active), (std::vector<int>{ 1, 2, 3 }));
  EXPECT_EQ(active, (std::vector<bool>{ true, true, true }));
  for (int port : { vtkMusculoskeletalPhantom::BONES_REST, vtkMusculoskeletalPhantom::BONES_CURRENT })
  {
    EXPECT_EQ(Roles(hip.Output(port)), (std::vector<int>{ Bone, Bone }));
  }
  EXPECT_EQ(Roles(hip.Output(vtkMusculoskeletalPhantom::ACTION_LINES_REST)), (std::vector<int>{ Line, Line, Line }));

  vtkNew<vtkActionLineMatching> matching;
  matching->SetInputConnection(0, hip.phantom->GetOutputPort(vtkMusculoskeletalPhantom::ACTION_LINES_REST));
  matching->SetInputConnection(1, hip.phantom->GetOutputPort(vtkMusculoskeletalPhantom::ACTION_LINES_CURRENT));
  matching->Update();
  EXPECT_EQ(Roles(matching->GetOutputDataObject(0)), (std::vector<int>{ Line, Line, Line }));

  vtkNew<vtkHullDecimation> hulls;
  hulls->SetInputConnection(hip.phantom->GetOutputPort(vtkMusculoskeletalPhantom::MUSCLES));
  hulls->SetTargetNumberOfPoints(100);
  hulls->Update();
  EXPECT_EQ(Roles(hulls->GetOutputDataObject(0)), (std::vector<int>{ Hull, Hull, Hull }));

  vtkNew<vtkMuscleDeformation> pass;
  pass->SetInputConnection(0, hip.phantom->GetOutputPort(vtkMusculoskeletalPhantom::MUSCLES));
  pass->SetInputConnection(1, matching->GetOutputPort(0));
  pass->AddInputConnection(2, hip.phantom->GetOutputPort(vtkMusculoskeletalPhantom::BONES_CURRENT));
  pass->SetHullTargetNumberOfPoints(100);
  pass->Update();
  EXPECT_EQ(Roles(pass->GetOutputDataObject(0)), (std::vector<int>{ 1, 2, 3 }));

  vtkNew<vtkInterpolatedMuscleDeformation> method;
  for (int port = 0; port < 5; ++port)
  {
    method->SetInputConnection(port, hip.phantom->GetOutputPort(port));
  }
  method->SetNumberOfSteps(1);
  method->SetHullTargetNumberOfPoints(100);
  method->Update();
  EXPECT_EQ(Roles(method->GetOutputDataObject(0)), (std::vector<int>{ 1, 2, 3 }));
  EXPECT_EQ(Roles(method->GetOutputDataObject(1)), (std::vector<int>{ Bone, Bone }));
  EXPECT_EQ(Roles(method->GetOutputDataObject(2)), (std::vector<int>{ Line, Line, Line }));
}

TEST(DisplayRoles, UnmarkedInputGetsItsRoleAndOwnScalarsStayActive)
{
  // Muscles read from files carry no Role: the deformation marks its output. A muscle with
  // active scalars of its own keeps them active (Role is added beside them).
  Hip hip;
  auto muscles = vtkSmartPointer<vtkMultiBlockDataSet>::New();
  muscles->DeepCopy(hip.Output(vtkMusculoskeletalPhantom::MUSCLES));
  for (unsigned int b = 0; b < muscles->GetNumberOfBlocks(); ++b)
  {
    auto* muscle = vtkPolyData::SafeDownCast(muscles->GetBlock(b));
    muscle->GetCellData()->RemoveArray("Role");
    if (b == 0)
    {
      vtkNew<vtkDoubleArray> thickness;
      thickness->SetName("Thickness");
      thickness->SetNumberOfTuples(muscle->GetNumberOfPoints());
      thickness->Fill(1.0);
      muscle->GetPointData()->SetScalars(thickness);
    }
  }
  vtkNew<vtkActionLineMatching> matching;
  matching->SetInputConnection(0, hip.phantom->GetOutputPort(vtkMusculoskeletalPhantom::ACTION_LINES_REST));
  matching->SetInputConnection(1, hip.phantom->GetOutputPort(vtkMusculoskeletalPhantom::ACTION_LINES_CURRENT));
  vtkNew<vtkMuscleDeformation> pass;
  pass->SetInputDataObject(0, muscles);
  pass->SetInputConnection(1, matching->GetOutputPort(0));
  pass->AddInputConnection(2, hip.phantom->GetOutputPort(vtkMusculoskeletalPhantom::BONES_CURRENT));
  pass->SetHullTargetNumberOfPoints(100);
  pass->Update();
  std::vector<bool> active;
  EXPECT_EQ(Roles(pass->GetOutputDataObject(0), &active), (std::vector<int>{ 1, 2, 3 }));
  EXPECT_EQ(active, (std::vector<bool>{ false, true, true }));
  EXPECT_EQ(Roles(muscles), (std::vector<int>{ -1, -1, -1 })) << "the input itself is left as it was";

  // BoneInterpolation keeps a role it is given, and calls unmarked surfaces bones and unmarked
  // polylines action lines.
  vtkNew<vtkBoneInterpolation> moved;
  moved->SetInputConnection(0, hip.phantom->GetOutputPort(vtkMusculoskeletalPhantom::MUSCLES));
  moved->SetInputConnection(1, hip.phantom->GetOutputPort(vtkMusculoskeletalPhantom::MUSCLES));
  moved->UpdateTimeStep(1);
  EXPECT_EQ(Roles(moved->GetOutputDataObject(0)), (std::vector<int>{ 1, 2, 3 }));
  moved->SetInputDataObject(0, muscles);
  moved->SetInputDataObject(1, muscles);
  moved->UpdateTimeStep(1);
  EXPECT_EQ(Roles(moved->GetOutputDataObject(0)), (std::vector<int>{ Bone, Bone, Bone }));
  moved->SetInputConnection(0, matching->GetOutputPort(0));
  moved->SetInputConnection(1, nullptr);
  moved->SetInterpolationMode(vtkBoneInterpolation::LINEAR); // the lines do not move rigidly
  moved->UpdateTimeStep(1);
  EXPECT_EQ(Roles(moved->GetOutputDataObject(0)), (std::vector<int>{ Line, Line, Line }));
}
