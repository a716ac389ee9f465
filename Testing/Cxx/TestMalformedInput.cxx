// SPDX-License-Identifier: BSD-3-Clause
// Malformed input through every filter: cells that refer to points a block does not have, and
// point arrays shorter than the points. Each must be refused with a message naming the input and
// the block, never read past an array's end (these crashed ParaView before).
#include "FilterTestUtilities.h"
#include "Geometry/MeshChecks.h"
#include "MDBlocks.h"
#include "MDReport.h"

#include "vtkActionLineGrouping.h"
#include "vtkActionLineMatching.h"
#include "vtkBoneInterpolation.h"
#include "vtkHullDecimation.h"
#include "vtkInterpolatedMuscleDeformation.h"
#include "vtkIntersectionResolve.h"
#include "vtkMoveWithBodies.h"
#include "vtkMuscleDeformation.h"
#include "vtkMusculoskeletalPhantom.h"

#include <vtkAOSDataArrayTemplate.h>
#include <vtkCellArray.h>
#include <vtkDoubleArray.h>
#include <vtkFieldData.h>
#include <vtkPointData.h>
#include <vtkStringArray.h>
#include <vtkTable.h>
#include <vtkVariant.h>

#include <gtest/gtest.h>

#include <cmath>
#include <functional>

namespace
{
constexpr vtkIdType kFarAway = 1000000000;

/// A copy of `source` with one more cell whose last point id is out of range: a polyline
/// [0, 1, 1e9] or a triangle (0, 1, 1e9).
vtkSmartPointer<vtkPolyData> WithBadCell(vtkPolyData* source, bool line)
{
  auto copy = vtkSmartPointer<vtkPolyData>::New();
  copy->DeepCopy(source);
  if (line)
  {
    const vtkIdType ids[3] = { 0, 1, kFarAway };
    copy->GetLines()->InsertNextCell(3, ids);
  }
  else
  {
    const vtkIdType ids[3] = { 0, 1, kFarAway };
    copy->GetPolys()->InsertNextCell(3, ids);
  }
  return copy;
}

/// `tree` with its first block replaced by `block`.
vtkSmartPointer<vtkMultiBlockDataSet> WithFirstBlock(vtkMultiBlockDataSet* tree, vtkPolyData* block)
{
  auto copy = vtkSmartPointer<vtkMultiBlockDataSet>::New();
  copy->ShallowCopy(tree);
  copy->SetBlock(0, block);
  return copy;
}

vtkPolyData* FirstBlock(vtkDataObject* tree)
{
  return vtkPolyData::SafeDownCast(vtkMultiBlockDataSet::SafeDownCast(tree)->GetBlock(0));
}

struct Phantom
{
  vtkNew<vtkMusculoskeletalPhantom> source;
  vtkNew<vtkActionLineMatching> matching;
  vtkMultiBlockDataSet* Output(int port)
  {
    return vtkMultiBlockDataSet::SafeDownCast(this->source->GetOutputDataObject(port));
  }
  Phantom()
  {
    this->source->SetResolution(12);
    this->source->SetFlexion(60); // the femur sweeps into the rectus femoris
    this->source->Update();
    this->matching->SetInputConnection(this->source->GetOutputPort(3));
    this->matching->SetCurrentPoseConnection(this->source->GetOutputPort(4));
    this->matching->Update();
  }
  vtkMultiBlockDataSet* Matched() { return vtkMultiBlockDataSet::SafeDownCast(this->matching->GetOutputDataObject(0)); }
  vtkSmartPointer<vtkMultiBlockDataSet> BadLines(int port)
  {
    return WithFirstBlock(this->Output(port), WithBadCell(FirstBlock(this->Output(port)), true));
  }
  vtkSmartPointer<vtkMultiBlockDataSet> BadMeshes(int port)
  {
    return WithFirstBlock(this->Output(port), WithBadCell(FirstBlock(this->Output(port)), false));
  }
};

/// Runs `filter` (inputs already set) and returns what it reported; the run must fail cleanly.
std::string Refusal(vtkAlgorithm* filter)
{
  CapturedMessages messages;
  filter->Update();
  return messages.Text();
}
}

