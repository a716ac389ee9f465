// SPDX-License-Identifier: BSD-3-Clause
// The one-pass filter as a pipeline: what it keeps between runs, and on the muscles' surfaces
// an answer that neither a hull nor rounding decides. A muscle's hull and mean value
// coordinates depend on its rest-pose surface and the hull size only; a new pose must not
// rebuild them (at 97k points the hull is most of a pass's time), and a kept hull must give
// exactly what a new one gives. And a user's cancel (AbortExecute) stops a run cleanly.
#include "FilterTestUtilities.h"

#include "Deformation/MuscleDeformer.h"
#include "Geometry/TriangleTree.h"
#include "MDBlocks.h"
#include "MDConvert.h"

#include "vtkActionLineMatching.h"
#include "vtkBoneInterpolation.h"
#include "vtkHullDecimation.h"
#include "vtkInterpolatedMuscleDeformation.h"
#include "vtkIntersectionResolve.h"
#include "vtkMuscleDeformation.h"
#include "vtkMusculoskeletalPhantom.h"

#include <vtkCallbackCommand.h>
#include <vtkCellData.h>
#include <vtkCommand.h>
#include <vtkDataArray.h>
#include <vtkFieldData.h>
#include <vtkIdList.h>
#include <vtkStreamingDemandDrivenPipeline.h>
#include <vtkStringArray.h>
#include <vtkTable.h>
#include <vtkVariant.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <random>

namespace
{
/// Largest difference between the points of two multiblocks of polydata with the same structure.
double LargestDifference(vtkDataObject* a, vtkDataObject* b)
{
  auto* x = vtkMultiBlockDataSet::SafeDownCast(a);
  auto* y = vtkMultiBlockDataSet::SafeDownCast(b);
  double largest = 0;
  for (unsigned int k = 0; k < x->GetNumberOfBlocks(); ++k)
  {
    auto* u = vtkPolyData::SafeDownCast(x->GetBlock(k));
    auto* v = vtkPolyData::SafeDownCast(y->GetBlock(k));
    for (vtkIdType i = 0; i < u->GetNumberOfPoints(); ++i)
    {
      double p[3], q[3];
      u->GetPoint(i, p);
      v->GetPoint(i, q);
      largest = std::max({ largest, std::abs(p[0] - q[0]), std::abs(p[1] - q[1]), std::abs(p[2] - q[2]) });
    }
  }
  return largest;
}

/// Sets the observed filter's AbortExecute (as ParaView's cancel does) once its progress passes
/// `threshold`, and counts the progress events that still come after.
struct AbortPast
{
  double threshold;
  int eventsAfterAbort = 0;
  vtkNew<vtkCallbackCommand> command;
  explicit AbortPast(double progress)
    : threshold(progress)
  {
    this->command->SetClientData(this);
    this->command->SetCallback([](vtkObject* caller, unsigned long, void* clientData, void*) {
      auto* self = static_cast<AbortPast*>(clientData);
      auto* filter = vtkAlgorithm::SafeDownCast(caller);
      if (filter->GetAbortExecute())
      {
        ++self->eventsAfterAbort;
      }
      else if (filter->GetProgress() > self->threshold)
      {
        filter->SetAbortExecute(1);
      }
    });
  }
};

/// Aborts `f` once its progress passes `threshold`: the run must stop there without an error and
/// leave an empty output, and the next run must compute afresh.
void ExpectAbortStopsCleanly(vtkAlgorithm* f, double threshold)
{
  AbortPast stop(threshold);
  const unsigned long observer = f->AddObserver(vtkCommand::ProgressEvent, stop.command);
  {
    CapturedMessages messages;
    f->Update();
    EXPECT_FALSE(messages.Contains("ERROR")) << messages.Text();
  }
  EXPECT_LE(stop.eventsAfterAbort, 1); // at most the executive's own final report
  EXPECT_EQ(vtkCompositeDataSet::SafeDownCast(f->GetOutputDataObject(0))->GetNumberOfPoints(), 0);
  f->RemoveObserver(observer);
  f->SetAbortExecute(0);
  f->Modified();
  f->Update();
  EXPECT_GT(vtkCompositeDataSet::SafeDownCast(f->GetOutputDataObject(0))->GetNumberOfPoints(), 0);
}

/// The phantom's muscles with one point of the second muscle moved by 0.5.
vtkSmartPointer<vtkMultiBlockDataSet> WithOnePointMoved(vtkMusculoskeletalPhantom* phantom)
{
  auto muscles = vtkSmartPointer<vtkMultiBlockDataSet>::New();
  muscles->DeepCopy(phantom->GetOutputDataObject(vtkMusculoskeletalPhantom::MUSCLES));
  vtkPoints* points = vtkPolyData::SafeDownCast(muscles->GetBlock(1))->GetPoints();
  double p[3];
  points->GetPoint(0, p);
  p[0] += 0.5;
  points->SetPoint(0, p);
  return muscles;
}

struct PhantomPipeline
{
  vtkNew<vtkMusculoskeletalPhantom> phantom;
  vtkNew<vtkActionLineMatching> matching;
  PhantomPipeline()
  {
    this->phantom->SetResolution(12);
    this->matching->SetInputConnection(0, this->phantom->GetOutputPort(vtkMusculoskeletalPhantom::ACTION_LINES_REST));
    this->matching->SetInputConnection(
      1, this->phantom->GetOutputPort(vtkMusculoskeletalPhantom::ACTION_LINES_CURRENT));
  }
  void Connect(vtkMuscleDeformation* f)
  {
    f->SetInputConnection(0, this->phantom->GetOutputPort(vtkMusculoskeletalPhantom::MUSCLES));
    f->SetInputConnection(1, this->matching->GetOutputPort(0));
    f->AddInputConnection(2, this->phantom->GetOutputPort(vtkMusculoskeletalPhantom::BONES_CURRENT));
    f->SetHullTargetNumberOfPoints(100);
  }
  /// The phantom's five outputs into the whole method, as they are (raw action lines).
  void Connect(vtkInterpolatedMuscleDeformation* f)
  {
    for (int port = 0; port < 5; ++port)
    {
      f->SetInputConnection(port, this->phantom->GetOutputPort(port));
    }
    f->SetHullTargetNumberOfPoints(100);
  }
};
}

