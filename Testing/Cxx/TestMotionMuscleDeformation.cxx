// SPDX-License-Identifier: BSD-3-Clause
// MotionMuscleDeformation as a pipeline drives it, data-free: the phantom's bones and action
// lines made time-varying by BoneInterpolation (times 0 ... N, the rest pose to 30 degrees of
// flexion), every frame deformed from the one before.
#include "FilterTestUtilities.h"
#include "Geometry/MeshChecks.h"
#include "MDConvert.h"

#include "vtkBoneInterpolation.h"
#include "vtkMotionMuscleDeformation.h"
#include "vtkMusculoskeletalPhantom.h"
#include "vtkPathsOverBones.h"

#include <vtkCallbackCommand.h>
#include <vtkCellData.h>
#include <vtkCommand.h>
#include <vtkDataArray.h>
#include <vtkFieldData.h>
#include <vtkInformationVector.h>
#include <vtkObjectFactory.h>
#include <vtkPassInputTypeAlgorithm.h>
#include <vtkPointData.h>
#include <vtkStreamingDemandDrivenPipeline.h>
#include <vtkTable.h>

#include <gtest/gtest.h>

#include <cmath>

namespace
{
using SDDP = vtkStreamingDemandDrivenPipeline;

/// A time-varying copy of its input at the given times; from `dropFrom` on (a time), its
/// polydata gain a point: bad input to test.
class TimedCopy : public vtkPassInputTypeAlgorithm
{
public:
  static TimedCopy* New();
  vtkTypeMacro(TimedCopy, vtkPassInputTypeAlgorithm);
  std::vector<double> Times{ 0.0, 1.0 };
  double DropFrom = 1e300;

protected:
  int RequestInformation(vtkInformation*, vtkInformationVector**, vtkInformationVector* out) override
  {
    vtkInformation* info = out->GetInformationObject(0);
    info->Set(SDDP::TIME_STEPS(), this->Times.data(), static_cast<int>(this->Times.size()));
    const double range[2] = { this->Times.front(), this->Times.back() };
    info->Set(SDDP::TIME_RANGE(), range, 2);
    return 1;
  }
  int RequestData(vtkInformation*, vtkInformationVector** in, vtkInformationVector* out) override
  {
    vtkInformation* info = out->GetInformationObject(0);
    const double time = info->Has(SDDP::UPDATE_TIME_STEP()) ? info->Get(SDDP::UPDATE_TIME_STEP()) : 0.0;
    vtkDataObject* output = vtkDataObject::GetData(out, 0);
    output->DeepCopy(vtkDataObject::GetData(in[0], 0));
    if (time >= this->DropFrom)
    {
      auto* tree = vtkMultiBlockDataSet::SafeDownCast(output);
      for (unsigned int b = 0; tree && b < tree->GetNumberOfBlocks(); ++b)
      {
        if (auto* poly = vtkPolyData::SafeDownCast(tree->GetBlock(b)))
        {
          poly->GetPoints()->InsertNextPoint(0.0, 0.0, 0.0);
        }
      }
    }
    output->GetInformation()->Set(vtkDataObject::DATA_TIME_STEP(), time);
    return 1;
  }
};
vtkStandardNewMacro(TimedCopy);

/// The phantom carried from the rest pose to `flexion` degrees in `frames` + 1 frames.
struct PhantomMotionPipeline
{
  vtkNew<vtkMusculoskeletalPhantom> phantom;
  vtkNew<vtkBoneInterpolation> bones, lines;
  vtkNew<vtkMotionMuscleDeformation> motion;
  PhantomMotionPipeline(double flexion, int frames, int lineFrames = -1)
  {
    this->phantom->SetFlexion(flexion);
    this->phantom->SetResolution(16);
    this->bones->SetInputConnection(0, this->phantom->GetOutputPort(1));
    this->bones->SetInputConnection(1, this->phantom->GetOutputPort(2));
    this->bones->SetNumberOfSteps(frames);
    this->lines->SetInputConnection(0, this->phantom->GetOutputPort(3));
    this->lines->SetInputConnection(1, this->phantom->GetOutputPort(4));
    this->lines->SetNumberOfSteps(lineFrames < 0 ? frames : lineFrames);
    this->motion->SetInputConnection(0, this->phantom->GetOutputPort(0));
    this->motion->SetBonesRestConnection(this->phantom->GetOutputPort(1));
    this->motion->SetBonesMotionConnection(this->bones->GetOutputPort());
    this->motion->SetActionLinesRestConnection(this->phantom->GetOutputPort(3));
    this->motion->SetActionLinesMotionConnection(this->lines->GetOutputPort());
  }
  int At(double time)
  {
    this->motion->UpdateInformation();
    return this->motion->UpdateTimeStep(time);
  }
  vtkPolyData* Muscle(unsigned int b)
  {
    return vtkPolyData::SafeDownCast(
      vtkMultiBlockDataSet::SafeDownCast(this->motion->GetOutputDataObject(0))->GetBlock(b));
  }
};

double Field(vtkPolyData* muscle, const char* name)
{
  vtkDataArray* array = muscle->GetFieldData()->GetArray(name);
  return array ? array->GetTuple1(0) : std::nan("");
}

double LargestDifference(vtkPoints* a, vtkPoints* b)
{
  double largest = a->GetNumberOfPoints() == b->GetNumberOfPoints() ? 0.0 : 1e300;
  for (vtkIdType i = 0; largest < 1e300 && i < a->GetNumberOfPoints(); ++i)
  {
    double pa[3], pb[3];
    a->GetPoint(i, pa);
    b->GetPoint(i, pb);
    largest = std::max(largest, std::sqrt(vtkMath::Distance2BetweenPoints(pa, pb)));
  }
  return largest;
}
}

