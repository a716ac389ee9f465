// SPDX-License-Identifier: BSD-3-Clause
#include "FilterTestUtilities.h"
#include "MDConvert.h"

#include "vtkActionLineMatching.h"
#include "vtkBoneInterpolation.h"
#include "vtkMusculoskeletalPhantom.h"

#include <vtkCellData.h>
#include <vtkDataArray.h>
#include <vtkFieldData.h>
#include <vtkMath.h>
#include <vtkPointData.h>
#include <vtkStreamingDemandDrivenPipeline.h>
#include <vtkTrivialProducer.h>
#include <vtkUnsignedCharArray.h>

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

namespace
{
vtkPolyData* Block(vtkDataObject* data, unsigned int index)
{
  return vtkPolyData::SafeDownCast(vtkMultiBlockDataSet::SafeDownCast(data)->GetBlock(index));
}

void ExpectSamePoints(vtkPoints* a, vtkPoints* b, double tolerance = 0.0)
{
  ASSERT_EQ(a->GetNumberOfPoints(), b->GetNumberOfPoints());
  for (vtkIdType i = 0; i < a->GetNumberOfPoints(); ++i)
  {
    double pa[3], pb[3];
    a->GetPoint(i, pa);
    b->GetPoint(i, pb);
    for (int c = 0; c < 3; ++c)
    {
      ASSERT_NEAR(pa[c], pb[c], tolerance) << "point " << i;
    }
  }
}

int Update(vtkAlgorithm* algorithm)
{
  return algorithm->GetExecutive()->Update();
}

/// Two plain polylines in each pose: the first of 3 rest points against 2 current ones, the
/// second of 2 against 3 (a point is inserted on each pose's line).
vtkSmartPointer<vtkPolyData> TwoLinesRest()
{
  return MakePolylines({ { 0, 0, 0, 1, 0, 0, 1, 2, 0 }, { 5, 5, 5, 6, 6, 6 } });
}
vtkSmartPointer<vtkPolyData> TwoLinesCurrent()
{
  return MakePolylines({ { 0, 0, 0, 0, 3, 0 }, { 5, 5, 5, 5, 5, 6, 6, 6, 6 } });
}

/// `matching` run on `rest` and `current`.
void Match(vtkActionLineMatching* matching, vtkDataObject* rest, vtkDataObject* current)
{
  matching->SetInputData(0, rest);
  matching->SetInputData(1, current);
  matching->Update();
}
}

TEST(MusculoskeletalPhantom, OutputsNamedBlocksOnFivePorts)
{
  vtkNew<vtkMusculoskeletalPhantom> phantom;
  phantom->SetFlexion(60);
  phantom->Update();
  auto* muscles = vtkMultiBlockDataSet::SafeDownCast(phantom->GetOutputDataObject(0));
  ASSERT_NE(muscles, nullptr);
  ASSERT_EQ(muscles->GetNumberOfBlocks(), 3u);
  EXPECT_EQ(BlockName(muscles, 0), "Iliopsoas");
  EXPECT_EQ(BlockName(muscles, 1), "GluteusMaximus");
  EXPECT_EQ(BlockName(muscles, 2), "RectusFemoris");
  auto* bonesRest = vtkMultiBlockDataSet::SafeDownCast(phantom->GetOutputDataObject(1));
  auto* bonesCurrent = vtkMultiBlockDataSet::SafeDownCast(phantom->GetOutputDataObject(2));
  EXPECT_EQ(BlockName(bonesRest, 1), "Femur");
  EXPECT_EQ(Block(bonesRest, 1)->GetNumberOfPoints(), Block(bonesCurrent, 1)->GetNumberOfPoints());
  ExpectSamePoints(Block(bonesRest, 0)->GetPoints(), Block(bonesCurrent, 0)->GetPoints());
  auto* linesRest = vtkMultiBlockDataSet::SafeDownCast(phantom->GetOutputDataObject(3));
  auto* linesCurrent = vtkMultiBlockDataSet::SafeDownCast(phantom->GetOutputDataObject(4));
  EXPECT_EQ(BlockName(linesRest, 1), "GluteusMaximus");
  EXPECT_EQ(Block(linesRest, 1)->GetNumberOfLines(), 2);
  EXPECT_EQ(Block(linesRest, 0)->GetNumberOfPoints(), 3);
  EXPECT_EQ(Block(linesCurrent, 0)->GetNumberOfPoints(), 2); // conditional via point inactive
}