TEST(MalformedInput, OutOfRangePointIdsAreRefusedByEveryFilter)
{
  Phantom phantom;
  const std::string far = "refers to point 1000000000";
  {
    vtkNew<vtkActionLineMatching> f;
    f->SetInputDataObject(0, phantom.BadLines(vtkMusculoskeletalPhantom::ACTION_LINES_REST));
    f->SetInputDataObject(1, phantom.Output(vtkMusculoskeletalPhantom::ACTION_LINES_CURRENT));
    const std::string text = Refusal(f);
    EXPECT_NE(
      text.find("Input block 'Iliopsoas' has a line cell that " + far + ", but it has 3 points"), std::string::npos)
      << text;
  }
  {
    vtkNew<vtkBoneInterpolation> f;
    f->SetInputDataObject(0, phantom.Output(vtkMusculoskeletalPhantom::BONES_REST));
    f->SetInputDataObject(1, phantom.BadMeshes(vtkMusculoskeletalPhantom::BONES_CURRENT));
    const std::string text = Refusal(f);
    EXPECT_NE(text.find("CurrentPose block 'Pelvis' has a polygon cell that " + far), std::string::npos) << text;
  }
  {
    vtkNew<vtkHullDecimation> f;
    f->SetInputDataObject(0, phantom.BadMeshes(vtkMusculoskeletalPhantom::MUSCLES));
    EXPECT_NE(Refusal(f).find(far), std::string::npos);
  }
  {
    vtkNew<vtkMuscleDeformation> f;
    f->SetInputDataObject(0, phantom.Output(vtkMusculoskeletalPhantom::MUSCLES));
    f->SetInputDataObject(1, phantom.Matched());
    f->AddInputDataObject(2, phantom.BadMeshes(vtkMusculoskeletalPhantom::BONES_CURRENT));
    const std::string text = Refusal(f);
    EXPECT_NE(text.find("Obstacles connection 1 block 'Pelvis' has a polygon cell that " + far), std::string::npos)
      << text;
  }
  {
    // A CurrentPosition array shorter than the points of its lines.
    auto lines = vtkSmartPointer<vtkPolyData>::New();
    lines->DeepCopy(FirstBlock(phantom.Matched()));
    vtkNew<vtkDoubleArray> shortPositions;
    shortPositions->SetName("CurrentPosition");
    shortPositions->SetNumberOfComponents(3);
    shortPositions->InsertNextTuple3(0, 0, 0);
    lines->GetPointData()->AddArray(shortPositions);
    vtkNew<vtkMuscleDeformation> f;
    f->SetInputDataObject(0, phantom.Output(vtkMusculoskeletalPhantom::MUSCLES));
    f->SetInputDataObject(1, WithFirstBlock(phantom.Matched(), lines));
    const std::string text = Refusal(f);
    EXPECT_NE(text.find("point array 'CurrentPosition' has 1 values but the block has"), std::string::npos) << text;
  }
  {
    vtkNew<vtkIntersectionResolve> f;
    f->SetInputDataObject(0, phantom.BadMeshes(vtkMusculoskeletalPhantom::MUSCLES));
    f->AddInputDataObject(1, phantom.Output(vtkMusculoskeletalPhantom::BONES_CURRENT));
    EXPECT_NE(Refusal(f).find(far), std::string::npos);
  }
  {
    vtkNew<vtkIntersectionResolve> f;
    f->SetInputDataObject(0, phantom.Output(vtkMusculoskeletalPhantom::MUSCLES));
    f->AddInputDataObject(1, phantom.BadMeshes(vtkMusculoskeletalPhantom::BONES_CURRENT));
    EXPECT_NE(Refusal(f).find(far), std::string::npos);
  }
  {
    vtkNew<vtkInterpolatedMuscleDeformation> f;
    f->SetInputDataObject(0, phantom.Output(vtkMusculoskeletalPhantom::MUSCLES));
    f->SetInputDataObject(1, phantom.Output(vtkMusculoskeletalPhantom::BONES_REST));
    f->SetInputDataObject(2, phantom.BadMeshes(vtkMusculoskeletalPhantom::BONES_CURRENT));
    f->SetInputDataObject(3, phantom.Output(vtkMusculoskeletalPhantom::ACTION_LINES_REST));
    f->SetInputDataObject(4, phantom.BadLines(vtkMusculoskeletalPhantom::ACTION_LINES_CURRENT));
    EXPECT_NE(Refusal(f).find(far), std::string::npos);
  }
  {
    vtkNew<vtkActionLineGrouping> f;
    f->SetInputDataObject(0, phantom.Output(vtkMusculoskeletalPhantom::MUSCLES));
    f->SetInputDataObject(1, phantom.BadLines(vtkMusculoskeletalPhantom::ACTION_LINES_REST));
    EXPECT_NE(Refusal(f).find(far), std::string::npos);
  }
  {
    vtkNew<vtkMoveWithBodies> f;
    vtkNew<vtkTable> transforms;
    f->SetInputDataObject(0, phantom.BadMeshes(vtkMusculoskeletalPhantom::BONES_REST));
    f->SetInputDataObject(1, transforms);
    EXPECT_NE(Refusal(f).find(far), std::string::npos);
  }
}