TEST(MotionMuscleDeformation, ComputesEachFrameOnceWhicheverOrderTheyAreAskedIn)
{
  PhantomMotionPipeline p(30, 6);
  ASSERT_EQ(p.At(6), 1);
  EXPECT_EQ(p.motion->GetFramesComputed(), 7); // frames 0 ... 6, each from the one before
  vtkInformation* info = p.motion->GetOutputInformation(0);
  ASSERT_EQ(info->Length(SDDP::TIME_STEPS()), 7);
  const unsigned int muscles =
    vtkMultiBlockDataSet::SafeDownCast(p.motion->GetOutputDataObject(0))->GetNumberOfBlocks();
  ASSERT_GE(muscles, 2u);

  // Scrubbing back and forth computes nothing.
  ASSERT_EQ(p.At(2), 1);
  vtkNew<vtkPoints> atTwo;
  atTwo->SetDataTypeToDouble();
  atTwo->DeepCopy(p.Muscle(0)->GetPoints());
  EXPECT_EQ(Field(p.Muscle(0), "Frame"), 2);
  ASSERT_EQ(p.At(5), 1);
  ASSERT_EQ(p.At(0), 1);
  EXPECT_EQ(p.motion->GetFramesComputed(), 7);
  EXPECT_EQ(p.motion->GetFramesKept(), 7);

  // A frame is the same however it was reached: a new filter asked for frame 2 first.
  PhantomMotionPipeline fresh(30, 6);
  ASSERT_EQ(fresh.At(2), 1);
  EXPECT_EQ(fresh.motion->GetFramesComputed(), 3);
  EXPECT_EQ(LargestDifference(fresh.Muscle(0)->GetPoints(), atTwo), 0.0);

  // A memory limit of a few frames keeps those nearest the one shown; a frame dropped is computed
  // again, the same.
  p.motion->SetCacheMemoryLimit(1.0);
  ASSERT_EQ(p.At(6), 1);
  EXPECT_EQ(p.motion->GetFramesComputed(), 7); // a limit changes no result: frame 6 is still kept
  EXPECT_LE(p.motion->GetCacheMegabytes(), 1.0);
  EXPECT_LT(p.motion->GetFramesKept(), 7);
  ASSERT_EQ(p.At(2), 1);
  EXPECT_GT(p.motion->GetFramesComputed(), 7);
  EXPECT_EQ(LargestDifference(p.Muscle(0)->GetPoints(), atTwo), 0.0);

  // A property that changes the result starts the motion again.
  const int before = p.motion->GetFramesComputed();
  p.motion->SetMaximumStepDisplacement(5.0);
  ASSERT_EQ(p.At(1), 1);
  EXPECT_EQ(p.motion->GetFramesComputed(), before + 2);
}