TEST(MuscleDeformationFilter, HullsAreKeptAcrossPosesAndSettingsThatDoNotTouchThem)
{
  PhantomPipeline pipeline;
  vtkNew<vtkMuscleDeformation> f;
  pipeline.Connect(f);
  f->Update();
  ASSERT_EQ(f->GetHullBuildCount(), 3); // one per muscle

  // Another iteration setting, then another pose: the same hulls.
  f->SetConvergenceTolerance(0.005);
  f->Update();
  EXPECT_EQ(f->GetHullBuildCount(), 3);
  pipeline.phantom->SetFlexion(30);
  f->Update();
  EXPECT_EQ(f->GetHullBuildCount(), 3);

  // A kept hull gives exactly what a new filter builds for itself.
  vtkNew<vtkMuscleDeformation> fresh;
  pipeline.Connect(fresh);
  fresh->SetConvergenceTolerance(0.005);
  fresh->Update();
  EXPECT_EQ(LargestDifference(f->GetOutputDataObject(0), fresh->GetOutputDataObject(0)), 0.0);

  // Another hull size rebuilds every hull; a changed muscle rebuilds that muscle's only.
  f->SetHullTargetNumberOfPoints(90);
  f->Update();
  EXPECT_EQ(f->GetHullBuildCount(), 6);
  f->SetInputDataObject(0, WithOnePointMoved(pipeline.phantom));
  f->Update();
  EXPECT_EQ(f->GetHullBuildCount(), 7);
  EXPECT_NE(
    vtkPolyData::SafeDownCast(vtkMultiBlockDataSet::SafeDownCast(f->GetOutputDataObject(0))->GetBlock(1)), nullptr);
}

namespace
{
/// Points of the blocks of `muscles` inside the blocks of `bones` (closed surfaces).
std::int64_t PointsInside(vtkDataObject* muscles, vtkDataObject* bones)
{
  std::vector<md::TriangleTree> trees;
  auto* boneTree = vtkMultiBlockDataSet::SafeDownCast(bones);
  for (unsigned int k = 0; k < boneTree->GetNumberOfBlocks(); ++k)
  {
    md::TriangleMesh mesh;
    mdvtk::ReadTriangles(vtkPolyData::SafeDownCast(boneTree->GetBlock(k)), mesh);
    trees.emplace_back(mesh);
  }
  std::int64_t inside = 0;
  auto* muscleTree = vtkMultiBlockDataSet::SafeDownCast(muscles);
  for (unsigned int k = 0; k < muscleTree->GetNumberOfBlocks(); ++k)
  {
    const md::Points points = mdvtk::ToPoints(vtkPolyData::SafeDownCast(muscleTree->GetBlock(k))->GetPoints());
    for (const md::TriangleTree& tree : trees)
    {
      inside += md::CountInsideTree(tree, points);
    }
  }
  return inside;
}

/// A copy of `input` (a multiblock of polydata) with every coordinate moved by up to 1e-7 of
/// itself, a function of the value (equal coordinates stay equal).
vtkSmartPointer<vtkMultiBlockDataSet> Rounded(vtkDataObject* input, int seed)
{
  auto copy = vtkSmartPointer<vtkMultiBlockDataSet>::New();
  copy->DeepCopy(input);
  for (unsigned int k = 0; k < copy->GetNumberOfBlocks(); ++k)
  {
    vtkPoints* points = vtkPolyData::SafeDownCast(copy->GetBlock(k))->GetPoints();
    for (vtkIdType i = 0; i < points->GetNumberOfPoints(); ++i)
    {
      double p[3];
      points->GetPoint(i, p);
      for (double& x : p)
      {
        std::seed_seq sequence{ static_cast<int>(std::hash<double>{}(x)), seed };
        std::mt19937 random(sequence);
        x *= 1 + 1e-7 * std::uniform_real_distribution<double>(-1.0, 1.0)(random);
      }
      points->SetPoint(i, p);
    }
  }
  return copy;
}
}