TEST(MalformedInput, ABoneEmptyInOnePoseIsAnError)
{
  Phantom phantom;
  auto current = vtkSmartPointer<vtkMultiBlockDataSet>::New();
  current->ShallowCopy(phantom.Output(vtkMusculoskeletalPhantom::BONES_CURRENT));
  current->SetBlock(1, nullptr); // the femur's current pose is missing
  vtkNew<vtkInterpolatedMuscleDeformation> f;
  f->SetInputDataObject(0, phantom.Output(vtkMusculoskeletalPhantom::MUSCLES));
  f->SetInputDataObject(1, phantom.Output(vtkMusculoskeletalPhantom::BONES_REST));
  f->SetInputDataObject(2, current);
  f->SetInputDataObject(3, phantom.Output(vtkMusculoskeletalPhantom::ACTION_LINES_REST));
  f->SetInputDataObject(4, phantom.Output(vtkMusculoskeletalPhantom::ACTION_LINES_CURRENT));
  const std::string text = Refusal(f);
  EXPECT_NE(text.find("BonesCurrent block 'Femur' is empty but BonesRest block 'Femur' is not"), std::string::npos)
    << text;
}

TEST(MalformedInput, IntersectionResolveReportsItsOwnVolumeChange)
{
  // A muscle with upstream field data claiming no volume change: after the resolution the
  // output must say what the resolution did, not pass the claim on.
  Phantom phantom;
  auto muscles = vtkSmartPointer<vtkMultiBlockDataSet>::New();
  muscles->ShallowCopy(phantom.Output(vtkMusculoskeletalPhantom::MUSCLES));
  auto claimed = vtkSmartPointer<vtkPolyData>::New();
  claimed->ShallowCopy(FirstBlock(muscles));
  vtkNew<vtkFieldData> fieldData;
  vtkNew<vtkDoubleArray> stale;
  stale->SetName("VolumeChangePercent");
  stale->InsertNextValue(0.0);
  fieldData->AddArray(stale);
  claimed->SetFieldData(fieldData);
  muscles->SetBlock(0, claimed);
  vtkNew<vtkIntersectionResolve> f;
  f->SetInputDataObject(0, muscles);
  // The bones in the current pose (60 degrees): the femur has swept into the rectus femoris.
  f->AddInputDataObject(1, phantom.Output(vtkMusculoskeletalPhantom::BONES_CURRENT));
  f->Update();
  auto* out = vtkMultiBlockDataSet::SafeDownCast(f->GetOutputDataObject(0));
  for (unsigned int b = 0; b < out->GetNumberOfBlocks(); ++b)
  {
    auto* muscle = vtkPolyData::SafeDownCast(out->GetBlock(b));
    auto* input = vtkPolyData::SafeDownCast(muscles->GetBlock(b));
    vtkDataArray* change = muscle->GetFieldData()->GetArray("VolumeChangePercent");
    ASSERT_NE(change, nullptr);
    ASSERT_EQ(muscle->GetFieldData()->GetNumberOfArrays(), 7);
    // Recomputed independently: the divergence theorem over the output's triangles.
    auto volume = [](vtkPolyData* mesh) {
      double sum = 0;
      vtkCellArray* polys = mesh->GetPolys();
      const vtkIdType* ids;
      vtkIdType n;
      for (polys->InitTraversal(); polys->GetNextCell(n, ids);)
      {
        double a[3], p[3], c[3];
        mesh->GetPoint(ids[0], a);
        mesh->GetPoint(ids[1], p);
        mesh->GetPoint(ids[2], c);
        sum += (a[0] * (p[1] * c[2] - p[2] * c[1]) - a[1] * (p[0] * c[2] - p[2] * c[0]) +
                 a[2] * (p[0] * c[1] - p[1] * c[0])) /
          6;
      }
      return sum;
    };
    EXPECT_NEAR(change->GetTuple1(0), 100 * (volume(muscle) - volume(input)) / volume(input), 1e-9);
  }
  auto* rectus = vtkPolyData::SafeDownCast(out->GetBlock(2));
  EXPECT_GT(rectus->GetFieldData()->GetArray("MaxStaticShift")->GetTuple1(0), 1.0);
  EXPECT_GT(std::abs(rectus->GetFieldData()->GetArray("VolumeChangePercent")->GetTuple1(0)), 1e-3);
}