TEST(MotionMuscleDeformation, EveryFrameHoldsTheVolumeStaysOutOfTheBonesAndMovesSmoothly)
{
  PhantomMotionPipeline p(30, 6);
  ASSERT_EQ(p.At(6), 1);
  vtkTable* table = vtkTable::SafeDownCast(p.motion->GetOutputDataObject(3));
  ASSERT_NE(table, nullptr);
  ASSERT_EQ(table->GetNumberOfRows(), 7); // a row per frame computed
  ASSERT_NE(table->GetColumnByName("Time"), nullptr);
  const unsigned int muscles =
    vtkMultiBlockDataSet::SafeDownCast(p.motion->GetOutputDataObject(0))->GetNumberOfBlocks();
  for (unsigned int b = 0; b < muscles; ++b)
  {
    const std::string name = BlockName(vtkMultiBlockDataSet::SafeDownCast(p.motion->GetOutputDataObject(0)), b);
    auto column = [&](const std::string& measure) {
      vtkAbstractArray* array = table->GetColumnByName((measure + " (" + name + ")").c_str());
      EXPECT_NE(array, nullptr) << measure << " of " << name;
      return vtkDataArray::SafeDownCast(array);
    };
    vtkDataArray* volume = column("VolumeChangePercent");
    vtkDataArray* depth = column("MaxNewBonePenetrationDepth");
    vtkDataArray* converged = column("Converged");
    vtkDataArray* ratio = column("SmoothnessRatio");
    ASSERT_TRUE(volume && depth && converged && ratio);
    for (vtkIdType k = 0; k < table->GetNumberOfRows(); ++k)
    {
      EXPECT_LT(std::abs(volume->GetTuple1(k)), 1e-4) << name << " frame " << k;
      EXPECT_EQ(depth->GetTuple1(k), 0.0) << name << " frame " << k;
      EXPECT_EQ(converged->GetTuple1(k), 1.0) << name << " frame " << k;
      if (k < 2)
      {
        EXPECT_TRUE(std::isnan(ratio->GetTuple1(k))); // needs three frames
      }
      else
      {
        // Measured 0.0-1.5 (docs/DESIGN.md section 8): no pop.
        EXPECT_LE(ratio->GetTuple1(k), 3.0) << name << " frame " << k;
      }
    }
  }
  // The bones and action lines shown are those of the frame.
  vtkNew<vtkBoneInterpolation> reference;
  reference->SetInputConnection(0, p.phantom->GetOutputPort(1));
  reference->SetInputConnection(1, p.phantom->GetOutputPort(2));
  reference->SetNumberOfSteps(6);
  reference->UpdateTimeStep(6);
  auto block = [](vtkDataObject* data, unsigned int b) {
    return vtkPolyData::SafeDownCast(vtkMultiBlockDataSet::SafeDownCast(data)->GetBlock(b));
  };
  EXPECT_EQ(LargestDifference(block(p.motion->GetOutputDataObject(1), 1)->GetPoints(),
              block(reference->GetOutputDataObject(0), 1)->GetPoints()),
    0.0);
}