TEST(ActionLineMatching, PairsBlocksByNameAndCarriesTheCurrentPosition)
{
  vtkNew<vtkMusculoskeletalPhantom> phantom;
  phantom->SetFlexion(60);
  phantom->Update();
  auto* linesRest = vtkMultiBlockDataSet::SafeDownCast(phantom->GetOutputDataObject(3));
  auto* linesCurrent = vtkMultiBlockDataSet::SafeDownCast(phantom->GetOutputDataObject(4));
  // The current pose lists the muscles in another order: pairing is by name.
  auto reordered = MakeBlocks({ { "RectusFemoris", Block(linesCurrent, 2) }, { "Iliopsoas", Block(linesCurrent, 0) },
    { "GluteusMaximus", Block(linesCurrent, 1) } });
  vtkNew<vtkActionLineMatching> matching;
  matching->SetInputData(0, linesRest);
  matching->SetInputData(1, reordered);
  matching->Update();
  auto* matchedRest = vtkMultiBlockDataSet::SafeDownCast(matching->GetOutputDataObject(0));
  auto* matchedCurrent = vtkMultiBlockDataSet::SafeDownCast(matching->GetOutputDataObject(1));
  ASSERT_EQ(matchedRest->GetNumberOfBlocks(), 3u);
  EXPECT_EQ(BlockName(matchedRest, 0), "Iliopsoas");
  EXPECT_EQ(BlockName(matchedCurrent, 0), "RectusFemoris");
  const unsigned int currentIndexOf[3] = { 1, 2, 0 };
  for (unsigned int b = 0; b < 3; ++b)
  {
    vtkPolyData* rest = Block(matchedRest, b);
    vtkPolyData* current = Block(matchedCurrent, currentIndexOf[b]);
    ASSERT_EQ(rest->GetNumberOfPoints(), current->GetNumberOfPoints()) << BlockName(matchedRest, b);
    EXPECT_EQ(rest->GetNumberOfLines(), Block(linesRest, b)->GetNumberOfLines());
    vtkDataArray* position = rest->GetPointData()->GetArray("CurrentPosition");
    ASSERT_NE(position, nullptr);
    vtkNew<vtkPoints> asPoints;
    asPoints->SetData(position);
    ExpectSamePoints(asPoints, current->GetPoints());
    ASSERT_NE(rest->GetPointData()->GetArray("ArcLength"), nullptr);
    ASSERT_NE(current->GetPointData()->GetArray("Inserted"), nullptr);
    EXPECT_NE(rest->GetCellData()->GetAbstractArray("ActionLineName"), nullptr);
  }
  // Iliopsoas: 3 RP points against 2 CP points; one point inserted on the CP line.
  vtkDataArray* inserted = Block(matchedCurrent, 1)->GetPointData()->GetArray("Inserted");
  EXPECT_EQ(Block(matchedCurrent, 1)->GetNumberOfPoints(), 3);
  EXPECT_EQ(inserted->GetTuple1(1), 1.0);
}

TEST(ActionLineMatching, PlainPolyDataInputsGivePolyDataOutputs)
{
  vtkNew<vtkActionLineMatching> matching;
  Match(matching, TwoLinesRest(), TwoLinesCurrent());
  auto* outRest = vtkPolyData::SafeDownCast(matching->GetOutputDataObject(0));
  auto* outCurrent = vtkPolyData::SafeDownCast(matching->GetOutputDataObject(1));
  ASSERT_NE(outRest, nullptr);
  ASSERT_NE(outCurrent, nullptr);
  EXPECT_EQ(outRest->GetNumberOfLines(), 2);
  EXPECT_EQ(outRest->GetNumberOfPoints(), outCurrent->GetNumberOfPoints());
  EXPECT_EQ(outRest->GetNumberOfPoints(), 3 + 3);
}