TEST(MuscleDeformationFilter, OnTheSurfaceTheAnswerIsTheMusclesNotTheHulls)
{
  // DeformationMesh Muscle surface: one settle from the rest pose on the muscles' own surfaces.
  // No hull is built or used, the hull's size is no part of the answer, the energies are kept
  // across poses, and no point ends inside a bone, where the paper's pass leaves the rectus
  // femoris's points that the femur swept over.
  PhantomPipeline pipeline;
  vtkNew<vtkMuscleDeformation> onHull;
  pipeline.Connect(onHull);
  onHull->Update();
  vtkNew<vtkMuscleDeformation> f;
  pipeline.Connect(f);
  f->SetDeformationMesh(vtkMuscleDeformation::MUSCLE_SURFACE);
  {
    CapturedMessages messages;
    f->Update();
    EXPECT_FALSE(messages.Contains("ERROR")) << messages.Text();
    EXPECT_TRUE(messages.Contains("an action line of muscle 'RectusFemoris' crosses bone 'Femur'")) << messages.Text();
  }
  EXPECT_EQ(f->GetHullBuildCount(), 0);
  EXPECT_EQ(f->GetSurfaceEnergyBuildCount(), 3);
  vtkDataObject* bones = pipeline.phantom->GetOutputDataObject(vtkMusculoskeletalPhantom::BONES_CURRENT);
  EXPECT_GT(PointsInside(onHull->GetOutputDataObject(0), bones), 0); // the case is not trivial
  EXPECT_EQ(PointsInside(f->GetOutputDataObject(0), bones), 0);
  auto* tree = vtkMultiBlockDataSet::SafeDownCast(f->GetOutputDataObject(0));
  for (unsigned int k = 0; k < tree->GetNumberOfBlocks(); ++k)
  {
    SCOPED_TRACE(BlockName(tree, k));
    vtkFieldData* field = vtkPolyData::SafeDownCast(tree->GetBlock(k))->GetFieldData();
    EXPECT_EQ(field->GetArray("Converged")->GetTuple1(0), 1.0);
    EXPECT_LT(std::abs(field->GetArray("VolumeChangePercent")->GetTuple1(0)), 1e-6);
    EXPECT_EQ(field->GetArray("FlippedTriangleCount")->GetTuple1(0), 0.0);
    EXPECT_NE(field->GetArray("PointsInContact"), nullptr);
    EXPECT_EQ(field->GetArray("PointsFrozenInObstacles"), nullptr); // the hull's own measure
  }
  auto exact = vtkSmartPointer<vtkMultiBlockDataSet>::New();
  exact->DeepCopy(f->GetOutputDataObject(0));

  // Another hull size, or a hull given: the same answer, and the given hull is said to be unused.
  f->SetHullTargetNumberOfPoints(60);
  f->Update();
  EXPECT_EQ(LargestDifference(exact, f->GetOutputDataObject(0)), 0.0);
  vtkNew<vtkHullDecimation> hulls;
  hulls->SetInputConnection(pipeline.phantom->GetOutputPort(vtkMusculoskeletalPhantom::MUSCLES));
  hulls->SetTargetNumberOfPoints(100);
  f->SetInputConnection(3, hulls->GetOutputPort());
  {
    CapturedMessages messages;
    f->Update();
    EXPECT_TRUE(messages.Contains("the Hull input is not used")) << messages.Text();
  }
  EXPECT_EQ(LargestDifference(exact, f->GetOutputDataObject(0)), 0.0);
  f->SetInputConnection(3, nullptr);

  // Rounding noise of the muscles (1e-7 of each coordinate) moves the answer continuously
  // (measured on the phantom at its default resolution: 1e-4 mm; the paper's pass: 3-5 mm).
  vtkNew<vtkMuscleDeformation> rounded;
  pipeline.Connect(rounded);
  rounded->SetDeformationMesh(vtkMuscleDeformation::MUSCLE_SURFACE);
  rounded->SetInputDataObject(0, Rounded(pipeline.phantom->GetOutputDataObject(vtkMusculoskeletalPhantom::MUSCLES), 1));
  rounded->Update();
  EXPECT_LT(LargestDifference(exact, rounded->GetOutputDataObject(0)), 1e-3);

  // Settings that do not touch the energy keep it (the hull's size above, the pass's iterations
  // here); a new pose keeps those of the muscles whose matched rest-pose lines it leaves alone
  // (ActionLineMatching puts points into the rest-pose lines where the current ones have them),
  // and a changed muscle builds its own again.
  EXPECT_EQ(f->GetSurfaceEnergyBuildCount(), 3);
  f->SetMaximumNumberOfIterations(50);
  f->Update();
  EXPECT_EQ(f->GetSurfaceEnergyBuildCount(), 3);
  pipeline.phantom->SetFlexion(20);
  f->Update();
  const int afterNewPose = f->GetSurfaceEnergyBuildCount();
  EXPECT_LT(afterNewPose, 6);
  EXPECT_GT(LargestDifference(exact, f->GetOutputDataObject(0)), 1.0);
  f->SetInputDataObject(0, WithOnePointMoved(pipeline.phantom));
  f->Update();
  EXPECT_EQ(f->GetSurfaceEnergyBuildCount(), afterNewPose + 1);
}

