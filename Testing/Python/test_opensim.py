# SPDX-License-Identifier: BSD-3-Clause
"""OpenSimModelReader, MoveWithBodies and ActionLineGrouping as a pvpython user drives them: a
small model written here, bad input, and (when the data is present) OpenSim's own muscle lengths,
gait2392 played through, and the LHDL hip from its own OpenSim files."""
import csv
import math
import os
import unittest

import numpy
import mdtesting
import mdexamples
from paraview import servermanager, simple
from vtkmodules.vtkCommonCore import vtkDoubleArray
from vtkmodules.vtkCommonDataModel import vtkPolyData
from vtkmodules.vtkFiltersSources import vtkCubeSource, vtkLineSource
from vtkmodules.vtkIOXML import vtkXMLPolyDataWriter

mdtesting.load_plugin()
DATA = mdexamples.data_dir()

# OpenSim 3.x layout: a pin joint (about z, at (0, 1, 0)) between ground and 'upper', a mesh named
# the Windows way and scaled by 2, one muscle from ground to 'upper'.
SMALL_MODEL = """<?xml version="1.0" encoding="UTF-8" ?>
<OpenSimDocument Version="30000">
 <Model name="arm">
  <BodySet><objects>
   <Body name="ground"><VisibleObject><GeometrySet><objects /></GeometrySet></VisibleObject></Body>
   <Body name="upper">
    <Joint><PinJoint name="shoulder">
     <parent_body>ground</parent_body>
     <location_in_parent>0 1 0</location_in_parent><orientation_in_parent>0 0 0</orientation_in_parent>
     <location>0 0 0</location><orientation>0 0 0</orientation>
     <CoordinateSet><objects><Coordinate name="shoulder_angle"><default_value>0</default_value><range>-3.2 3.2</range></Coordinate></objects></CoordinateSet>
    </PinJoint></Joint>
    <VisibleObject>
     <GeometrySet><objects><DisplayGeometry><geometry_file>.\\geometry\\bone.vtp</geometry_file><scale_factors>1 1 1</scale_factors></DisplayGeometry></objects></GeometrySet>
     <scale_factors>2 2 2</scale_factors>
    </VisibleObject>
    <WrapObjectSet><objects><WrapSphere name="ball"><xyz_body_rotation>0 0 0</xyz_body_rotation><translation>0 -0.5 0</translation><radius>0.1</radius></WrapSphere></objects></WrapObjectSet>
   </Body>
  </objects></BodySet>
  <ForceSet><objects>
   <Thelen2003Muscle name="deltoid"><GeometryPath><PathPointSet><objects>
    <PathPoint name="origin"><location>0 1.5 0</location><body>ground</body></PathPoint>
    <PathPoint name="insertion"><location>0 -0.5 0</location><body>upper</body></PathPoint>
   </objects></PathPointSet></GeometryPath></Thelen2003Muscle>
  </objects></ForceSet>
 </Model>
</OpenSimDocument>
"""
MOTION = """arm
version=1
nRows=3
nColumns=2
inDegrees=yes
endheader
time\tshoulder_angle
0\t0
0.5\t90
1\t180
"""


def write(folder, name, text):
    path = os.path.join(folder, name)
    with open(path, "w") as f:
        f.write(text)
    return path


points = mdtesting.points
block = mdtesting.block


def output(proxy, port=0):
    """The output of the proxy's last update (at the time it was given): builtin session."""
    return proxy.GetClientSideObject().GetOutputDataObject(port)


field = mdtesting.field


def small_model_folder():
    folder = mdtesting.output_dir("opensim-small-model")
    os.makedirs(os.path.join(folder, "geometry"), exist_ok=True)
    cube = vtkCubeSource()
    cube.SetCenter(0, -0.25, 0)
    cube.SetXLength(0.1)
    cube.SetYLength(0.5)
    cube.SetZLength(0.1)
    writer = vtkXMLPolyDataWriter()
    writer.SetInputConnection(cube.GetOutputPort())
    writer.SetFileName(os.path.join(folder, "geometry", "bone.vtp"))
    writer.Write()
    write(folder, "arm.osim", SMALL_MODEL)
    write(folder, "arm.mot", MOTION)
    return folder