TEST(ActionLineMatching, APathsOwnPointsStayItsOwnAmongThePointsInserted)
{
  // PathOwnPoint (PathsOverBones'): the points matching inserts are not the path's own.
  auto rest = TwoLinesRest();
  vtkNew<vtkUnsignedCharArray> own;
  own->SetName("PathOwnPoint");
  for (const unsigned char value : { 1, 0, 1, 1, 1 })
  {
    own->InsertNextValue(value);
  }
  rest->GetPointData()->AddArray(own);
  vtkNew<vtkActionLineMatching> matching;
  Match(matching, rest, TwoLinesCurrent());
  auto* outRest = vtkPolyData::SafeDownCast(matching->GetOutputDataObject(0));
  ASSERT_NE(outRest, nullptr);
  vtkDataArray* matched = outRest->GetPointData()->GetArray("PathOwnPoint");
  ASSERT_NE(matched, nullptr);
  ASSERT_EQ(matched->GetNumberOfTuples(), 6);
  const double expected[6] = { 1, 0, 1, 1, 0, 1 }; // the second line's middle point is inserted
  for (vtkIdType i = 0; i < 6; ++i)
  {
    EXPECT_EQ(matched->GetTuple1(i), expected[i]) << i;
  }
  const std::vector<md::Knots> knots = mdvtk::ToKnots(outRest);
  ASSERT_EQ(knots.size(), 2u);
  EXPECT_EQ(knots[0], md::Knots({ 0, 2 }));
  EXPECT_EQ(knots[1], md::Knots({ 0, 2 }));
  // Without the array every point is its own.
  EXPECT_TRUE(mdvtk::ToKnots(MakePolylines({ { 0, 0, 0, 1, 0, 0 } })).empty());
}

TEST(ActionLineMatching, BlocksThatShareNoNamePairByOrderWithANote)
{
  // Group Datasets in the GUI names blocks after its inputs ('femur_r.vtk', 'Transform1'): such
  // inputs pair by order, and the warning says which block went with which.
  auto first = MakePolylines({ { 0, 0, 0, 1, 0, 0 } });
  auto second = MakePolylines({ { 0, 0, 0, 0, 2, 0 } });
  auto firstMoved = MakePolylines({ { 0, 0, 1, 1, 0, 1 } });
  auto secondMoved = MakePolylines({ { 0, 0, 3, 0, 2, 3 } });
  CapturedMessages messages;
  vtkNew<vtkActionLineMatching> matching;
  matching->SetInputData(0, MakeBlocks({ { "Iliacus", first }, { "Psoas", second } }));
  matching->SetInputData(1, MakeBlocks({ { "Transform1", firstMoved }, { "Transform2", secondMoved } }));
  ASSERT_EQ(Update(matching), 1) << messages.Text();
  EXPECT_TRUE(messages.Contains("share no block name, so their blocks pair by order: 'Iliacus' with "
                                "'Transform1', 'Psoas' with 'Transform2'"))
    << messages.Text();
  vtkDataArray* current = Block(matching->GetOutputDataObject(0), 1)->GetPointData()->GetArray("CurrentPosition");
  ASSERT_NE(current, nullptr);
  EXPECT_EQ(current->GetComponent(0, 2), 3.0); // the second block's lines moved by 3
}

TEST(ActionLineMatching, BadInputGivesAClearErrorAndNoOutput)
{
  struct Case
  {
    const char* what;
    vtkSmartPointer<vtkDataObject> rest;
    vtkSmartPointer<vtkDataObject> current;
    std::string expected;
  };
  const double nan = std::numeric_limits<double>::quiet_NaN();
  auto good = MakePolylines({ { 0, 0, 0, 1, 0, 0, 1, 2, 0 } });
  std::vector<Case> cases = {
    { "different numbers of polylines", good, MakePolylines({ { 0, 0, 0, 1, 0, 0 }, { 0, 0, 0, 1, 1, 1 } }),
      "Input has 1 polyline(s) but CurrentPose has 2" },
    { "zero-length line", good, MakePolylines({ { 1, 1, 1, 1, 1, 1 } }), "zero length" },
    { "single point", MakePolylines({ { 1, 1, 1 } }), good, "at least two points" },
    { "NaN", good, MakePolylines({ { 0, 0, 0, nan, 0, 0 } }), "NaN" },
    { "empty input", vtkSmartPointer<vtkPolyData>::New(), good, "Input has no polylines" },
    { "unmatched block name", MakeBlocks({ { "Iliacus", good }, { "Psoas", good } }),
      MakeBlocks({ { "Iliacus", good }, { "Gluteus", good } }),
      "Input block 'Psoas' has no block of the same name in CurrentPose" },
    { "different block counts", MakeBlocks({ { "A", good }, { "", good } }), MakeBlocks({ { "A", good } }),
      "Input has 2 block(s) but CurrentPose has 1" },
  };
  for (const Case& c : cases)
  {
    CapturedMessages messages;
    vtkNew<vtkActionLineMatching> matching;
    matching->SetInputData(0, c.rest);
    matching->SetInputData(1, c.current);
    EXPECT_EQ(Update(matching), 0) << c.what;
    EXPECT_TRUE(messages.Contains(c.expected)) << c.what << ": got " << messages.Text();
  }
}