TEST(InterpolatedMuscleDeformationFilter, RestHullsAreKeptAcrossSettingsThatDoNotTouchThem)
{
  // Every property change recomputed everything, hulls included; the rest-pose hulls and
  // mappings depend on the rest-pose muscles and the hull size only.
  PhantomPipeline pipeline;
  vtkNew<vtkInterpolatedMuscleDeformation> f;
  pipeline.Connect(f);
  f->SetNumberOfSteps(2);
  f->SetDeformationMesh(vtkInterpolatedMuscleDeformation::MUSCLE_SURFACE);
  f->Update();
  ASSERT_EQ(f->GetHullBuildCount(), 0); // solved on the muscles' surfaces: no hull at all
  ASSERT_EQ(f->GetSurfaceEnergyBuildCount(), 3);
  // Their energies are kept as the hulls are, and give what a new filter builds for itself. (A
  // new current pose can change the matched rest lines, points inserted by the matching, and
  // with them the energy.)
  f->SetNumberOfSteps(3);
  f->Update();
  f->SetDeformableShare(0.5);
  f->Update();
  EXPECT_EQ(f->GetSurfaceEnergyBuildCount(), 3);
  {
    vtkNew<vtkInterpolatedMuscleDeformation> fresh;
    pipeline.Connect(fresh);
    fresh->SetNumberOfSteps(3);
    fresh->SetDeformableShare(0.5);
    fresh->SetDeformationMesh(vtkInterpolatedMuscleDeformation::MUSCLE_SURFACE);
    f->UpdateTimeStep(3);
    fresh->UpdateTimeStep(3);
    EXPECT_EQ(LargestDifference(f->GetOutputDataObject(0), fresh->GetOutputDataObject(0)), 0.0);
  }
  f->SetDeformableShare(0.6);
  f->SetNumberOfSteps(2);
  f->SetDeformationMesh(vtkInterpolatedMuscleDeformation::HULL);
  f->Update();
  ASSERT_EQ(f->GetHullBuildCount(), 3); // one per muscle

  // Other steps, weights, a new current pose and the other hull mode: the same rest hulls.
  f->SetNumberOfSteps(3);
  f->Update();
  f->SetBoneContactWeight(0.25);
  f->SetConvergenceTolerance(0.005);
  f->Update();
  pipeline.phantom->SetFlexion(20); // moves the current pose only
  f->Update();
  f->SetHullMode(vtkInterpolatedMuscleDeformation::REBUILD);
  f->Update();
  f->SetHullMode(vtkInterpolatedMuscleDeformation::REFIT);
  f->Update();
  EXPECT_EQ(f->GetHullBuildCount(), 3);

  // Kept hulls give exactly what a new filter builds for itself, at every step.
  vtkNew<vtkInterpolatedMuscleDeformation> fresh;
  pipeline.Connect(fresh);
  fresh->SetDeformationMesh(vtkInterpolatedMuscleDeformation::HULL);
  fresh->SetNumberOfSteps(3);
  fresh->SetBoneContactWeight(0.25);
  fresh->SetConvergenceTolerance(0.005);
  for (double step : { 1.0, 3.0 })
  {
    f->UpdateTimeStep(step);
    fresh->UpdateTimeStep(step);
    EXPECT_EQ(LargestDifference(f->GetOutputDataObject(0), fresh->GetOutputDataObject(0)), 0.0) << "step " << step;
  }

  // Another hull size rebuilds every hull.
  f->SetHullTargetNumberOfPoints(90);
  f->Update();
  EXPECT_EQ(f->GetHullBuildCount(), 6);
}