TEST(MotionMuscleDeformation, BadMotionsGiveClearErrorsAndNoCrash)
{
  {
    CapturedMessages messages;
    PhantomMotionPipeline p(30, 6, 5); // the lines have other times than the bones
    EXPECT_EQ(p.At(6), 0);
    EXPECT_TRUE(messages.Contains("BonesMotion has 7 time steps")) << messages.Text();
    EXPECT_TRUE(messages.Contains("must come from the same motion")) << messages.Text();
  }
  vtkNew<vtkMusculoskeletalPhantom> phantom;
  phantom->SetResolution(16);
  phantom->SetFlexion(20);
  auto pipeline = [&](TimedCopy* bones, TimedCopy* lines, vtkMotionMuscleDeformation* motion) {
    bones->SetInputConnection(phantom->GetOutputPort(2));
    lines->SetInputConnection(phantom->GetOutputPort(4));
    motion->SetInputConnection(0, phantom->GetOutputPort(0));
    motion->SetBonesRestConnection(phantom->GetOutputPort(1));
    motion->SetBonesMotionConnection(bones->GetOutputPort());
    motion->SetActionLinesRestConnection(phantom->GetOutputPort(3));
    motion->SetActionLinesMotionConnection(lines->GetOutputPort());
    motion->UpdateInformation();
  };
  {
    CapturedMessages messages;
    vtkNew<TimedCopy> bones, lines;
    bones->Times = lines->Times = { 0.5 };
    vtkNew<vtkMotionMuscleDeformation> motion;
    pipeline(bones, lines, motion);
    EXPECT_EQ(motion->UpdateTimeStep(0.5), 0);
    EXPECT_TRUE(messages.Contains("the motion has one frame (time 0.5)")) << messages.Text();
  }
  {
    // Times that decrease: asked for 0.9, it showed the frame of time 0. Refused, naming the input.
    CapturedMessages messages;
    vtkNew<TimedCopy> bones, lines;
    bones->Times = lines->Times = { 1.0, 0.5, 0.0 };
    vtkNew<vtkMotionMuscleDeformation> motion;
    pipeline(bones, lines, motion);
    EXPECT_EQ(motion->UpdateTimeStep(0.9), 0);
    EXPECT_TRUE(messages.Contains("BonesMotion's time steps do not increase (1 then 0.5)")) << messages.Text();
    EXPECT_EQ(motion->GetFramesComputed(), 0);
  }
  {
    CapturedMessages messages;
    vtkNew<TimedCopy> bones, lines;
    bones->Times = lines->Times = { 0.0, 1.0, 2.0 };
    bones->DropFrom = 2.0; // the bones gain a point at the last frame
    vtkNew<vtkMotionMuscleDeformation> motion;
    pipeline(bones, lines, motion);
    EXPECT_EQ(motion->UpdateTimeStep(1.0), 1) << messages.Text();
    EXPECT_EQ(motion->UpdateTimeStep(2.0), 0);
    EXPECT_TRUE(messages.Contains("points at time 2")) << messages.Text();
    EXPECT_TRUE(messages.Contains("a bone must keep its points through the motion")) << messages.Text();
    EXPECT_EQ(motion->GetFramesComputed(), 2); // the frames before are kept
    EXPECT_EQ(motion->UpdateTimeStep(1.0), 1);
    EXPECT_EQ(motion->GetFramesComputed(), 2);
  }
}