TEST(MalformedInput, IdsChangedBehindTheArraysBackAreStillChecked)
{
  // An id written straight into the connectivity after its range was computed (and cached),
  // with no Modified(): a check trusting the cached range would let it through.
  Phantom phantom;
  auto muscle = vtkSmartPointer<vtkPolyData>::New();
  muscle->DeepCopy(FirstBlock(phantom.Output(vtkMusculoskeletalPhantom::MUSCLES)));
  vtkDataArray* connectivity = muscle->GetPolys()->GetConnectivityArray();
  double range[2];
  connectivity->GetRange(range, 0);
  auto* ids = vtkAOSDataArrayTemplate<vtkTypeInt64>::FastDownCast(connectivity);
  ASSERT_NE(ids, nullptr);
  ids->GetPointer(0)[5] = kFarAway;
  vtkNew<vtkHullDecimation> f;
  f->SetInputDataObject(0, muscle);
  const std::string text = Refusal(f);
  EXPECT_NE(text.find("refers to point 1000000000"), std::string::npos) << text;
}

TEST(MalformedInput, AFlatMuscleGetsAnErrorNotABrokenHull)
{
  // The phantom's gluteus maximus squashed to 1e-4 of its thickness: closed, but flat. Its hull
  // came out with non-manifold edges and no message; now either a clear error or a true hull.
  Phantom phantom;
  for (double thickness : { 0.0, 1e-4 })
  {
    auto muscle = vtkSmartPointer<vtkPolyData>::New();
    muscle->DeepCopy(vtkPolyData::SafeDownCast(phantom.Output(vtkMusculoskeletalPhantom::MUSCLES)->GetBlock(1)));
    vtkPoints* points = muscle->GetPoints();
    for (vtkIdType i = 0; i < points->GetNumberOfPoints(); ++i)
    {
      double p[3];
      points->GetPoint(i, p);
      p[2] *= thickness;
      points->SetPoint(i, p);
    }
    vtkNew<vtkHullDecimation> f;
    f->SetInputDataObject(0, muscle);
    CapturedMessages messages;
    f->Update();
    auto* hull = vtkPolyData::SafeDownCast(f->GetOutputDataObject(0));
    if (hull->GetNumberOfPolys() == 0)
    {
      EXPECT_TRUE(messages.Contains("ERR") || messages.Contains("ERROR")) << thickness;
      continue;
    }
    md::TriangleMesh mesh;
    mesh.points.resize(hull->GetNumberOfPoints(), 3);
    for (vtkIdType i = 0; i < hull->GetNumberOfPoints(); ++i)
    {
      hull->GetPoint(i, mesh.points.row(i).data());
    }
    vtkCellArray* polys = hull->GetPolys();
    mesh.triangles.resize(polys->GetNumberOfCells(), 3);
    const vtkIdType* ids;
    vtkIdType n;
    Eigen::Index t = 0;
    for (polys->InitTraversal(); polys->GetNextCell(n, ids); ++t)
    {
      mesh.triangles.row(t) << ids[0], ids[1], ids[2];
    }
    EXPECT_TRUE(md::CheckEdges(mesh.triangles).IsClosedOrientedManifold()) << thickness;
  }
}