/// Every progress value `f` reports in one update, in order.
std::vector<double> ProgressOfOneUpdate(vtkAlgorithm* f)
{
  std::vector<double> seen;
  vtkNew<vtkCallbackCommand> record;
  record->SetClientData(&seen);
  record->SetCallback([](vtkObject*, unsigned long, void* clientData, void* callData) {
    static_cast<std::vector<double>*>(clientData)->push_back(*static_cast<double*>(callData));
  });
  const unsigned long observer = f->AddObserver(vtkCommand::ProgressEvent, record);
  f->Modified();
  f->Update();
  f->RemoveObserver(observer);
  return seen;
}

TEST(MuscleDeformationFilter, ProgressNeverGoesBackWithinARun)
{
  // The GUI's progress bar once jumped from 89 % back to 6 % within a filter's run.
  PhantomPipeline pipeline;
  vtkNew<vtkMuscleDeformation> pass;
  pipeline.Connect(pass);
  vtkNew<vtkInterpolatedMuscleDeformation> method; // solved on the muscles' surfaces
  pipeline.Connect(method);
  method->SetNumberOfSteps(2);
  method->SetDeformationMesh(vtkInterpolatedMuscleDeformation::MUSCLE_SURFACE);
  vtkNew<vtkInterpolatedMuscleDeformation> onHulls;
  pipeline.Connect(onHulls);
  onHulls->SetNumberOfSteps(2);
  onHulls->SetHullMode(vtkInterpolatedMuscleDeformation::REBUILD); // hulls inside the steps too
  for (vtkAlgorithm* f :
    { static_cast<vtkAlgorithm*>(pass), static_cast<vtkAlgorithm*>(method), static_cast<vtkAlgorithm*>(onHulls) })
  {
    const std::vector<double> seen = ProgressOfOneUpdate(f);
    ASSERT_GT(seen.size(), 10u) << f->GetClassName();
    for (size_t i = 1; i < seen.size(); ++i)
    {
      // The executive reports 0 when a run starts (RequestData of an output's time step).
      if (seen[i] != 0.0)
      {
        EXPECT_GE(seen[i], seen[i - 1]) << f->GetClassName() << ", report " << i;
      }
    }
    EXPECT_EQ(seen.back(), 1.0) << f->GetClassName();
  }
}

TEST(InterpolatedMuscleDeformationFilter, SaysSoWhenANewNumberOfStepsChangesWhatTheTimeShows)
{
  // Time j is step j of N. The view stayed on time 2 after N went from 4 to 8, now a quarter of
  // the motion instead of half, and nothing said so.
  PhantomPipeline pipeline;
  vtkNew<vtkInterpolatedMuscleDeformation> f;
  pipeline.Connect(f);
  f->SetNumberOfSteps(4);
  f->UpdateTimeStep(2);
  f->SetNumberOfSteps(8);
  {
    CapturedMessages messages;
    f->UpdateTimeStep(2);
    EXPECT_TRUE(messages.Contains("time 2 shows step 2 of 8 (25 % of the motion), where it showed step 2 of 4 (50 %)"))
      << messages.Text();
  }
  {
    CapturedMessages messages; // a new time, or the same N: nothing to say
    f->UpdateTimeStep(4);
    f->UpdateTimeStep(2);
    EXPECT_FALSE(messages.Contains("NumberOfSteps is now")) << messages.Text();
  }
}

TEST(MuscleDeformationFilter, AbortStopsTheRunWithAnEmptyOutputAndTheNextRunWorks)
{
  // ParaView's cancel sets the filter's AbortExecute; here an observer does it once the
  // deformation has started (progress past the hulls).
  PhantomPipeline pipeline;
  vtkNew<vtkMuscleDeformation> f;
  pipeline.Connect(f);
  ExpectAbortStopsCleanly(f, 0.35); // past the hulls: the pass then reports progress ~40 times
  f->SetDeformationMesh(vtkMuscleDeformation::MUSCLE_SURFACE);
  ExpectAbortStopsCleanly(f, 0.301); // in the settle: its iterations are the only reports past 0.3
}

TEST(MuscleDeformationFilter, AbortStopsTheWholeMethodToo)
{
  PhantomPipeline pipeline;
  vtkNew<vtkInterpolatedMuscleDeformation> f;
  pipeline.Connect(f);
  f->SetNumberOfSteps(3);
  ExpectAbortStopsCleanly(f, 0.201); // in the first step's settle: its iterations are the only reports past 0.2
  f->SetDeformationMesh(vtkInterpolatedMuscleDeformation::HULL);
  ExpectAbortStopsCleanly(f, 0.4); // in the first step (0.2-0.47 of the run at N = 3)
}