class SmallModel(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.folder = small_model_folder()

    def reader(self, **properties):
        with mdtesting.CapturedMessages() as messages:
            reader = simple.OpenSimModelReader(FileName=os.path.join(self.folder, "arm.osim"), **properties)
            reader.UpdatePipeline()
        return reader, messages.text

    def test_time_steps_bodies_paths_and_transforms(self):
        reader, messages = self.reader(MotionFileName=os.path.join(self.folder, "arm.mot"), Scale=1000.0)
        self.assertNotIn("ERR", messages)
        self.assertEqual(list(reader.TimestepValues), [0.0, 0.5, 1.0])
        rest_bone = points(block(servermanager.Fetch(reader, idx=2), "upper"))
        # The cube (0.5 long, below the joint) scaled by 2, in mm: from y = 1000 down to 0.
        self.assertAlmostEqual(rest_bone[:, 1].max(), 1000.0, places=9)
        self.assertAlmostEqual(rest_bone[:, 1].min(), 0.0, places=9)
        for time, angle in ((0.0, 0.0), (0.5, 90.0), (1.0, 180.0), (0.6, 90.0)):
            reader.UpdatePipeline(time)
            bone = points(block(output(reader, 0), "upper"))
            a = math.radians(angle)
            rotation = numpy.array([[math.cos(a), -math.sin(a), 0], [math.sin(a), math.cos(a), 0], [0, 0, 1]])
            joint = numpy.array([0.0, 1000.0, 0.0])
            expected = (rest_bone - joint) @ rotation.T + joint
            self.assertLess(numpy.abs(bone - expected).max(), 1e-9, time)
            path = block(output(reader, 1), "deltoid")
            insertion = joint + rotation @ numpy.array([0.0, -500.0, 0.0])
            self.assertLess(numpy.abs(points(path)[1] - insertion).max(), 1e-9)
            self.assertAlmostEqual(field(path, "PathLength"), numpy.linalg.norm(insertion - [0, 1500, 0]), places=9)
            self.assertEqual(path.GetPointData().GetAbstractArray("PathPointBody").GetValue(1), "upper")
            table = output(reader, 4)
            self.assertAlmostEqual(field(table, "shoulder_angle"), angle, places=9)
            row = [table.GetColumnByName("Body").GetValue(r) for r in range(table.GetNumberOfRows())].index("upper")
            r = numpy.array([[table.GetColumnByName("R%d%d" % (i, j)).GetValue(row) for j in range(3)] for i in range(3)])
            t = numpy.array([table.GetColumnByName(c).GetValue(row) for c in ("Tx", "Ty", "Tz")])
            self.assertLess(numpy.abs(rest_bone @ r.T + t - bone).max(), 1e-9)
            wrap = points(block(output(reader, 5), "ball"))
            self.assertLess(abs(numpy.linalg.norm(wrap.mean(axis=0) - insertion) - 0.0), 1.0)

    def test_file_open_offers_the_reader(self):
        reader = simple.OpenDataFile(os.path.join(self.folder, "arm.osim"))
        self.assertEqual(reader.GetXMLName(), "OpenSimModelReader")
        simple.Delete(reader)

    def test_a_fixed_pose(self):
        reader, _ = self.reader(MotionFileName=os.path.join(self.folder, "arm.mot"))
        reader.PlayMotion = 0
        reader.CurrentPoseTime = 0.5
        reader.UpdatePipelineInformation()
        reader.UpdatePipeline()
        self.assertEqual(len(reader.TimestepValues), 0)
        path = block(servermanager.Fetch(reader, idx=1), "deltoid")
        self.assertAlmostEqual(field(path, "PathLength"), math.sqrt(0.5), places=12)

    def test_move_with_bodies_and_action_line_grouping(self):
        reader, _ = self.reader(MotionFileName=os.path.join(self.folder, "arm.mot"))
        # A scanned 'upper' bone, named as files are, moves exactly as the model's body.
        surface = simple.PVTrivialProducer(registrationName="upper.vtk")
        cube = vtkCubeSource()
        cube.SetCenter(0.05, 0.5, 0)
        cube.Update()
        surface.GetClientSideObject().SetOutput(cube.GetOutput())
        group = simple.GroupDatasets(Input=[surface])
        moved = simple.MoveWithBodies(Input=group, BodyTransforms=simple.OutputPort(reader, 4))
        moved.UpdatePipeline(0.5)
        out = block(output(moved), "upper.vtk")
        rest = points(cube.GetOutput())
        expected = numpy.column_stack([-(rest[:, 1] - 1.0), rest[:, 0] + 1.0, rest[:, 2]])
        self.assertLess(numpy.abs(points(out) - expected).max(), 1e-12)
        self.assertEqual(out.GetFieldData().GetAbstractArray("Body").GetValue(0), "upper")
        # A surface that names no body: an error that says how to give it one.
        with mdtesting.CapturedMessages() as messages:
            simple.RenameSource("shoulder blade.vtk", surface)
            moved2 = simple.MoveWithBodies(Input=simple.GroupDatasets(Input=[surface]),
                                           BodyTransforms=simple.OutputPort(reader, 4))
            moved2.UpdatePipeline(0.5)
        self.assertIn("BodyOfSurface", messages.text)
        self.assertIn("ground, upper", messages.text)
        # The muscle path runs inside a box 'deltoid_surface' (most of it) and not inside 'other'.
        boxes = []
        for name, centre in (("deltoid_surface", (0, 1.25, 0)), ("other", (3, 0, 0))):
            box = vtkCubeSource()
            box.SetCenter(*centre)
            box.SetXLength(0.2)
            box.SetYLength(0.4)
            box.SetZLength(0.2)
            box.Update()
            source = simple.PVTrivialProducer(registrationName=name)
            source.GetClientSideObject().SetOutput(box.GetOutput())
            boxes.append(source)
        muscles = simple.GroupDatasets(Input=boxes)
        grouping = simple.ActionLineGrouping(Input=muscles, Paths=simple.OutputPort(reader, 3),
                                             PathsCurrent=simple.OutputPort(reader, 1))
        with mdtesting.CapturedMessages() as messages:
            grouping.UpdatePipeline()
        self.assertIn("'other': no path runs inside this muscle", messages.text)
        grouping.PathsOfMuscle = "other=deltoid"
        with mdtesting.CapturedMessages() as messages:
            grouping.UpdatePipeline()
        self.assertIn("'deltoid_surface': no path runs inside", messages.text)
        simple.Delete(grouping)
        grouping = simple.ActionLineGrouping(Input=simple.GroupDatasets(Input=[boxes[0]]),
                                             Paths=simple.OutputPort(reader, 3), PathsCurrent=simple.OutputPort(reader, 1))
        grouping.UpdatePipeline()
        lines = servermanager.Fetch(grouping, idx=0)
        decided = block(lines, "deltoid_surface")
        self.assertEqual(decided.GetFieldData().GetAbstractArray("ActionLinePaths").GetValue(0), "deltoid")
        # 0.4 of the path is inside; measured at the midpoints of 16 pieces.
        self.assertAlmostEqual(decided.GetFieldData().GetArray("PathInsideFraction").GetValue(0), 0.4, delta=1 / 16)
        self.assertEqual(decided.GetNumberOfPoints(), 2)
        # Through a motion the grouping is decided once: another time moves the current paths but
        # groups nothing again and says nothing again (it did at every frame, 4 of a frame's 10 ms
        # on the LHDL hip); a new PathsOfMuscle decides again.
        def current(t):
            grouping.UpdatePipeline(t)
            return points(block(grouping.GetClientSideObject().GetOutputDataObject(1), "deltoid_surface"))

        def rest_output():
            grouped = block(grouping.GetClientSideObject().GetOutputDataObject(0), "deltoid_surface")
            arrays = sorted(grouped.GetPointData().GetArrayName(a) for a in range(grouped.GetPointData().GetNumberOfArrays()))
            return points(grouped), arrays, grouped.GetFieldData().GetAbstractArray("ActionLinePaths").GetValue(0)

        start = current(0.0)
        rest_start = rest_output()
        with mdtesting.CapturedMessages() as messages:
            later = current(1.0)
        self.assertNotIn("ActionLineGrouping", messages.text)
        self.assertGreater(numpy.abs(later - start).max(), 0.1)
        # The rest pose's paths (output 0, kept from the first time rather than built again) are the same.
        rest_later = rest_output()
        self.assertEqual(rest_later[2], "deltoid")
        self.assertEqual(rest_later[1], rest_start[1])
        self.assertTrue(numpy.array_equal(rest_later[0], rest_start[0]))
        grouping.PathsOfMuscle = "deltoid_surface=deltoid"
        with mdtesting.CapturedMessages() as messages:
            current(0.5)
        self.assertIn("deltoid -> deltoid_surface (as given", messages.text)

    def test_grouping_follows_a_change_of_the_paths_arrays(self):
        # Output 0 (the rest pose's paths, grouped) is kept between updates while the grouping and
        # the paths are the same; a change of a path's array alone, its points unchanged, is seen.
        box = vtkCubeSource()
        box.SetXLength(2.0)
        box.Update()
        muscle = simple.PVTrivialProducer(registrationName="belly")
        muscle.GetClientSideObject().SetOutput(box.GetOutput())
        line = vtkLineSource()
        line.SetPoint1(-0.5, 0, 0)
        line.SetPoint2(0.5, 0, 0)
        line.Update()
        path = vtkPolyData()
        path.DeepCopy(line.GetOutput())
        tension = vtkDoubleArray()
        tension.SetName("Tension")
        tension.SetNumberOfTuples(path.GetNumberOfPoints())
        tension.Fill(1.0)
        path.GetPointData().AddArray(tension)
        paths = simple.PVTrivialProducer(registrationName="belly_path")
        paths.GetClientSideObject().SetOutput(path)
        grouping = simple.ActionLineGrouping(Input=simple.GroupDatasets(Input=[muscle]), Paths=paths)

        def grouped_tension():
            grouping.GetClientSideObject().Update()  # the proxy does not see a change made to the data
            grouped = block(grouping.GetClientSideObject().GetOutputDataObject(0), "belly")
            return grouped.GetPointData().GetArray("Tension").GetValue(0)

        self.assertEqual(grouped_tension(), 1.0)
        doubled = vtkDoubleArray()  # a new array: one changed in place may be shared with the output
        doubled.DeepCopy(tension)
        doubled.Fill(2.0)
        path.GetPointData().RemoveArray("Tension")
        path.GetPointData().AddArray(doubled)
        path.Modified()
        paths.GetClientSideObject().Modified()
        self.assertEqual(grouped_tension(), 2.0)
        simple.Delete(grouping)

    def test_a_path_over_a_wrap_ellipsoid(self):
        """opensim-core's ellipsoid length case read as a user would: a path along y = r over a
        quarter of the ellipsoid's section (radii 1, 0.5, 1) and down x = -1 has the tangents' and
        the quarter ellipse's length, draws its points over the ellipsoid on it, named after it, and
        the reader warns of nothing."""
        a, r = 1.0, 0.5
        text = """<?xml version="1.0"?>
<OpenSimDocument Version="40000"><Model name="ellipse"><Ground name="ground">
  <WrapObjectSet><objects><WrapEllipsoid name="pulley1"><dimensions>1 0.5 1</dimensions></WrapEllipsoid></objects></WrapObjectSet>
 </Ground>
 <ForceSet><objects><PathSpring name="spring1"><GeometryPath name="path"><PathPointSet><objects>
  <PathPoint name="origin"><socket_parent_frame>/ground</socket_parent_frame><location>0.4 0.5 0</location></PathPoint>
  <PathPoint name="insert"><socket_parent_frame>/ground</socket_parent_frame><location>-1 -0.5 0</location></PathPoint>
 </objects></PathPointSet>
 <PathWrapSet><objects><PathWrap name="w"><wrap_object>pulley1</wrap_object></PathWrap></objects></PathWrapSet>
 </GeometryPath></PathSpring></objects></ForceSet>
</Model></OpenSimDocument>"""
        with mdtesting.CapturedMessages() as messages:
            reader = simple.OpenSimModelReader(FileName=write(self.folder, "ellipse.osim", text), Scale=1000)
            reader.UpdatePipeline()
        self.assertNotIn("WARN", messages.text)
        self.assertNotIn("ERR", messages.text)
        path = block(output(reader, 1), "spring1")
        t = numpy.linspace(0.0, 0.5 * math.pi, 20001)
        speed = numpy.hypot(a * numpy.cos(t), r * numpy.sin(t))
        quarter = (t[1] - t[0]) / 3 * (speed[0] + speed[-1] + 4 * speed[1:-1:2].sum() + 2 * speed[2:-1:2].sum())
        self.assertAlmostEqual(field(path, "PathLength"), 1000 * (2 * r - 0.1 + quarter), delta=1e-6)
        names = path.GetPointData().GetAbstractArray("PathPointName")
        on = [names.GetValue(i) == "pulley1" for i in range(path.GetNumberOfPoints())]
        over = points(path)[numpy.array(on)] / 1000
        self.assertGreater(len(over), 10)
        numpy.testing.assert_allclose((over[:, 0] / a) ** 2 + (over[:, 1] / r) ** 2, 1.0, atol=1e-9)
        numpy.testing.assert_allclose(over[:, 2], 0.0, atol=1e-12)
        simple.Delete(reader)

    def test_bad_input_is_named(self):
        for text, expected in (
                (SMALL_MODEL.replace("</Model>", ""), "malformed XML"),
                (SMALL_MODEL.replace("PinJoint", "HingeJoint"), "unknown joint type 'HingeJoint'"),
                (SMALL_MODEL.replace("<body>upper</body>", "<body>uper</body>"), "body 'uper' is not in the model")):
            path = write(self.folder, "bad.osim", text)
            with mdtesting.CapturedMessages() as messages:
                reader = simple.OpenSimModelReader(FileName=path)
                reader.UpdatePipeline()
            self.assertIn(expected, messages.text)
            self.assertIn("bad.osim", messages.text)
            self.assertEqual(servermanager.Fetch(reader, idx=1).GetNumberOfBlocks(), 0)
            simple.Delete(reader)
        for motion, expected in (
                (MOTION.replace("time\tshoulder_angle", "elbow\tshoulder_angle"), "not 'time'"),
                (MOTION.replace("0.5\t90", "0.5\tnan"), "holds 'nan', not a finite number"),
                (MOTION.replace("shoulder_angle", "elbow_angle"), "column 'elbow_angle' names no coordinate")):
            path = write(self.folder, "bad.mot", motion)
            _, messages = self.reader(MotionFileName=path, IgnoreUnknownColumns=0)
            self.assertIn(expected, messages)
            self.assertIn("bad.mot", messages)
        _, messages = self.reader(MotionFileName=os.path.join(self.folder, "arm.mot"), IgnoreUnknownColumns=1)
        self.assertNotIn("ERR", messages)
        os.rename(os.path.join(self.folder, "geometry", "bone.vtp"), os.path.join(self.folder, "geometry", "b.vtp"))
        try:
            reader, messages = self.reader()
            self.assertIn("mesh files not found (the bodies still move)", messages)
            self.assertIn("bone.vtp (upper)", messages)
            self.assertEqual(block(servermanager.Fetch(reader, idx=0), "upper").GetNumberOfPoints(), 0)
        finally:
            os.rename(os.path.join(self.folder, "geometry", "b.vtp"), os.path.join(self.folder, "geometry", "bone.vtp"))


def read_lengths(path):
    """An OpenSim .sto table: its column labels and its rows of numbers."""
    with open(path) as f:
        lines = f.read().split("endheader")[1].strip().splitlines()
    return lines[0].split("\t"), [[float(v) for v in line.split()] for line in lines[1:]]


@unittest.skipIf(DATA is None or not os.path.isdir(os.path.join(DATA or "", "opensim")), "OpenSim data not found")
class OpenSimData(unittest.TestCase):
    def test_gait10dof18musc_lengths_through_the_reader(self):
        folder = os.path.join(DATA, "opensim", "gait10dof18musc_walk")
        reader = simple.OpenSimModelReader(FileName=os.path.join(folder, "walk_gait1018_subject01.osim"),
                                           MotionFileName=os.path.join(folder, "walk_gait1018_state_reference.mot"))
        times = list(reader.TimestepValues)
        self.assertEqual(len(times), 151)
        labels, rows = read_lengths(os.path.join(folder, "std_testGeometryPathWrapping_walk_gait1018_muscle_lengths.sto"))
        worst = 0.0
        for frame in (0, 40, 75, 119, 150):
            reader.UpdatePipeline(times[frame])
            paths = output(reader, 1)
            for column, label in enumerate(labels[1:], start=1):
                name = label.split("/")[-1].split("|")[0]
                worst = max(worst, abs(field(block(paths, name), "PathLength") - rows[frame][column]))
        self.assertLess(worst, 1e-6)
        # Bodies carry their meshes.
        bodies = servermanager.Fetch(reader, idx=0)
        self.assertEqual(block(bodies, "femur_r").GetNumberOfPoints(), 456)

    def test_rajagopal2016_wrapped_paths_through_the_reader(self):
        """14 of the model's 18 paths wrap over its cylinders: PathLength is OpenSim 4.4's, the drawn
        points over a cylinder are named after it, and the stepped poses (MomentArmStep) give
        every path as many points as the frame's, however much of a cylinder they wrap over."""
        folder = os.path.join(DATA, "opensim", "rajagopal2016_walk_armless_18musc")
        reader = simple.OpenSimModelReader(FileName=os.path.join(folder, "subject_walk_armless_18musc.osim"),
                                           MotionFileName=os.path.join(folder, "subject_walk_armless_coordinates.mot"),
                                           MomentArmStep=1.0)
        times = list(reader.TimestepValues)
        self.assertEqual(len(times), 238)
        labels, rows = read_lengths(os.path.join(folder, "std_testGeometryPathWrapping_subject_walk_armless_muscle_lengths.sto"))
        worst, wrapped = 0.0, set()
        reader.UpdatePipeline(times[0])
        wraps = output(reader, 5)
        wrap_names = {wraps.GetMetaData(b).Get(wraps.NAME()) for b in range(wraps.GetNumberOfBlocks())}
        self.assertEqual(len(wrap_names), 40)
        for frame in (0, 25, 60, 85, 138, 200):
            reader.UpdatePipeline(times[frame])
            paths = output(reader, 1)
            for column, label in enumerate(labels[1:], start=1):
                name = label.split("/")[-1].split("|")[0]
                path = block(paths, name)
                worst = max(worst, abs(field(path, "PathLength") - rows[frame][column]))
                names = path.GetPointData().GetAbstractArray("PathPointName")
                if any(names.GetValue(i) in wrap_names for i in range(path.GetNumberOfPoints())):
                    wrapped.add(name)
                stepped = [path.GetPointData().GetArray(a) for a in range(path.GetPointData().GetNumberOfArrays())]
                stepped = [a for a in stepped if a is not None and a.GetName().startswith("PointsAt(")]
                self.assertGreater(len(stepped), 0, name)  # +-1 degree in each coordinate the motion moves
                for array in stepped:
                    self.assertEqual(array.GetNumberOfTuples(), path.GetNumberOfPoints(), name)
        self.assertLess(worst, 1e-6)
        self.assertTrue({"med_gas_r", "med_gas_l", "glut_max2_r", "psoas_r", "semimem_r"} <= wrapped, wrapped)
        with mdtesting.CapturedMessages() as messages:
            simple.OpenSimModelReader(FileName=os.path.join(folder, "subject_walk_armless_18musc.osim")).UpdatePipeline()
        self.assertNotIn("not wrapped", messages.text)

    def test_gait2392_loads_with_its_meshes_and_plays(self):
        folder = os.path.join(DATA, "opensim", "gait2392_walk_forward")
        reader = simple.OpenSimModelReader(FileName=os.path.join(folder, "subject01_simbody_adjusted.osim"),
                                           MotionFileName=os.path.join(folder, "subject01_walk1_Kinematics_q.mot"))
        times = list(reader.TimestepValues)
        self.assertEqual(len(times), 175)
        for time in times:
            reader.UpdatePipeline(time)
        bodies = servermanager.Fetch(reader, idx=0)
        for name in ("pelvis", "femur_r", "tibia_r", "calcn_l", "torso"):
            self.assertGreater(block(bodies, name).GetNumberOfPoints(), 100, name)
        paths = servermanager.Fetch(reader, idx=1)
        self.assertEqual(paths.GetNumberOfBlocks(), 92)

    def test_gait2392_walks_in_place_about_its_pelvis(self):
        # FollowReferenceBody: the pelvis stays where it is at rest at every time, every other body
        # and path moves about it as in the ground frame, the lengths as they are.
        folder = os.path.join(DATA, "opensim", "gait2392_walk_forward")
        model, motion = (os.path.join(folder, "subject01_simbody_adjusted.osim"),
                         os.path.join(folder, "subject01_walk1_Kinematics_q.mot"))
        ground = simple.OpenSimModelReader(FileName=model, MotionFileName=motion, Scale=1000.0, ReferenceBody="pelvis")
        still = simple.OpenSimModelReader(FileName=model, MotionFileName=motion, Scale=1000.0, ReferenceBody="pelvis",
                                          FollowReferenceBody=1)
        rest = block(servermanager.Fetch(still, idx=2), "pelvis")
        travelled = 0.0
        for time in list(ground.TimestepValues)[::40]:
            ground.UpdatePipeline(time)
            still.UpdatePipeline(time)
            moving, kept = servermanager.Fetch(ground, idx=0), servermanager.Fetch(still, idx=0)
            self.assertLess(abs(points(block(kept, "pelvis")) - points(rest)).max(), 1e-9)
            travelled = max(travelled, abs(points(block(moving, "pelvis")) - points(rest)).max())
            # The same relative placement: distances from the pelvis to the other bodies' points.
            anchor_moving, anchor_kept = points(block(moving, "pelvis"))[0], points(block(kept, "pelvis"))[0]
            for name in ("femur_r", "tibia_l", "calcn_r", "torso"):
                numpy.testing.assert_allclose(numpy.linalg.norm(points(block(moving, name)) - anchor_moving, axis=1),
                                              numpy.linalg.norm(points(block(kept, name)) - anchor_kept, axis=1),
                                              atol=1e-6)
            for name in ("glut_max1_r", "soleus_l"):
                self.assertAlmostEqual(mdtesting.field(block(servermanager.Fetch(ground, idx=1), name), "PathLength"),
                                       mdtesting.field(block(servermanager.Fetch(still, idx=1), name), "PathLength"),
                                       places=9)
        self.assertGreater(travelled, 500.0)  # the walk carries the pelvis half a metre and more


@unittest.skipIf(DATA is None or not os.path.isdir(os.path.join(DATA or "", "lhdl_hip_r")), "LHDL data not found")
class LhdlFromItsOpenSimFiles(unittest.TestCase):
    def test_femur_and_action_lines_as_the_tables_give_them(self):
        import lhdl
        folder = os.path.join(DATA, "lhdl_hip_r")
        inputs = lhdl.load(folder, "hip_flexion", 35)
        self.assertEqual(inputs["frame"].hip_flexion, 60.0)
        femur_rest = points(block(servermanager.Fetch(inputs["bones_rest"]), "femur_r"))
        femur = points(block(servermanager.Fetch(inputs["bones_current"]), "femur_r"))
        with open(os.path.join(folder, "femur_transforms.csv")) as f:
            rows = {(r["motion"], int(r["frame"])): r for r in csv.DictReader(f)}

        def transform(row):
            r = numpy.array([float(row["r%d%d" % (i, j)]) for i in range(3) for j in range(3)]).reshape(3, 3)
            return r, numpy.array([float(row[c]) for c in ("tx_mm", "ty_mm", "tz_mm")])
        r, t = transform(rows[("hip_flexion", 35)])
        r0, t0 = transform(rows[("scan_pose_RP", 0)])
        # Relative to the table's own scan-pose row (t_z = -0.001 mm, its rounding).
        expected = (femur_rest - t0) @ numpy.linalg.inv(r0).T @ r.T + t
        self.assertLess(numpy.abs(femur - expected).max(), 1e-3)
        iliac = block(servermanager.Fetch(inputs["bones_current"]), "iliac_r")
        self.assertEqual(numpy.abs(points(iliac) - points(block(servermanager.Fetch(inputs["bones_rest"]), "iliac_r"))).max(), 0.0)
        # The paths grouped as the data set's README says, the psoas's conditional point gone at 60 degrees.
        grouping = simple.FindSource("LHDL action lines")
        rest = servermanager.Fetch(grouping, idx=0)
        current = servermanager.Fetch(grouping, idx=1)
        expected_groups = {"gluteus_maximus_r": {"glut_max1_r", "glut_max2_r", "glut_max3_r"},
                           "gluteus_medius_r": {"glut_med1_r", "glut_med2_r", "glut_med3_r"},
                           "iliacus_r": {"iliacus_r"}, "psoas_r": {"psoas_r"}}
        for muscle, paths in expected_groups.items():
            names = block(rest, muscle).GetFieldData().GetAbstractArray("ActionLinePaths")
            self.assertEqual({names.GetValue(i) for i in range(names.GetNumberOfValues())}, paths, muscle)
        self.assertEqual(block(rest, "psoas_r").GetNumberOfPoints(), 5)
        self.assertEqual(block(current, "psoas_r").GetNumberOfPoints(), 4)
        with open(os.path.join(folder, "action_lines_rp_mm.csv")) as f:
            csv_points = [r for r in csv.DictReader(f) if r["muscle"] == "glut_max1_r"]
        ours = points(block(rest, "gluteus_maximus_r"))[:4]
        theirs = numpy.array([[float(r[c]) for c in ("x_mm", "y_mm", "z_mm")] for r in csv_points])
        # The table's 3 decimals (5e-4 mm) and its scan pose's 1e-3 mm offset (see above).
        self.assertLess(numpy.abs(ours - theirs).max(), 2e-3)

    def test_the_state_file_loads_and_runs_the_method(self):
        state = os.path.join(mdtesting.SOURCE_DIR, "Examples", "LHDL_hip.pvsm")
        simple.LoadState(state, data_directory=os.path.join(DATA, "lhdl_hip_r"))
        method = simple.FindSource("Method")
        self.assertEqual(os.path.realpath(method.AttachmentFileName),
                         os.path.realpath(os.path.join(DATA, "lhdl_hip_r", "attachment_areas_rp_mm.csv")))
        self.assertEqual(list(method.TimestepValues), [0.0, 1.0, 2.0, 3.0, 4.0])
        with mdtesting.CapturedMessages() as messages:
            method.UpdatePipeline(4)
        for muscle in ("gluteus_maximus_r", "gluteus_medius_r", "iliacus_r", "psoas_r"):
            self.assertIn("muscle '%s.vtk': attached by landmarks" % muscle, messages.text)
        result = servermanager.Fetch(method)
        self.assertEqual({result.GetMetaData(i).Get(result.NAME()) for i in range(result.GetNumberOfBlocks())},
                         {m + ".vtk" for m in ("gluteus_maximus_r", "gluteus_medius_r", "iliacus_r", "psoas_r")})
        for index in range(result.GetNumberOfBlocks()):
            muscle = result.GetBlock(index)
            self.assertLess(abs(field(muscle, "VolumeChangePercent")), 1e-4)
            self.assertLessEqual(field(muscle, "MaxNewBonePenetrationDepth"), 0.5)
            self.assertEqual(field(muscle, "Converged"), 1)

    def test_the_readmes_motion_click_path_plays_the_motion(self):
        import lhdl_gui_pipeline
        folder = os.path.join(DATA, "lhdl_hip_r")
        pipeline = lhdl_gui_pipeline.build(folder, motion=True)
        motion = pipeline["method"]
        self.assertEqual(motion.GetXMLName(), "MotionMuscleDeformation")
        times = list(motion.TimestepValues)
        self.assertEqual(times, list(pipeline["model"].TimestepValues))  # Play Motion left on
        self.assertEqual(len(times), 36)
        with mdtesting.CapturedMessages() as messages:
            for time in times[:3]:  # frames in order, as Play asks for them
                motion.UpdatePipeline(time)
        muscles = ("gluteus_maximus_r", "gluteus_medius_r", "iliacus_r", "psoas_r")
        for muscle in muscles:
            self.assertIn("muscle '%s.vtk': attached by landmarks" % muscle, messages.text)
        result = servermanager.Fetch(motion)
        for index in range(result.GetNumberOfBlocks()):
            muscle = result.GetBlock(index)
            self.assertEqual(field(muscle, "Time"), times[2])
            self.assertLess(abs(field(muscle, "VolumeChangePercent")), 1e-4)
            self.assertEqual(field(muscle, "NewBonePenetrationCount"), 0)
            self.assertEqual(field(muscle, "Converged"), 1)
        self.assertEqual(servermanager.Fetch(motion, idx=3).GetNumberOfRows(), 3)  # MeasuresOverTime


if __name__ == "__main__":
    mdtesting.main()
