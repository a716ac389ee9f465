// SPDX-License-Identifier: BSD-3-Clause
// The OpenSim reader as a VTK filter, without data: time steps, which frame a request gets, what
// is read again when (counters, not timers).
#include "FilterTestUtilities.h"
#include "vtkOpenSimModelReader.h"

#include <vtkDoubleArray.h>
#include <vtkFieldData.h>
#include <vtkInformation.h>
#include <vtkMultiBlockDataSet.h>
#include <vtkPolyData.h>
#include <vtkStreamingDemandDrivenPipeline.h>
#include <vtkTable.h>

#include <gtest/gtest.h>

#include <cmath>
#include <fstream>

namespace
{
const char* kModel = R"(<?xml version="1.0"?>
<OpenSimDocument Version="40000"><Model name="knee">
 <Ground name="ground"/>
 <BodySet><objects><Body name="shank"/></objects></BodySet>
 <JointSet><objects>
  <PinJoint name="knee"><socket_parent_frame>/ground</socket_parent_frame><socket_child_frame>/bodyset/shank</socket_child_frame>
   <coordinates><Coordinate name="angle"/></coordinates></PinJoint>
 </objects></JointSet>
 <ForceSet><objects><Thelen2003Muscle name="m"><GeometryPath name="path"><PathPointSet><objects>
  <PathPoint name="a"><socket_parent_frame>/ground</socket_parent_frame><location>0 1 0</location></PathPoint>
  <PathPoint name="b"><socket_parent_frame>/bodyset/shank</socket_parent_frame><location>0 -1 0</location></PathPoint>
 </objects></PathPointSet></GeometryPath></Thelen2003Muscle></objects></ForceSet>
</Model></OpenSimDocument>)";

std::string Write(const std::string& name, const std::string& text)
{
  const std::string path = testing::TempDir() + "/" + name;
  std::ofstream(path) << text;
  return path;
}

double Field(vtkDataObject* data, const char* name)
{
  return vtkDoubleArray::SafeDownCast(data->GetFieldData()->GetArray(name))->GetValue(0);
}

/// Asks output port `port` for `time`, as a filter downstream of it would.
void UpdatePortAt(vtkOpenSimModelReader* reader, int port, double time)
{
  reader->UpdateInformation();
  reader->GetOutputInformation(port)->Set(vtkStreamingDemandDrivenPipeline::UPDATE_TIME_STEP(), time);
  reader->Update(port);
}

/// The path length at `time`, asked for through port `port`.
double UpdateAndLength(vtkOpenSimModelReader* reader, int port, double time)
{
  UpdatePortAt(reader, port, time);
  return Field(vtkMultiBlockDataSet::SafeDownCast(reader->GetOutputDataObject(1))->GetBlock(0), "PathLength");
}
}