TEST(BoneInterpolation, AdvertisesOneTimeStepPerStepAndDeliversEach)
{
  vtkNew<vtkMusculoskeletalPhantom> phantom;
  phantom->SetFlexion(60);
  vtkNew<vtkBoneInterpolation> interpolation;
  interpolation->SetInputConnection(0, phantom->GetOutputPort(1));
  interpolation->SetInputConnection(1, phantom->GetOutputPort(2));
  interpolation->SetNumberOfSteps(3);
  interpolation->SetInterpolationMode(vtkBoneInterpolation::LINEAR);
  interpolation->UpdateInformation();
  vtkInformation* info = interpolation->GetOutputInformation(0);
  ASSERT_TRUE(info->Has(vtkStreamingDemandDrivenPipeline::TIME_STEPS()));
  ASSERT_EQ(info->Length(vtkStreamingDemandDrivenPipeline::TIME_STEPS()), 4);
  EXPECT_EQ(info->Get(vtkStreamingDemandDrivenPipeline::TIME_STEPS())[3], 3.0);

  phantom->Update();
  vtkPolyData* femurRest = Block(phantom->GetOutputDataObject(1), 1);
  vtkPolyData* femurCurrent = Block(phantom->GetOutputDataObject(2), 1);
  for (int step = 0; step <= 3; ++step)
  {
    interpolation->UpdateTimeStep(step);
    vtkDataObject* output = interpolation->GetOutputDataObject(0);
    vtkPolyData* femur = Block(output, 1);
    ASSERT_NE(femur, nullptr);
    EXPECT_EQ(BlockName(vtkMultiBlockDataSet::SafeDownCast(output), 1), "Femur");
    EXPECT_EQ(femur->GetNumberOfPolys(), femurRest->GetNumberOfPolys());
    EXPECT_EQ(femur->GetFieldData()->GetArray("InterpolationStep")->GetTuple1(0), step);
    EXPECT_EQ(output->GetInformation()->Get(vtkDataObject::DATA_TIME_STEP()), step);
    double expected[3], rest[3], current[3], got[3];
    femurRest->GetPoint(100, rest);
    femurCurrent->GetPoint(100, current);
    femur->GetPoint(100, got);
    for (int c = 0; c < 3; ++c)
    {
      expected[c] = rest[c] + step * (current[c] - rest[c]) / 3.0;
      EXPECT_NEAR(got[c], expected[c], 1e-9);
    }
  }
  ExpectSamePoints(Block(interpolation->GetOutputDataObject(0), 1)->GetPoints(), femurCurrent->GetPoints());
}

TEST(BoneInterpolation, AutomaticStepsFollowTheLargestDisplacement)
{
  vtkNew<vtkMusculoskeletalPhantom> phantom;
  phantom->SetFlexion(30);
  vtkNew<vtkBoneInterpolation> interpolation;
  interpolation->SetInputConnection(0, phantom->GetOutputPort(1));
  interpolation->SetInputConnection(1, phantom->GetOutputPort(2));
  interpolation->SetNumberOfSteps(0);
  interpolation->SetMaximumStepDisplacement(25.0);
  interpolation->UpdateInformation();
  phantom->Update();
  // The femur's far end is about 430 mm from the hip: 2 * 430 * sin(15 deg) = 223 mm.
  vtkPolyData* rest = Block(phantom->GetOutputDataObject(1), 1);
  vtkPolyData* current = Block(phantom->GetOutputDataObject(2), 1);
  double largest = 0;
  for (vtkIdType i = 0; i < rest->GetNumberOfPoints(); ++i)
  {
    double a[3], b[3];
    rest->GetPoint(i, a);
    current->GetPoint(i, b);
    largest = std::max(largest, std::sqrt(vtkMath::Distance2BetweenPoints(a, b)));
  }
  EXPECT_EQ(interpolation->GetResolvedNumberOfSteps(), static_cast<int>(std::ceil(largest / 25.0)));
  EXPECT_GT(interpolation->GetResolvedNumberOfSteps(), 5);
}

TEST(BoneInterpolation, InterpolatesMatchedActionLinesThroughCurrentPosition)
{
  vtkNew<vtkMusculoskeletalPhantom> phantom;
  phantom->SetFlexion(60);
  vtkNew<vtkActionLineMatching> matching;
  matching->SetInputConnection(0, phantom->GetOutputPort(3));
  matching->SetInputConnection(1, phantom->GetOutputPort(4));
  vtkNew<vtkBoneInterpolation> interpolation;
  interpolation->SetInputConnection(0, matching->GetOutputPort(0));
  interpolation->SetInterpolationMode(vtkBoneInterpolation::LINEAR);
  interpolation->SetNumberOfSteps(2);
  interpolation->UpdateTimeStep(2);
  matching->Update();
  for (unsigned int b = 0; b < 3; ++b)
  {
    ExpectSamePoints(Block(interpolation->GetOutputDataObject(0), b)->GetPoints(),
      Block(matching->GetOutputDataObject(1), b)->GetPoints());
  }
}