TEST(MotionMuscleDeformation, ARestInputModifiedInPlaceIsReadAndCheckedAgain)
{
  // A frame checks the rest-pose inputs only when they were modified since they were checked:
  // a leaf modified in place (the multiblock holding it is not) counts, and starts the motion again.
  PhantomMotionPipeline p(30, 6);
  p.phantom->Update();
  vtkNew<vtkMultiBlockDataSet> muscles;
  muscles->DeepCopy(p.phantom->GetOutputDataObject(0));
  p.motion->SetInputData(0, muscles);
  ASSERT_EQ(p.At(2), 1);
  ASSERT_EQ(p.At(3), 1);
  EXPECT_EQ(p.motion->GetFramesComputed(), 4);
  auto* leaf = vtkPolyData::SafeDownCast(muscles->GetBlock(1));
  ASSERT_NE(leaf, nullptr);
  double kept[3];
  leaf->GetPoint(7, kept);
  leaf->GetPoints()->SetPoint(7, std::nan(""), 0.0, 0.0);
  leaf->GetPoints()->Modified();
  {
    CapturedMessages messages;
    EXPECT_EQ(p.At(4), 0);
    EXPECT_TRUE(messages.Contains("NaN or infinite coordinates (point 7)")) << messages.Text();
  }
  leaf->GetPoints()->SetPoint(7, kept);
  leaf->GetPoints()->Modified();
  ASSERT_EQ(p.At(5), 1);                           // another time: the pipeline does not see into the multiblock either
  EXPECT_EQ(p.motion->GetFramesComputed(), 4 + 6); // frames 0 ... 5 again, from the rest pose
}

TEST(MotionMuscleDeformation, AStoppedRunKeepsTheFramesDoneAndTheNextGoesOnFromThem)
{
  PhantomMotionPipeline p(30, 6);
  // ParaView's cancel sets AbortExecute; here an observer does, once the run is half through.
  vtkNew<vtkCallbackCommand> stop;
  stop->SetCallback([](vtkObject* caller, unsigned long, void*, void*) {
    auto* filter = vtkAlgorithm::SafeDownCast(caller);
    if (!filter->GetAbortExecute() && filter->GetProgress() > 0.5)
    {
      filter->SetAbortExecute(1);
    }
  });
  const unsigned long observer = p.motion->AddObserver(vtkCommand::ProgressEvent, stop);
  {
    CapturedMessages messages;
    p.At(6);
    EXPECT_FALSE(messages.Contains("ERROR")) << messages.Text();
  }
  const int done = p.motion->GetFramesComputed();
  EXPECT_GE(done, 2);
  EXPECT_LT(done, 7);
  EXPECT_EQ(p.motion->GetFramesKept(), done);
  EXPECT_EQ(vtkCompositeDataSet::SafeDownCast(p.motion->GetOutputDataObject(0))->GetNumberOfPoints(), 0);
  p.motion->RemoveObserver(observer);
  p.motion->SetAbortExecute(0);
  p.motion->Modified();
  ASSERT_EQ(p.At(6), 1);
  EXPECT_EQ(p.motion->GetFramesComputed(), 7); // the frames kept are not computed again
  EXPECT_GT(vtkCompositeDataSet::SafeDownCast(p.motion->GetOutputDataObject(0))->GetNumberOfPoints(), 0);
}

TEST(MotionMuscleDeformation, FramesComputedAgainAfterTheCacheDroppedThemKeepTheirSmoothness)
{
  // A small CacheMemoryLimit, the motion played to its end, then scrubbed back: the frames
  // computed again had NaN SecondDifference and SmoothnessRatio where the two frames before them
  // had been dropped too.
  PhantomMotionPipeline whole(30, 12), scrubbed(30, 12);
  ASSERT_EQ(whole.At(12), 1);
  const double frameMegabytes = whole.motion->GetCacheMegabytes() / whole.motion->GetFramesKept();
  scrubbed.motion->SetCacheMemoryLimit(std::max(1.0, 3.5 * frameMegabytes));
  ASSERT_EQ(scrubbed.At(12), 1);
  ASSERT_LT(scrubbed.motion->GetFramesKept(), 13) << "the cache dropped nothing: the test would test nothing";
  for (int frame : { 9, 6, 4, 10 })
  {
    ASSERT_EQ(whole.At(frame), 1);
    ASSERT_EQ(scrubbed.At(frame), 1);
    const unsigned int muscles =
      vtkMultiBlockDataSet::SafeDownCast(scrubbed.motion->GetOutputDataObject(0))->GetNumberOfBlocks();
    ASSERT_EQ(muscles, 3u);
    for (unsigned int b = 0; b < muscles; ++b)
    {
      for (const char* name : { "SecondDifference", "SmoothnessRatio" })
      {
        const double expected = Field(whole.Muscle(b), name);
        ASSERT_TRUE(std::isfinite(expected)) << name;
        EXPECT_EQ(Field(scrubbed.Muscle(b), name), expected) << name << " of muscle " << b << " at frame " << frame;
      }
    }
  }
  EXPECT_GT(scrubbed.motion->GetFramesComputed(), 13); // frames were computed again
}