TEST(OpenSimModelReader, FramesFollowTheRequestedTimeAndTheModelIsReadOnce)
{
  const std::string model = Write("knee.osim", kModel);
  const std::string motion =
    Write("knee.mot", "knee\nversion=1\ninDegrees=yes\nendheader\ntime angle\n0 0\n1 90\n2 180\n");
  vtkNew<vtkOpenSimModelReader> reader;
  reader->SetFileName(model.c_str());
  reader->SetMotionFileName(motion.c_str());
  reader->UpdateInformation();
  ASSERT_EQ(reader->GetNumberOfTimeSteps(), 3);
  EXPECT_DOUBLE_EQ(reader->GetTimeStep(2), 2.0);
  // Path from (0, 1, 0) to the shank's (0, -1, 0) turned by the angle about z.
  auto length = [](double degrees) {
    const double a = degrees * M_PI / 180;
    return std::hypot(std::sin(a), 1 + std::cos(a));
  };
  for (double time : { 2.0, 0.0, 1.0, 1.4, 1.6, 0.0, 2.0 })
  {
    EXPECT_NEAR(UpdateAndLength(reader, 1, time), length(90 * std::round(time)), 1e-12) << time;
  }
  // A request through another port (the table) gets its own time, not the last one of port 1.
  UpdatePortAt(reader, vtkOpenSimModelReader::BODY_TRANSFORMS, 1.0);
  EXPECT_DOUBLE_EQ(Field(reader->GetOutputDataObject(vtkOpenSimModelReader::BODY_TRANSFORMS), "Time"), 1.0);
  EXPECT_NEAR(Field(reader->GetOutputDataObject(vtkOpenSimModelReader::BODY_TRANSFORMS), "angle"), 90.0, 1e-12);
  // Scrubbing, a new motion and a new rest pose: the model file is not read again.
  reader->SetMotionFileName(
    Write("knee2.mot", "knee\nversion=1\ninDegrees=yes\nendheader\ntime angle\n0 45\n").c_str());
  reader->SetRestPoseCoordinates("angle=10");
  EXPECT_NEAR(UpdateAndLength(reader, 1, 0.0), length(45), 1e-12);
  EXPECT_EQ(reader->GetModelReadCount(), 1);
  // Without PlayMotion: no time steps, the pose at CurrentPoseTime whatever time is asked for.
  reader->SetMotionFileName(motion.c_str());
  reader->PlayMotionOff();
  reader->SetCurrentPoseTime(1.9);
  reader->UpdateInformation();
  EXPECT_FALSE(reader->GetOutputInformation(0)->Has(vtkStreamingDemandDrivenPipeline::TIME_STEPS()));
  EXPECT_NEAR(UpdateAndLength(reader, 1, 0.0), length(180), 1e-12);
  EXPECT_EQ(reader->GetModelReadCount(), 1);
  reader->SetFileName(Write("knee_copy.osim", kModel).c_str());
  reader->Update();
  EXPECT_EQ(reader->GetModelReadCount(), 2);
}

TEST(OpenSimModelReader, TheRestPoseCanComeFromAMotionFilesFirstRow)
{
  vtkNew<vtkOpenSimModelReader> reader;
  reader->SetFileName(Write("knee.osim", kModel).c_str());
  reader->SetRestPoseFileName(
    Write("static.mot", "static\nversion=1\ninDegrees=yes\nendheader\ntime angle\n0 90\n1 0\n").c_str());
  reader->Update();
  // The rest pose (90 degrees, the first row): rest and current outputs agree without a motion.
  auto* rest =
    vtkMultiBlockDataSet::SafeDownCast(reader->GetOutputDataObject(vtkOpenSimModelReader::MUSCLE_PATHS_REST));
  EXPECT_NEAR(Field(rest->GetBlock(0), "PathLength"), std::hypot(1.0, 1.0), 1e-12);
  // Coordinates given by value override the file's.
  reader->SetRestPoseCoordinates("angle=0");
  reader->Update();
  rest = vtkMultiBlockDataSet::SafeDownCast(reader->GetOutputDataObject(vtkOpenSimModelReader::MUSCLE_PATHS_REST));
  EXPECT_NEAR(Field(rest->GetBlock(0), "PathLength"), 2.0, 1e-12);
}

TEST(OpenSimModelReader, BadInputLeavesEmptyOutputs)
{
  CapturedMessages messages;
  vtkNew<vtkOpenSimModelReader> reader;
  reader->SetFileName(Write("broken.osim", "<OpenSimDocument Version=\"40000\"><Model>").c_str());
  reader->Update();
  EXPECT_NE(messages.Text().find("broken.osim', line 1: malformed XML"), std::string::npos) << messages.Text();
  EXPECT_EQ(vtkMultiBlockDataSet::SafeDownCast(reader->GetOutputDataObject(1))->GetNumberOfBlocks(), 0u);
  EXPECT_EQ(vtkTable::SafeDownCast(reader->GetOutputDataObject(4))->GetNumberOfRows(), 0);
}
