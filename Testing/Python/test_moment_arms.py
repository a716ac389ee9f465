# SPDX-License-Identifier: BSD-3-Clause
"""The reader's MomentArms table as a pvpython user reads it: against OpenSim 3.3's own moment
arms of the LHDL model's straight paths (an external oracle, skipped without the data), through
the data set's motions, and on a small model written here."""
import json
import math
import os
import unittest

import mdtesting
import mdexamples
import numpy
from paraview import servermanager, simple
from vtkmodules.util.numpy_support import vtk_to_numpy

mdtesting.load_plugin()
DATA = mdexamples.data_dir()
MOTIONS = ("hip_flexion", "hip_adduction")
# Where a conditional point of the LHDL psoas (40 deg) and iliacus (54 deg) comes or goes: the
# moment arm jumps there, so no curve is interpolated across them.
SWITCHES_DEG = (math.degrees(0.698132), math.degrees(0.942478))


def read_table(model, motion, **properties):
    reader = simple.OpenSimModelReader(FileName=model, MotionFileName=motion, LoadGeometry=0, **properties)
    reader.UpdatePipeline()
    table = servermanager.Fetch(reader, idx=6)
    simple.Delete(reader)
    return table


def column(table, name):
    array = table.GetColumnByName(name)
    assert array is not None, "no column " + name
    return [array.GetValue(i) for i in range(array.GetNumberOfTuples())]


def write_motion(path, coordinate, angles):
    rows = "".join("%r\t%r\n" % (0.01 * i, a) for i, a in enumerate(angles))
    with open(path, "w") as f:
        f.write("m\nversion=1\nnRows=%d\nnColumns=2\ninDegrees=yes\nendheader\ntime\t%s\n%s"
                % (len(angles), coordinate, rows))


@unittest.skipIf(DATA is None, "real data not found: set MUSCLEDEFORMATION_DATA_DIR to the folder holding "
                 "lhdl_hip_r and literature")
class StraightPathsAgainstOpenSim(unittest.TestCase):
    def setUp(self):
        self.model = os.path.join(DATA, "lhdl_hip_r", "LHDL_hip_r.osim")
        self.output = mdtesting.output_dir("test_moment_arms")

    def oracle(self, motion):
        with open(os.path.join(DATA, "literature", "opensim_straight_lines_%s.json" % motion)) as f:
            return json.load(f)

    def test_every_path_at_every_pose_of_opensims_own_analysis(self):
        """OpenSim's MuscleAnalysis poses (100 per motion, across both conditional switches): every
        path's moment arm within 0.5 mm (they agree to the file's 0.0001 mm)."""
        for motion in MOTIONS:
            oracle = self.oracle(motion)
            coordinate = oracle["coordinate"]
            path = os.path.join(self.output, motion + "_oracle_poses.mot")
            write_motion(path, coordinate, oracle["angle_deg"])
            table = read_table(self.model, path, Scale=1000)
            self.assertEqual(table.GetNumberOfRows(), len(oracle["angle_deg"]))
            for name, expected in oracle["paths"].items():
                ours = column(table, "MomentArm(%s, %s)" % (name, coordinate))
                worst = max(abs(a - b) for a, b in zip(ours, expected))
                self.assertLess(worst, 0.5, "%s %s: %.4f mm from OpenSim's" % (motion, name, worst))
                self.assertLess(worst, 0.001, "%s %s: %.4f mm from OpenSim's" % (motion, name, worst))

    def test_the_data_sets_motions_frame_by_frame(self):
        """The LHDL motions as given: a row per frame, the coordinate that moves and no other, and
        every frame's moment arm on OpenSim's curve (interpolated between its poses, 1 deg apart,
        where no conditional point switches in between) to 0.5 mm."""
        for motion in MOTIONS:
            oracle = self.oracle(motion)
            coordinate = oracle["coordinate"]
            table = read_table(self.model, os.path.join(DATA, "lhdl_hip_r", "kinematics", motion + ".mot"), Scale=1000)
            names = [table.GetColumnName(i) for i in range(table.GetNumberOfColumns())]
            self.assertEqual(names[:2], ["Time", coordinate])
            self.assertFalse([n for n in names if "pelvis" in n or ("hip_" in n and coordinate not in n)], names)
            angles = column(table, coordinate)
            poses = oracle["angle_deg"]
            compared = 0
            for name, expected in oracle["paths"].items():
                ours = column(table, "MomentArm(%s, %s)" % (name, coordinate))
                for angle, arm in zip(angles, ours):
                    k = max(i for i in range(len(poses) - 1) if poses[i] <= angle + 1e-9)
                    if any(poses[k] < s <= poses[k + 1] for s in SWITCHES_DEG):
                        continue
                    share = (angle - poses[k]) / (poses[k + 1] - poses[k])
                    interpolated = expected[k] + share * (expected[k + 1] - expected[k])
                    self.assertLess(abs(arm - interpolated), 0.5, "%s %s at %g deg" % (motion, name, angle))
                    compared += 1
            self.assertGreater(compared, 8 * (len(angles) - 4))