TEST(BoneInterpolation, RigidModeWarnsAboutANonRigidMotion)
{
  auto rest = MakePolylines({ { 0, 0, 0, 10, 0, 0, 10, 10, 0, 0, 10, 5 } });
  auto current = MakePolylines({ { 0, 0, 0, 10, 0, 0, 10, 10, 0, 0, 30, 5 } });
  CapturedMessages messages;
  vtkNew<vtkBoneInterpolation> interpolation;
  interpolation->SetInputData(0, rest);
  interpolation->SetInputData(1, current);
  interpolation->UpdateTimeStep(1);
  EXPECT_TRUE(messages.Contains("is not rigid")) << messages.Text();
  auto* output = vtkPolyData::SafeDownCast(interpolation->GetOutputDataObject(0));
  EXPECT_GT(output->GetFieldData()->GetArray("RigidFitMaxResidual")->GetTuple1(0), 1.0);
  // Said once, not again at every step an animation asks for; again once the input changes.
  auto count = [&] {
    const std::string text = messages.Text();
    size_t n = 0;
    for (size_t at = text.find("is not rigid"); at != std::string::npos; at = text.find("is not rigid", at + 1))
    {
      ++n;
    }
    return n;
  };
  interpolation->UpdateTimeStep(0);
  interpolation->UpdateTimeStep(1);
  EXPECT_EQ(count(), 1u) << messages.Text();
  current->Modified();
  interpolation->UpdateTimeStep(0);
  EXPECT_EQ(count(), 2u) << messages.Text();
}

TEST(BoneInterpolation, BadInputGivesAClearErrorAndNoOutput)
{
  vtkNew<vtkMusculoskeletalPhantom> phantom;
  phantom->SetFlexion(60);
  phantom->Update();
  vtkSmartPointer<vtkPolyData> femur = Block(phantom->GetOutputDataObject(1), 1);
  vtkSmartPointer<vtkPolyData> pelvis = Block(phantom->GetOutputDataObject(1), 0);
  auto withNaN = vtkSmartPointer<vtkPolyData>::New();
  withNaN->DeepCopy(femur);
  withNaN->GetPoints()->SetPoint(7, std::numeric_limits<double>::quiet_NaN(), 0, 0);
  auto otherCells = vtkSmartPointer<vtkPolyData>::New();
  otherCells->DeepCopy(femur);
  otherCells->GetPolys()->ReplaceCellAtId(0, { 0, 1, 2 });
  auto lines = MakePolylines({ { 0, 0, 0, 1, 0, 0 } });
  struct Case
  {
    const char* what;
    vtkSmartPointer<vtkDataObject> rest;
    vtkSmartPointer<vtkDataObject> current;
    std::string expected;
  };
  std::vector<Case> cases = {
    { "different point counts", MakeBlocks({ { "Femur", femur } }), MakeBlocks({ { "Femur", pelvis } }),
      "Input block 'Femur' has " + std::to_string(femur->GetNumberOfPoints()) +
        " points but CurrentPose block 'Femur' has " + std::to_string(pelvis->GetNumberOfPoints()) },
    { "NaN in the current pose", femur, withNaN, "CurrentPose has NaN" },
    { "different cells", femur, otherCells, "have different cells" },
    { "empty input", vtkSmartPointer<vtkPolyData>::New(), femur, "Input has no points" },
    { "no current pose and no CurrentPosition", lines, nullptr, "no 3-component point array CurrentPosition" },
    { "mismatched bone blocks", MakeBlocks({ { "Femur", femur }, { "Pelvis", pelvis } }),
      MakeBlocks({ { "Femur", femur }, { "Sacrum", pelvis } }),
      "Input block 'Pelvis' has no block of the same name in CurrentPose" },
  };
  for (const Case& c : cases)
  {
    CapturedMessages messages;
    vtkNew<vtkBoneInterpolation> interpolation;
    interpolation->SetInputData(0, c.rest);
    if (c.current)
    {
      interpolation->SetInputData(1, c.current);
    }
    EXPECT_EQ(Update(interpolation), 0) << c.what;
    EXPECT_TRUE(messages.Contains(c.expected)) << c.what << ": got " << messages.Text();
  }
}
