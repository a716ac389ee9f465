// SPDX-License-Identifier: BSD-3-Clause
// Reading a motion and mapping its columns onto a model's coordinates; bad motions named.
#include "OpenSim/OpenSimKinematics.h"
#include "OpenSim/OpenSimMotion.h"
#include "OpenSimTestModels.h"

#include <gtest/gtest.h>

#include <cmath>
#include <map>

using namespace md::osim;
using namespace md::osim::test;

TEST(OpenSimMotion, ReadsAndMapsColumns)
{
  const Model model = ParseModel(kSmallModel, "small.osim");
  const std::string path = WriteTemporary("m.mot",
    "walk\nversion=1\nnRows=2\nnColumns=4\ninDegrees=yes\nendheader\n"
    "time\t/jointset/hip/flex/value\t/jointset/hip/flex/speed\ttx\n0\t10\t1\t0.5\n0.1\t20\t1\t0.25\n");
  const MotionTable table = ReadMotion(path);
  EXPECT_TRUE(table.inDegrees);
  ASSERT_EQ(table.times.size(), 2u);
  const CoordinateTrajectory t = MapMotion(model, table);
  EXPECT_NEAR(t.frames[1][model.FindCoordinate("flex")], 20 * M_PI / 180, 1e-15);
  EXPECT_DOUBLE_EQ(t.frames[1][model.FindCoordinate("tx")], 0.25); // translational: not converted
  EXPECT_NEAR(t.frames[1][model.FindCoordinate("beta")], 2 * 20 * M_PI / 180 + 0.1, 1e-15);
  ASSERT_EQ(t.warnings.size(), 1u); // the coordinates the motion lacks
  EXPECT_NE(t.warnings[0].find("knee_angle"), std::string::npos);

  // A SIMM motion file (no version line) is in degrees; a .sto without inDegrees is in radians.
  EXPECT_TRUE(ReadMotion(WriteTemporary("s.mot", "x\nendheader\ntime flex\n0 1\n")).inDegrees);
  EXPECT_FALSE(ReadMotion(WriteTemporary("s.sto", "x\nversion=1\nendheader\ntime flex\n0 1\n")).inDegrees);

  std::vector<double> q = DefaultCoordinates(model);
  SetCoordinates(model, "flex=90, tx=2;knee_angle=-45", true, q);
  EXPECT_NEAR(q[model.FindCoordinate("flex")], M_PI / 2, 1e-15);
  EXPECT_DOUBLE_EQ(q[model.FindCoordinate("tx")], 2);
  EXPECT_NE(ExpectInputError([&] { SetCoordinates(model, "elbow=3", true, q); }).find("'elbow' is not a coordinate"),
    std::string::npos);
}

TEST(OpenSimMotion, BadMotionsAreNamed)
{
  const Model model = ParseModel(kSmallModel, "small.osim");
  std::string e = ExpectInputError([] { ReadMotion(WriteTemporary("nt.mot", "endheader\nflex tx\n1 2\n")); });
  EXPECT_NE(e.find("not 'time'"), std::string::npos) << e;
  EXPECT_NE(e.find("nt.mot"), std::string::npos) << e;
  e = ExpectInputError([] { ReadMotion(WriteTemporary("nan.mot", "endheader\ntime flex\n0 1\n0.1 nan\n")); });
  EXPECT_NE(e.find("line 4"), std::string::npos) << e;
  EXPECT_NE(e.find("column 'flex'"), std::string::npos) << e;
  e = ExpectInputError([] { ReadMotion(WriteTemporary("nh.mot", "time flex\n0 1\n")); });
  EXPECT_NE(e.find("endheader"), std::string::npos) << e;
  e = ExpectInputError([] { ReadMotion(WriteTemporary("back.mot", "endheader\ntime flex\n0 1\n0 2\n")); });
  EXPECT_NE(e.find("does not come after"), std::string::npos) << e;
  e = ExpectInputError([] { ReadMotion(WriteTemporary("huge.mot", "endheader\ntime flex\n0 1\n0.1 1e307\n")); });
  EXPECT_NE(e.find("line 4: column 'flex' holds 1e307, beyond the +-1e12"), std::string::npos) << e;
  const MotionTable extra = ReadMotion(WriteTemporary("x.mot", "endheader\ntime flex elbow\n0 1 2\n"));
  MotionOptions strict;
  strict.ignoreUnknownColumns = false;
  e = ExpectInputError([&] { MapMotion(model, extra, strict); });
  EXPECT_NE(e.find("column 'elbow' names no coordinate"), std::string::npos) << e;
  const CoordinateTrajectory t = MapMotion(model, extra); // skipped by default, as OpenSim does
  EXPECT_NE(t.warnings[0].find("elbow"), std::string::npos);
}

TEST(OpenSimMotion, AMotionOfAnotherModelIsSaidToBeOne)
{
  const Model model = ParseModel(kSmallModel, "small.osim");
  // Most of what the file moves names no coordinate of this model.
  const MotionTable other = ReadMotion(
    WriteTemporary("other.mot", "endheader\ntime flex elbow_flex wrist_dev pro_sup\n0 1 2 3 4\n0.1 2 3 4 5\n"));
  const CoordinateTrajectory t = MapMotion(model, other);
  std::string all;
  for (const std::string& w : t.warnings)
  {
    all += w + "\n";
  }
  EXPECT_NE(all.find("does not look like a motion of model"), std::string::npos) << all;
  EXPECT_NE(all.find("3 of the 4 columns whose values change name no coordinate"), std::string::npos) << all;
  // Columns of another name that stay constant (the LHDL motions' six zero pelvis columns) move
  // nothing: no such warning.
  const MotionTable constant = ReadMotion(
    WriteTemporary("constant.mot", "endheader\ntime xRotation yRotation zRotation flex\n0 0 0 0 1\n0.1 0 0 0 2\n"));
  for (const std::string& w : MapMotion(model, constant).warnings)
  {
    EXPECT_EQ(w.find("does not look like"), std::string::npos) << w;
  }
  // A motion that covers the model: no such warning.
  std::string header = "endheader\ntime", row = "0", next = "0.1";
  for (const Coordinate& c : model.coordinates)
  {
    header += " " + c.name;
    row += " 0";
    next += " 0.1";
  }
  const CoordinateTrajectory own =
    MapMotion(model, ReadMotion(WriteTemporary("own.mot", header + "\n" + row + "\n" + next + "\n")));
  for (const std::string& w : own.warnings)
  {
    EXPECT_EQ(w.find("does not look like"), std::string::npos) << w;
  }
}