TEST(MotionMuscleDeformation, FibresRunInsideEachMuscleAtEveryFrameWithTheirLengths)
{
  PhantomMotionPipeline p(30, 4);
  p.motion->SetNumberOfFibres(40);
  for (int k = 0; k <= 4; ++k)
  {
    ASSERT_EQ(p.At(k), 1);
    auto* muscles = vtkMultiBlockDataSet::SafeDownCast(p.motion->GetOutputDataObject(0));
    auto* fibres = vtkMultiBlockDataSet::SafeDownCast(p.motion->GetOutputDataObject(4));
    ExpectFibresInsideTheirMuscles(fibres, muscles, 40, "frame " + std::to_string(k));
  }
  // The lengths of every frame, in order; no moment arms where BonesMotion names no coordinates.
  auto* arms = vtkTable::SafeDownCast(p.motion->GetOutputDataObject(5));
  ASSERT_NE(arms, nullptr);
  EXPECT_EQ(arms->GetNumberOfRows(), 5);
  const std::string muscle = BlockName(vtkMultiBlockDataSet::SafeDownCast(p.motion->GetOutputDataObject(0)), 0);
  EXPECT_NE(arms->GetColumnByName(("FibreLength(" + muscle + ")").c_str()), nullptr);
  EXPECT_NE(arms->GetColumnByName(("FibreLengthMax(" + muscle + ")").c_str()), nullptr);
  for (vtkIdType c = 0; c < arms->GetNumberOfColumns(); ++c)
  {
    EXPECT_EQ(std::string(arms->GetColumnName(c)).find("MomentArm"), std::string::npos) << arms->GetColumnName(c);
  }
  // A setting of the deformation restarts the motion but keeps the fibres made (seconds on real
  // muscles), which then carry as a new filter's do.
  EXPECT_EQ(p.motion->GetFibreBuildCount(), 1);
  p.motion->SetMaximumStepDisplacement(15);
  ASSERT_EQ(p.At(4), 1);
  EXPECT_EQ(p.motion->GetFibreBuildCount(), 1);
  {
    PhantomMotionPipeline fresh(30, 4);
    fresh.motion->SetNumberOfFibres(40);
    fresh.motion->SetMaximumStepDisplacement(15);
    for (int k = 0; k <= 4; ++k)
    {
      ASSERT_EQ(fresh.At(k), 1);
    }
    auto* kept = vtkMultiBlockDataSet::SafeDownCast(p.motion->GetOutputDataObject(4));
    auto* made = vtkMultiBlockDataSet::SafeDownCast(fresh.motion->GetOutputDataObject(4));
    ASSERT_EQ(kept->GetNumberOfBlocks(), made->GetNumberOfBlocks());
    for (unsigned int b = 0; b < kept->GetNumberOfBlocks(); ++b)
    {
      EXPECT_EQ(LargestDifference(vtkPolyData::SafeDownCast(kept->GetBlock(b))->GetPoints(),
                  vtkPolyData::SafeDownCast(made->GetBlock(b))->GetPoints()),
        0.0)
        << "block " << b;
    }
  }
  p.motion->SetNumberOfFibres(30); // another count: made again
  ASSERT_EQ(p.At(4), 1);
  EXPECT_EQ(p.motion->GetFibreBuildCount(), 2);
  p.motion->SetNumberOfFibres(40);

  // None asked for: none made, the muscles the same to the bit.
  vtkNew<vtkPoints> with;
  with->SetDataTypeToDouble();
  with->DeepCopy(p.Muscle(0)->GetPoints());
  p.motion->SetNumberOfFibres(0);
  ASSERT_EQ(p.At(4), 1);
  EXPECT_EQ(vtkMultiBlockDataSet::SafeDownCast(p.motion->GetOutputDataObject(4))->GetNumberOfBlocks(), 0u);
  EXPECT_EQ(LargestDifference(p.Muscle(0)->GetPoints(), with), 0.0);
}