TEST(InterpolatedMuscleDeformationFilter, OutputsTheBonesAndActionLinesOfTheSameStep)
{
  // Seeing the bones at a step took a separate BoneInterpolation kept at the same N by hand;
  // with another N the femur appeared to cut through the muscle. Outputs 1 and 2 now show the
  // bones and the action lines of the step the muscles are at.
  PhantomPipeline pipeline;
  vtkNew<vtkInterpolatedMuscleDeformation> f;
  pipeline.Connect(f);
  f->SetNumberOfSteps(2);
  vtkNew<vtkBoneInterpolation> bones;
  bones->SetInputConnection(0, pipeline.phantom->GetOutputPort(vtkMusculoskeletalPhantom::BONES_REST));
  bones->SetInputConnection(1, pipeline.phantom->GetOutputPort(vtkMusculoskeletalPhantom::BONES_CURRENT));
  bones->SetNumberOfSteps(2);
  for (int step = 0; step <= 2; ++step)
  {
    SCOPED_TRACE(step);
    f->UpdateInformation();
    for (int port = 0; port < 3; ++port)
    {
      f->GetOutputInformation(port)->Set(vtkStreamingDemandDrivenPipeline::UPDATE_TIME_STEP(), step);
      f->Update(port);
    }
    bones->UpdateTimeStep(step);
    EXPECT_LT(LargestDifference(f->GetOutputDataObject(1), bones->GetOutputDataObject(0)), 1e-9);
    auto* lines = vtkMultiBlockDataSet::SafeDownCast(f->GetOutputDataObject(2));
    ASSERT_NE(lines, nullptr);
    ASSERT_EQ(lines->GetNumberOfBlocks(), 3u);
    EXPECT_GT(vtkPolyData::SafeDownCast(lines->GetBlock(0))->GetNumberOfLines(), 0);
    for (int port = 0; port < 3; ++port)
    {
      EXPECT_EQ(f->GetOutputDataObject(port)->GetInformation()->Get(vtkDataObject::DATA_TIME_STEP()), step);
    }
  }
  // At the last step: the bones in the current pose and the lines at their current positions.
  EXPECT_EQ(LargestDifference(f->GetOutputDataObject(1),
              pipeline.phantom->GetOutputDataObject(vtkMusculoskeletalPhantom::BONES_CURRENT)),
    0.0);
  pipeline.matching->Update();
  EXPECT_LT(LargestDifference(f->GetOutputDataObject(2), pipeline.matching->GetOutputDataObject(1)), 1e-9);

  // Output 3: the per-muscle measures of the step as a table, the same as the field data.
  auto* table = vtkTable::SafeDownCast(f->GetOutputDataObject(3));
  ASSERT_NE(table, nullptr);
  auto* muscles = vtkMultiBlockDataSet::SafeDownCast(f->GetOutputDataObject(0));
  ASSERT_EQ(table->GetNumberOfRows(), static_cast<vtkIdType>(muscles->GetNumberOfBlocks()));
  for (unsigned int b = 0; b < muscles->GetNumberOfBlocks(); ++b)
  {
    EXPECT_EQ(table->GetValueByName(b, "Muscle").ToString(), BlockName(muscles, b));
    for (const char* name : { "VolumeChangePercent", "MaxStaticShift", "FlippedTriangleCount", "InterpolationStep" })
    {
      EXPECT_EQ(table->GetValueByName(b, name).ToDouble(),
        vtkPolyData::SafeDownCast(muscles->GetBlock(b))->GetFieldData()->GetArray(name)->GetTuple1(0))
        << name;
    }
  }
}