TEST(MalformedInput, NoStaleResultAfterAFailureHereOrUpstream)
{
  // After a good run, a failure (of the filter itself, or of a filter upstream, when the
  // pipeline never calls this one) must leave an empty output, not the last result: in the GUI
  // that looked like the new result.
  Phantom phantom;
  auto points = [](vtkAlgorithm* f) {
    return vtkCompositeDataSet::SafeDownCast(f->GetOutputDataObject(0))->GetNumberOfPoints();
  };
  vtkNew<vtkActionLineMatching> matching;
  matching->SetInputConnection(0, phantom.source->GetOutputPort(vtkMusculoskeletalPhantom::ACTION_LINES_REST));
  matching->SetInputConnection(1, phantom.source->GetOutputPort(vtkMusculoskeletalPhantom::ACTION_LINES_CURRENT));
  vtkNew<vtkMuscleDeformation> pass;
  pass->SetInputConnection(0, phantom.source->GetOutputPort(vtkMusculoskeletalPhantom::MUSCLES));
  pass->SetInputConnection(1, matching->GetOutputPort(0));
  pass->SetHullTargetNumberOfPoints(100);
  vtkNew<vtkInterpolatedMuscleDeformation> method;
  method->SetInputConnection(0, phantom.source->GetOutputPort(vtkMusculoskeletalPhantom::MUSCLES));
  method->SetBonesRestConnection(phantom.source->GetOutputPort(vtkMusculoskeletalPhantom::BONES_REST));
  method->SetBonesCurrentConnection(phantom.source->GetOutputPort(vtkMusculoskeletalPhantom::BONES_CURRENT));
  method->SetActionLinesRestConnection(phantom.source->GetOutputPort(vtkMusculoskeletalPhantom::ACTION_LINES_REST));
  method->SetActionLinesCurrentConnection(matching->GetOutputPort(0));
  method->SetNumberOfSteps(2);
  method->SetHullTargetNumberOfPoints(100);
  vtkNew<vtkHullDecimation> hull;
  hull->SetInputConnection(pass->GetOutputPort(0));
  hull->SetTargetNumberOfPoints(100);
  for (vtkAlgorithm* f : std::initializer_list<vtkAlgorithm*>{ pass, method, hull })
  {
    f->Update();
    ASSERT_GT(points(f), 0) << f->GetClassName();
  }

  // Upstream: the matching fails (the muscles given as current action lines).
  matching->SetInputConnection(1, phantom.source->GetOutputPort(vtkMusculoskeletalPhantom::MUSCLES));
  {
    CapturedMessages messages;
    for (vtkAlgorithm* f : std::initializer_list<vtkAlgorithm*>{ pass, method, hull })
    {
      f->Update();
      EXPECT_EQ(points(f), 0) << f->GetClassName();
    }
    EXPECT_TRUE(messages.Contains("ActionLineMatching"));
  }

  // Here: good inputs again, then the raw lines (no CurrentPosition) given to the pass.
  matching->SetInputConnection(1, phantom.source->GetOutputPort(vtkMusculoskeletalPhantom::ACTION_LINES_CURRENT));
  pass->Update();
  ASSERT_GT(points(pass), 0);
  pass->SetInputConnection(1, phantom.source->GetOutputPort(vtkMusculoskeletalPhantom::ACTION_LINES_REST));
  {
    CapturedMessages messages;
    pass->Update();
    EXPECT_EQ(points(pass), 0);
    EXPECT_TRUE(messages.Contains("CurrentPosition"));
  }
}