TEST(MotionMuscleDeformation, PathsKeptOverTheBonesDriveTheMusclesByTheirOwnPoints)
{
  // PathsOverBones puts 3 points between each two of a path's own and marks its own
  // (PathOwnPoint). With only a bone far away the paths are the straight ones subdivided, and the
  // muscles move exactly as the plain lines move them; over the phantom's bones, every frame holds
  // its volume and stays out of the bones.
  PhantomMotionPipeline plain(30, 6);
  ASSERT_EQ(plain.At(6), 1);
  auto far = MakeBlocks({ { "Far", vtkSmartPointer<vtkPolyData>() } });
  {
    md::TriangleMesh box;
    box.points.resize(8, 3);
    for (int i = 0; i < 8; ++i)
    {
      box.points.row(i) << 1e5 + (i & 1), 1e5 + (i & 2 ? 1 : 0), 1e5 + (i & 4 ? 1 : 0);
    }
    box.triangles.resize(12, 3);
    box.triangles << 0, 2, 1, 1, 2, 3, 4, 5, 6, 5, 7, 6, 0, 1, 4, 1, 5, 4, 2, 6, 3, 3, 6, 7, 0, 4, 2, 2, 4, 6, 1, 3, 5,
      3, 7, 5;
    far->SetBlock(0, mdvtk::ToPolyData(box));
  }
  for (const bool overBones : { false, true })
  {
    PhantomMotionPipeline p(30, 6);
    vtkNew<vtkPathsOverBones> rest, moving;
    rest->SetInputConnection(0, p.phantom->GetOutputPort(3));
    moving->SetInputConnection(0, p.lines->GetOutputPort());
    if (overBones)
    {
      rest->SetBonesConnection(p.phantom->GetOutputPort(1));
      moving->SetBonesConnection(p.bones->GetOutputPort());
    }
    else
    {
      rest->SetInputData(1, far);
      moving->SetInputData(1, far);
    }
    for (vtkPathsOverBones* paths : { rest.Get(), moving.Get() })
    {
      paths->SetPointsPerSegment(3);
    }
    p.motion->SetActionLinesRestConnection(rest->GetOutputPort());
    p.motion->SetActionLinesMotionConnection(moving->GetOutputPort());
    ASSERT_EQ(p.At(6), 1);
    auto* line =
      vtkPolyData::SafeDownCast(vtkMultiBlockDataSet::SafeDownCast(rest->GetOutputDataObject(0))->GetBlock(0));
    vtkDataArray* own = line->GetPointData()->GetArray("PathOwnPoint");
    ASSERT_NE(own, nullptr);
    for (vtkIdType i = 0; i < line->GetNumberOfPoints(); ++i)
    {
      EXPECT_EQ(own->GetTuple1(i), i % 4 == 0 ? 1.0 : 0.0) << i;
    }
    const unsigned int muscles =
      vtkMultiBlockDataSet::SafeDownCast(p.motion->GetOutputDataObject(0))->GetNumberOfBlocks();
    for (unsigned int b = 0; b < muscles; ++b)
    {
      EXPECT_LT(std::abs(Field(p.Muscle(b), "VolumeChangePercent")), 1e-4) << b;
      EXPECT_EQ(Field(p.Muscle(b), "MaxNewBonePenetrationDepth"), 0.0) << b;
      const double apart = LargestDifference(p.Muscle(b)->GetPoints(), plain.Muscle(b)->GetPoints());
      if (!overBones)
      {
        EXPECT_LT(apart, 1e-6) << "muscle " << b;
      }
    }
  }
}