namespace
{
/// The phantom's muscles with muscle `broken` opened (its last triangle taken away, or with
/// `keep` 0 all of them): no hull can enclose it.
vtkSmartPointer<vtkMultiBlockDataSet> MusclesWithAHole(
  vtkMusculoskeletalPhantom* phantom, unsigned int broken, vtkIdType keep = -1)
{
  phantom->Update();
  auto muscles = vtkSmartPointer<vtkMultiBlockDataSet>::New();
  muscles->DeepCopy(phantom->GetOutputDataObject(vtkMusculoskeletalPhantom::MUSCLES));
  auto* block = vtkPolyData::SafeDownCast(muscles->GetBlock(broken));
  vtkNew<vtkCellArray> polys;
  keep = keep < 0 ? block->GetNumberOfPolys() - 1 : keep;
  for (vtkIdType c = 0; c < keep; ++c)
  {
    vtkNew<vtkIdList> ids;
    block->GetCellPoints(c, ids);
    polys->InsertNextCell(ids);
  }
  block->SetPolys(polys);
  return muscles;
}

/// Every muscle computed but `broken`, which is an empty block flagged with why.
void ExpectOnlyTheBrokenMuscleFailed(
  vtkDataObject* output, unsigned int broken, CapturedMessages& messages, const std::string& why = "open")
{
  auto* tree = vtkMultiBlockDataSet::SafeDownCast(output);
  ASSERT_NE(tree, nullptr);
  ASSERT_EQ(tree->GetNumberOfBlocks(), 3u);
  const std::string name = BlockName(tree, broken);
  EXPECT_TRUE(messages.Contains("ERROR")) << messages.Text();
  EXPECT_TRUE(messages.Contains(name)) << messages.Text();
  EXPECT_TRUE(messages.Contains(why)) << messages.Text();
  for (unsigned int k = 0; k < 3; ++k)
  {
    SCOPED_TRACE(BlockName(tree, k));
    auto* block = vtkPolyData::SafeDownCast(tree->GetBlock(k));
    ASSERT_NE(block, nullptr);
    vtkDataArray* failed = block->GetFieldData()->GetArray("DeformationFailed");
    if (k != broken)
    {
      EXPECT_GT(block->GetNumberOfPoints(), 0);
      EXPECT_EQ(failed, nullptr);
      continue;
    }
    EXPECT_EQ(block->GetNumberOfPoints(), 0);
    ASSERT_NE(failed, nullptr);
    EXPECT_EQ(failed->GetTuple1(0), 1.0);
    auto* message = vtkStringArray::SafeDownCast(block->GetFieldData()->GetAbstractArray("FailureMessage"));
    ASSERT_NE(message, nullptr);
    EXPECT_NE(message->GetValue(0).find(why), std::string::npos) << message->GetValue(0);
  }
}
}

// Output 4: each muscle's fibres at the step shown, inside their muscle at every step (the
// winding number), their lengths as cell data; none asked for, none made and the muscles alike.
TEST(InterpolatedMuscleDeformationFilter, FibresRunInsideEachMuscleAtEveryStepWithTheirLengths)
{
  PhantomPipeline pipeline;
  vtkNew<vtkInterpolatedMuscleDeformation> f;
  pipeline.Connect(f);
  f->SetNumberOfSteps(2);
  f->SetNumberOfFibres(30);
  std::vector<double> restLengths;
  for (int step = 0; step <= 2; ++step)
  {
    SCOPED_TRACE(step);
    f->UpdateInformation();
    for (int port : { 0, 4 })
    {
      f->GetOutputInformation(port)->Set(vtkStreamingDemandDrivenPipeline::UPDATE_TIME_STEP(), step);
      f->Update(port);
    }
    auto* muscles = vtkMultiBlockDataSet::SafeDownCast(f->GetOutputDataObject(0));
    auto* fibres = vtkMultiBlockDataSet::SafeDownCast(f->GetOutputDataObject(4));
    ExpectFibresInsideTheirMuscles(fibres, muscles, 30, "step " + std::to_string(step));
    if (step == 0)
    {
      for (unsigned int b = 0; b < fibres->GetNumberOfBlocks(); ++b)
      {
        vtkDataArray* lengths = vtkPolyData::SafeDownCast(fibres->GetBlock(b))->GetCellData()->GetArray("FibreLength");
        for (vtkIdType c = 0; c < lengths->GetNumberOfTuples(); ++c)
        {
          restLengths.push_back(lengths->GetTuple1(c));
        }
      }
    }
    if (step == 2)
    {
      // The phantom's motion changes its fibres' lengths.
      double largestChange = 0;
      vtkIdType i = 0;
      for (unsigned int b = 0; b < fibres->GetNumberOfBlocks(); ++b)
      {
        vtkDataArray* lengths = vtkPolyData::SafeDownCast(fibres->GetBlock(b))->GetCellData()->GetArray("FibreLength");
        for (vtkIdType c = 0; c < lengths->GetNumberOfTuples(); ++c, ++i)
        {
          largestChange = std::max(largestChange, std::abs(lengths->GetTuple1(c) - restLengths[size_t(i)]));
        }
      }
      EXPECT_GT(largestChange, 0.01);
    }
  }
  // Another number of steps or deformation setting keeps the fibres made (seconds on real
  // muscles); they carry as a new filter's do.
  auto updateAt = [](vtkInterpolatedMuscleDeformation* filter, int port, double step) {
    filter->UpdateInformation();
    filter->GetOutputInformation(port)->Set(vtkStreamingDemandDrivenPipeline::UPDATE_TIME_STEP(), step);
    filter->Update(port);
  };
  EXPECT_EQ(f->GetFibreBuildCount(), 1);
  f->SetNumberOfSteps(3);
  f->SetBoneContactWeight(0.25);
  updateAt(f, 4, 2.0);
  EXPECT_EQ(f->GetFibreBuildCount(), 1);
  {
    vtkNew<vtkInterpolatedMuscleDeformation> fresh;
    pipeline.Connect(fresh);
    fresh->SetNumberOfSteps(3);
    fresh->SetBoneContactWeight(0.25);
    fresh->SetNumberOfFibres(30);
    updateAt(fresh, 4, 2.0);
    EXPECT_EQ(LargestDifference(f->GetOutputDataObject(4), fresh->GetOutputDataObject(4)), 0.0);
  }
  f->SetNumberOfSteps(2);
  f->SetBoneContactWeight(0.5);
  updateAt(f, 0, 2.0);
  EXPECT_EQ(f->GetFibreBuildCount(), 1);

  vtkNew<vtkPoints> with;
  with->SetDataTypeToDouble();
  with->DeepCopy(
    vtkPolyData::SafeDownCast(vtkMultiBlockDataSet::SafeDownCast(f->GetOutputDataObject(0))->GetBlock(0))->GetPoints());
  f->SetNumberOfFibres(0);
  f->Update(0);
  EXPECT_EQ(vtkMultiBlockDataSet::SafeDownCast(f->GetOutputDataObject(4))->GetNumberOfBlocks(), 0u);
  vtkPoints* without =
    vtkPolyData::SafeDownCast(vtkMultiBlockDataSet::SafeDownCast(f->GetOutputDataObject(0))->GetBlock(0))->GetPoints();
  ASSERT_EQ(without->GetNumberOfPoints(), with->GetNumberOfPoints());
  double largest = 0;
  for (vtkIdType i = 0; i < with->GetNumberOfPoints(); ++i)
  {
    double a[3], b[3];
    with->GetPoint(i, a);
    without->GetPoint(i, b);
    largest = std::max({ largest, std::abs(a[0] - b[0]), std::abs(a[1] - b[1]), std::abs(a[2] - b[2]) });
  }
  EXPECT_EQ(largest, 0.0);
}