@unittest.skipIf(DATA is None, "real data not found: set MUSCLEDEFORMATION_DATA_DIR to the folder holding lhdl_hip_r")
class ConditionalPointFade(unittest.TestCase):
    def test_the_psoas_path_jumps_by_default_and_fades_when_asked(self):
        """OpenSim's psoas path jumps at 40 degrees of flexion, where its via point goes (and the
        reader says so); with ConditionalPointFade 10 it moves continuously and is OpenSim's
        wherever the point is active."""
        output = mdtesting.output_dir("test_moment_arms")
        angles = [30 + 0.5 * k for k in range(61)]  # 30 to 60 degrees
        path = os.path.join(output, "flexion_30_60.mot")
        write_motion(path, "hip_flexion_r", angles)
        model = os.path.join(DATA, "lhdl_hip_r", "LHDL_hip_r.osim")
        lengths = {}
        for fade in (0.0, 10.0):
            with mdtesting.CapturedMessages() as messages:
                reader = simple.OpenSimModelReader(FileName=model, MotionFileName=path, LoadGeometry=0, Scale=1000,
                                                   ConditionalPointFade=fade)
                reader.UpdatePipelineInformation()
                lengths[fade] = []
                for t in reader.TimestepValues:
                    reader.UpdatePipeline(t)
                    paths = servermanager.Fetch(reader, idx=1)
                    lengths[fade].append(mdtesting.block(paths, "psoas_r").GetFieldData().GetArray(
                        "PathLength").GetValue(0))
            self.assertIn("the motion makes these paths gain or lose a conditional path point", messages.text)
            self.assertIn("psoas_r (at ", messages.text)
            simple.Delete(reader)
        # The largest change of length between two poses 0.5 degrees apart against the median change.
        ratio = {}
        for fade, values in lengths.items():
            steps = sorted(abs(b - a) for a, b in zip(values, values[1:]))
            ratio[fade] = steps[-1] / steps[len(steps) // 2]
        print("[ measured ] the psoas path's largest change between poses 0.5 degrees apart against the median: "
              "%.1f as OpenSim has it, %.1f faded over 10 degrees" % (ratio[0.0], ratio[10.0]))
        self.assertGreater(ratio[0.0], 4.0)
        self.assertLess(ratio[10.0], 2.0)
        for angle, exact, faded in zip(angles, lengths[0.0], lengths[10.0]):
            if angle <= 40.0:
                self.assertAlmostEqual(exact, faded, places=9)
            if angle >= 50.5:
                self.assertAlmostEqual(exact, faded, places=6)


class SmallModel(unittest.TestCase):
    """A pin joint about z through (0, 1, 0); the path from (0, 1.5, 0) on ground to (0, -0.5, 0)
    on the arm: 0.5 from the axis at each end."""

    MODEL = """<?xml version="1.0"?>
<OpenSimDocument Version="40000"><Model name="arm">
 <Ground name="ground"/>
 <BodySet><objects><Body name="arm"/></objects></BodySet>
 <JointSet><objects><PinJoint name="shoulder"><socket_parent_frame>shoulder_offset</socket_parent_frame><socket_child_frame>/bodyset/arm</socket_child_frame>
  <coordinates><Coordinate name="angle"><range>-3 3</range></Coordinate></coordinates>
  <frames><PhysicalOffsetFrame name="shoulder_offset"><socket_parent>/ground</socket_parent><translation>0 1 0</translation><orientation>0 0 0</orientation></PhysicalOffsetFrame></frames>
 </PinJoint></objects></JointSet>
 <ForceSet><objects><Thelen2003Muscle name="deltoid"><GeometryPath name="path"><PathPointSet><objects>
  <PathPoint name="o"><socket_parent_frame>/ground</socket_parent_frame><location>0 1.5 0</location></PathPoint>
  <PathPoint name="i"><socket_parent_frame>/bodyset/arm</socket_parent_frame><location>0 -0.5 0</location></PathPoint>
 </objects></PathPointSet></GeometryPath></Thelen2003Muscle></objects></ForceSet>
</Model></OpenSimDocument>
"""

    def setUp(self):
        self.output = mdtesting.output_dir("test_moment_arms")
        self.model = os.path.join(self.output, "arm.osim")
        with open(self.model, "w") as f:
            f.write(self.MODEL)

    def test_the_closed_form_and_the_units(self):
        """L = sqrt(0.5 + 0.5 cos q), so r = -dL/dq = 0.25 sin q / L; Scale 1000 gives millimetres
        (per radian)."""
        angles = [-60, -20, 0, 30, 90, 150]
        path = os.path.join(self.output, "arm.mot")
        write_motion(path, "angle", angles)
        table = read_table(self.model, path, Scale=1000)
        self.assertEqual(column(table, "Time"), [0.01 * i for i in range(len(angles))])
        for got, angle in zip(column(table, "angle"), angles):
            self.assertAlmostEqual(got, angle, places=12)
        lengths, arms = column(table, "Length(deltoid)"), column(table, "MomentArm(deltoid, angle)")
        for angle, length, arm in zip(angles, lengths, arms):
            q = math.radians(angle)
            expected_length = math.sqrt(0.5 ** 2 + 0.5 ** 2 + 2 * 0.5 * 0.5 * math.cos(q))
            self.assertAlmostEqual(length, 1000 * expected_length, places=9)
            self.assertAlmostEqual(arm, 1000 * 0.5 * 0.5 * math.sin(q) / expected_length, places=4)

    def test_without_a_motion_one_row_at_the_rest_pose_and_every_coordinate(self):
        table = read_table(self.model, "", RestPoseCoordinates="angle=30")
        self.assertEqual(table.GetNumberOfRows(), 1)
        self.assertAlmostEqual(column(table, "angle")[0], 30.0, places=12)
        self.assertAlmostEqual(column(table, "MomentArm(deltoid, angle)")[0],
                               0.25 * math.sin(math.radians(30)) / math.sqrt(0.5 + 0.5 * math.cos(math.radians(30))),
                               places=7)


class SteppedPoses(unittest.TestCase):
    """MomentArmStep through the motion filter, on a model written here: a universal joint whose
    two coordinates move at once, which differences between frames cannot tell apart."""

    MODEL = """<?xml version="1.0"?>
<OpenSimDocument Version="40000"><Model name="arm">
 <Ground name="ground"/>
 <BodySet><objects><Body name="arm"/></objects></BodySet>
 <JointSet><objects><UniversalJoint name="shoulder"><socket_parent_frame>shoulder_offset</socket_parent_frame><socket_child_frame>/bodyset/arm</socket_child_frame>
  <coordinates><Coordinate name="rx"><range>-3 3</range></Coordinate><Coordinate name="ry"><range>-3 3</range></Coordinate></coordinates>
  <frames><PhysicalOffsetFrame name="shoulder_offset"><socket_parent>/ground</socket_parent><translation>0 1 0</translation><orientation>0 0 0</orientation></PhysicalOffsetFrame></frames>
 </UniversalJoint></objects></JointSet>
 <ForceSet><objects><Thelen2003Muscle name="belly"><GeometryPath name="path"><PathPointSet><objects>
  <PathPoint name="o"><socket_parent_frame>/ground</socket_parent_frame><location>0.2 1.6 0.1</location></PathPoint>
  <PathPoint name="i"><socket_parent_frame>/bodyset/arm</socket_parent_frame><location>0.05 -0.5 0</location></PathPoint>
 </objects></PathPointSet></GeometryPath></Thelen2003Muscle></objects></ForceSet>
</Model></OpenSimDocument>
"""
    STEP = 1.0  # degrees
    FRAMES = 5

    @classmethod
    def setUpClass(cls):
        import lhdl
        output = mdtesting.output_dir("test_moment_arms")
        cls.model = os.path.join(output, "universal.osim")
        with open(cls.model, "w") as f:
            f.write(cls.MODEL)
        cls.motion_file = os.path.join(output, "universal.mot")
        rows = "".join("%r\t%r\t%r\n" % (0.01 * k, 6.0 * k, 4.0 * k) for k in range(cls.FRAMES))
        with open(cls.motion_file, "w") as f:
            f.write("m\nversion=1\nnRows=%d\nnColumns=3\ninDegrees=yes\nendheader\ntime\trx\try\n%s"
                    % (cls.FRAMES, rows))
        # In the rest pose (Scale 100): the path from o = (20, 160, 10) to i = (5, 50, 0), the joint
        # at (0, 100, 0). The belly an ellipsoid around it, tip to tip; a bone beyond each end.
        origin, insertion = numpy.array([20.0, 160.0, 10.0]), numpy.array([5.0, 50.0, 0.0])
        axis = (origin - insertion) / numpy.linalg.norm(origin - insertion)
        belly = cls.ellipsoid((origin + insertion) / 2, axis, numpy.linalg.norm(origin - insertion) / 2, 12.0)
        base = cls.ellipsoid(origin + 14.0 * axis, axis, 10.0, 10.0)
        hand = cls.ellipsoid(insertion - 14.0 * axis, axis, 10.0, 10.0)
        cls.muscles = lhdl.producer(lhdl.named_blocks([("belly", belly)]), "belly")
        cls.bones = lhdl.producer(lhdl.named_blocks([("base", base), ("hand", hand)]), "bones")

    @staticmethod
    def ellipsoid(centre, axis, half_length, radius):
        from vtkmodules.vtkFiltersSources import vtkSphereSource
        from vtkmodules.vtkCommonDataModel import vtkPolyData
        sphere = vtkSphereSource()
        sphere.SetThetaResolution(24)
        sphere.SetPhiResolution(16)
        sphere.SetRadius(1.0)
        sphere.Update()
        surface = vtkPolyData()
        surface.DeepCopy(sphere.GetOutput())
        # z of the unit sphere along `axis`, scaled to the half length; x and y to the radius.
        side = numpy.cross(axis, [1.0, 0.0, 0.0])
        side /= numpy.linalg.norm(side)
        frame = numpy.column_stack([side * radius, numpy.cross(axis, side) * radius, axis * half_length])
        unit = mdtesting.points(surface)
        placed = unit @ frame.T + centre
        for k, p in enumerate(placed):
            surface.GetPoints().SetPoint(k, *p)
        return surface

    def run_motion(self, step):
        reader = simple.OpenSimModelReader(FileName=self.model, MotionFileName=self.motion_file, LoadGeometry=0,
                                           Scale=100, MomentArmStep=step)
        moved = simple.MoveWithBodies(Input=self.bones, BodyTransforms=simple.OutputPort(reader, 4),
                                      BodyOfSurface="base=ground; hand=arm")
        motion = simple.MotionMuscleDeformation(Input=self.muscles, BonesRest=self.bones, BonesMotion=moved,
                                                ActionLinesRest=simple.OutputPort(reader, 3),
                                                ActionLinesMotion=simple.OutputPort(reader, 1), NumberOfFibres=30)
        motion.UpdatePipelineInformation()
        times = list(motion.TimestepValues)
        self.assertEqual(len(times), self.FRAMES)
        motion.UpdatePipeline(times[-1])
        table = servermanager.Fetch(motion, idx=5)
        reader_table = servermanager.Fetch(reader, idx=6)
        transforms = servermanager.Fetch(reader, idx=4)
        paths = servermanager.Fetch(reader, idx=1)
        for proxy in (motion, moved, reader):
            simple.Delete(proxy)
        return table, reader_table, transforms, paths

    def test_the_reader_gives_each_frame_stepped_in_each_moving_coordinate(self):
        _, reader_table, transforms, paths = self.run_motion(self.STEP)
        self.assertEqual(transforms.GetNumberOfRows(), 2 * 5)  # ground and arm; the frame and 4 stepped poses
        self.assertEqual(column(transforms, "Pose"), [""] * 2 + [p for p in ("rx+", "rx-", "ry+", "ry-")
                                                                 for _ in range(2)])
        self.assertEqual(transforms.GetFieldData().GetArray("MomentArmStep").GetValue(0), self.STEP)
        # The path's length at +-step: OpenSim's moment arm (the reader's table) to O(step^2).
        path = mdtesting.block(paths, "belly")
        last = reader_table.GetNumberOfRows() - 1
        for coordinate in ("rx", "ry"):
            at = {}
            for sign in "+-":
                ends = vtk_to_numpy(path.GetPointData().GetArray("PointsAt(%s%s)" % (coordinate, sign)))
                at[sign] = numpy.linalg.norm(ends[1] - ends[0])
            arm = -(at["+"] - at["-"]) / (2 * math.radians(self.STEP))
            expected = column(reader_table, "MomentArm(belly, %s)" % coordinate)[last]
            self.assertAlmostEqual(arm, expected, delta=1e-3 * abs(expected) + 1e-6)

    def test_moment_arms_about_two_coordinates_moving_at_once(self):
        """Differences between frames cannot tell two coordinates apart (NaN); stepped poses give
        the action line OpenSim's moment arm about each at every frame, and the fibres theirs."""
        without, _, _, _ = self.run_motion(0.0)
        self.assertEqual(without.GetFieldData().GetAbstractArray("MomentArmsFrom").GetValue(0),
                         "differences between frames")
        self.assertTrue(all(math.isnan(v) for v in column(without, "MomentArm(belly, rx)")))
        table, reader_table, _, _ = self.run_motion(self.STEP)
        self.assertEqual(table.GetFieldData().GetAbstractArray("MomentArmsFrom").GetValue(0), "stepped poses")
        for coordinate in ("rx", "ry"):
            line = column(table, "MomentArm(belly, %s)" % coordinate)
            expected = column(reader_table, "MomentArm(belly, %s)" % coordinate)
            fibres = column(table, "FibreMomentArm(belly, %s)" % coordinate)
            low = column(table, "FibreMomentArmMin(belly, %s)" % coordinate)
            high = column(table, "FibreMomentArmMax(belly, %s)" % coordinate)
            print("[ measured ] about %s: the line %s, OpenSim %s, the fibres' median %s (mm a radian)" % (
                coordinate, " ".join("%.2f" % v for v in line), " ".join("%.2f" % v for v in expected),
                " ".join("%.2f" % v for v in fibres)))
            for k in range(self.FRAMES):
                self.assertAlmostEqual(line[k], expected[k], delta=1e-3 * abs(expected[k]) + 1e-6)
                self.assertTrue(low[k] <= fibres[k] <= high[k])
                # A straight belly's fibres run beside its line: their median moment arm near it.
                self.assertAlmostEqual(fibres[k], expected[k], delta=0.25 * abs(expected[k]) + 2.0)


if __name__ == "__main__":
    mdtesting.main()