TEST(MalformedInput, IntersectionResolveWithoutObstaclesSaysSo)
{
  // Without Obstacles the bones are no part of the resolution: said, not silent.
  Phantom phantom;
  vtkNew<vtkIntersectionResolve> f;
  f->SetInputDataObject(0, phantom.Output(vtkMusculoskeletalPhantom::MUSCLES));
  CapturedMessages messages;
  f->Update();
  EXPECT_TRUE(messages.Contains("no Obstacles are connected")) << messages.Text();
  EXPECT_FALSE(messages.Contains("ERROR")) << messages.Text();
}

TEST(MalformedInput, EveryFailureOfTheCoreBecomesAnErrorMessageNotACrash)
{
  // Only InputError was caught: a diverged computation was reported as bad input, and out of
  // memory escaped RequestData. The one guard every filter calls the core through now tells
  // them apart and catches everything.
  vtkNew<vtkMuscleDeformation> filter;
  struct Case
  {
    std::function<void()> failure;
    const char* message;
    int result;
  };
  const std::vector<Case> cases = {
    { [] { throw md::InputError("no action line"); }, "muscle 'A': no action line", 0 },
    { [] { throw md::ComputationError("diverged"); }, "muscle 'A': diverged", 0 },
    { [] { throw std::bad_alloc(); }, "muscle 'A': out of memory", 0 },
    { [] { throw std::runtime_error("odd"); }, "muscle 'A': unexpected failure: odd", 0 },
  };
  for (const Case& c : cases)
  {
    CapturedMessages messages;
    int result = 1;
    EXPECT_FALSE(mdvtk::CallCore(filter, "muscle 'A': ", c.failure, result));
    EXPECT_EQ(result, c.result);
    EXPECT_TRUE(messages.Contains(c.message)) << messages.Text();
  }
  int result = 1;
  EXPECT_TRUE(mdvtk::CallCore(
    filter, "", [] {}, result));
  EXPECT_EQ(result, 1);
}

TEST(MalformedInput, AnInputCheckedOnceIsCheckedAgainWhenALeafOfItIsModified)
{
  // MoveWithBodies and MotionMuscleDeformation run at every frame of a motion with the same rest
  // pose: they check it once, and again only where it (or a leaf of it) was modified since.
  Phantom phantom;
  auto bones = vtkSmartPointer<vtkMultiBlockDataSet>::New();
  bones->DeepCopy(phantom.Output(vtkMusculoskeletalPhantom::BONES_REST));
  vtkNew<vtkTable> transforms; // every body still
  vtkNew<vtkStringArray> body;
  body->SetName("Body");
  transforms->AddColumn(body);
  for (const char* name : { "R00", "R01", "R02", "R10", "R11", "R12", "R20", "R21", "R22", "Tx", "Ty", "Tz" })
  {
    vtkNew<vtkDoubleArray> column;
    column->SetName(name);
    transforms->AddColumn(column);
  }
  for (unsigned int b = 0; b < bones->GetNumberOfBlocks(); ++b)
  {
    const char* blockName = bones->GetMetaData(b)->Get(vtkCompositeDataSet::NAME());
    transforms->InsertNextBlankRow();
    transforms->SetValue(b, 0, vtkVariant(blockName));
    for (int i = 0; i < 3; ++i)
    {
      transforms->SetValue(b, 1 + 4 * i, vtkVariant(1.0));
    }
  }
  vtkNew<vtkMoveWithBodies> f;
  f->SetInputDataObject(0, bones);
  f->SetInputDataObject(1, transforms);
  EXPECT_EQ(Refusal(f), "");
  auto* leaf = FirstBlock(bones);
  leaf->GetPoints()->SetPoint(3, std::nan(""), 0.0, 0.0);
  leaf->GetPoints()->Modified();
  f->SetBodyOfSurface("unused=nothing"); // runs again; the multiblock itself is not modified
  const std::string text = Refusal(f);
  EXPECT_NE(text.find("has NaN or infinite coordinates (point 3)"), std::string::npos) << text;
}