// One muscle no hull can be built for is reported by name and flagged in its block; the other
// muscles of the input are computed, by every filter that takes muscles.
TEST(MuscleFilters, OneBadMuscleDoesNotTakeTheOthersDown)
{
  PhantomPipeline pipeline;
  const unsigned int broken = 1;
  vtkSmartPointer<vtkMultiBlockDataSet> muscles = MusclesWithAHole(pipeline.phantom, broken);
  {
    vtkNew<vtkHullDecimation> f;
    f->SetInputDataObject(0, muscles);
    f->SetTargetNumberOfPoints(100);
    CapturedMessages messages;
    f->Update();
    ExpectOnlyTheBrokenMuscleFailed(f->GetOutputDataObject(0), broken, messages);
  }
  for (int mesh : { vtkMuscleDeformation::HULL, vtkMuscleDeformation::MUSCLE_SURFACE })
  {
    SCOPED_TRACE(mesh == vtkMuscleDeformation::HULL ? "one pass on the hull" : "one pass on the surface");
    vtkNew<vtkMuscleDeformation> f;
    pipeline.Connect(f);
    f->SetDeformationMesh(mesh);
    f->SetInputDataObject(0, muscles);
    CapturedMessages messages;
    f->Update();
    ExpectOnlyTheBrokenMuscleFailed(f->GetOutputDataObject(0), broken, messages);
  }
  {
    vtkNew<vtkInterpolatedMuscleDeformation> f;
    pipeline.Connect(f);
    f->SetInputDataObject(0, muscles);
    f->SetNumberOfSteps(2);
    CapturedMessages messages;
    f->Update();
    ExpectOnlyTheBrokenMuscleFailed(f->GetOutputDataObject(0), broken, messages);
    // The measures table has every muscle's row: the failed one's NaN, and flagged.
    vtkTable* table = vtkTable::SafeDownCast(f->GetOutputDataObject(3));
    ASSERT_EQ(table->GetNumberOfRows(), 3);
    vtkAbstractArray* flag = table->GetColumnByName("DeformationFailed");
    vtkAbstractArray* volume = table->GetColumnByName("VolumeChangePercent");
    ASSERT_NE(flag, nullptr);
    ASSERT_NE(volume, nullptr);
    for (vtkIdType row = 0; row < 3; ++row)
    {
      EXPECT_EQ(flag->GetVariantValue(row).ToDouble(), row == broken ? 1.0 : 0.0);
      EXPECT_EQ(std::isnan(volume->GetVariantValue(row).ToDouble()), row == broken);
    }
  }
  {
    vtkNew<vtkIntersectionResolve> f; // a surface with a hole can be resolved; one of no triangles not
    f->SetInputDataObject(0, MusclesWithAHole(pipeline.phantom, broken, 0));
    f->AddInputConnection(1, pipeline.phantom->GetOutputPort(vtkMusculoskeletalPhantom::BONES_CURRENT));
    CapturedMessages messages;
    f->Update();
    ExpectOnlyTheBrokenMuscleFailed(f->GetOutputDataObject(0), broken, messages, "no triangles");
  }
}
