# SPDX-License-Identifier: BSD-3-Clause
"""MuscleFromPath as a pvpython user drives it, on the OpenSim Model Reader's rest-pose paths: a
small model written here (a muscle, a path actuator that is not one), a path with no properties,
a bone that holds a surface off, and (when the data is present) every muscle of the three OpenSim
models: each surface closed, manifold, of the volume its properties give, its path inside it, and
held off the model's bones; gait10dof18musc's generated muscles through its walk's first frames."""
import os
import tempfile
import unittest

import numpy
import mdtesting
import mdexamples
import motion as job  # Examples/motion.py: the main job's pipeline and its helpers
from paraview import servermanager, simple
from vtkmodules.vtkCommonDataModel import vtkPolyData
from vtkmodules.vtkFiltersCore import vtkFeatureEdges, vtkMassProperties, vtkTriangleFilter
from vtkmodules.vtkFiltersModeling import vtkSelectEnclosedPoints
from vtkmodules.vtkFiltersSources import vtkCubeSource, vtkLineSource

mdtesting.load_plugin()
DATA = mdexamples.data_dir()

# OpenSim 4 layout: ground and 'shank' on a pin joint at (0, 1, 0); a Thelen muscle from the
# ground at (0, 1.5, 0) to the shank at (0, -0.5, 0), 1 m long at rest, and a path actuator.
MODEL = """<?xml version="1.0" encoding="UTF-8" ?>
<OpenSimDocument Version="40000">
 <Model name="leg">
  <BodySet><objects><Body name="shank"><mass>1</mass></Body></objects></BodySet>
  <JointSet><objects>
   <PinJoint name="knee">
    <socket_parent_frame>ground_offset</socket_parent_frame><socket_child_frame>shank_offset</socket_child_frame>
    <coordinates><Coordinate name="knee_angle"><default_value>0</default_value></Coordinate></coordinates>
    <frames>
     <PhysicalOffsetFrame name="ground_offset"><socket_parent>/ground</socket_parent><translation>0 1 0</translation><orientation>0 0 0</orientation></PhysicalOffsetFrame>
     <PhysicalOffsetFrame name="shank_offset"><socket_parent>/bodyset/shank</socket_parent><translation>0 0 0</translation><orientation>0 0 0</orientation></PhysicalOffsetFrame>
    </frames>
   </PinJoint>
  </objects></JointSet>
  <ForceSet><objects>
   <Thelen2003Muscle name="vastus">
    <GeometryPath><PathPointSet><objects>
     <PathPoint name="origin"><location>0 1.5 0</location><socket_parent_frame>/ground</socket_parent_frame></PathPoint>
     <PathPoint name="insertion"><location>0 -0.5 0</location><socket_parent_frame>/bodyset/shank</socket_parent_frame></PathPoint>
    </objects></PathPointSet></GeometryPath>
    <max_isometric_force>600</max_isometric_force>
    <optimal_fiber_length>0.3</optimal_fiber_length>
    <tendon_slack_length>0.4</tendon_slack_length>
    <pennation_angle_at_optimal>0.1</pennation_angle_at_optimal>
   </Thelen2003Muscle>
   <PathActuator name="motor">
    <GeometryPath><PathPointSet><objects>
     <PathPoint name="a"><location>0.1 1.5 0</location><socket_parent_frame>/ground</socket_parent_frame></PathPoint>
     <PathPoint name="b"><location>0.1 -0.5 0</location><socket_parent_frame>/bodyset/shank</socket_parent_frame></PathPoint>
    </objects></PathPointSet></GeometryPath>
    <optimal_force>10</optimal_force>
   </PathActuator>
  </objects></ForceSet>
 </Model>
</OpenSimDocument>
"""


def edges(surface):
    """Boundary and non-manifold edges of a surface."""
    features = vtkFeatureEdges()
    features.SetInputData(surface)
    features.BoundaryEdgesOn()
    features.NonManifoldEdgesOn()
    features.FeatureEdgesOff()
    features.ManifoldEdgesOff()
    features.Update()
    return features.GetOutput().GetNumberOfCells()


def volume(surface):
    mass = vtkMassProperties()
    mass.SetInputData(surface)
    mass.Update()
    return mass.GetVolume()


def path_points_outside(path, surface, count=40):
    """Points along `path` between its ends (the ends lie on the surface's caps) not inside `surface`."""
    p = mdtesting.points(path)
    at = numpy.concatenate([[0], numpy.cumsum(numpy.linalg.norm(numpy.diff(p, axis=0), axis=1))])
    samples = numpy.array([[numpy.interp(s, at, p[:, k]) for k in range(3)]
                           for s in numpy.linspace(0, at[-1], count + 1)[1:-1]])
    queries = vtkPolyData()
    queries.SetPoints(vtk_points(samples))
    return len(samples) - count_inside(queries, surface)


def vtk_points(array):
    from vtkmodules.vtkCommonCore import vtkPoints
    points = vtkPoints()
    for q in array:
        points.InsertNextPoint(*q)
    return points


def count_inside(points, surface):
    """How many of the points of the dataset `points` lie inside the closed `surface`."""
    enclosed = vtkSelectEnclosedPoints()
    enclosed.SetInputData(points)
    enclosed.SetSurfaceData(surface)
    enclosed.SetTolerance(1e-9)
    enclosed.Update()
    selected = enclosed.GetOutput().GetPointData().GetArray("SelectedPoints")
    return sum(selected.GetValue(i) for i in range(selected.GetNumberOfTuples()))


def points_in_closed_bones(muscles, bones):
    """How many of the muscles' surface points lie inside any of `bones` (closed surfaces)."""
    return sum(count_inside(surface, bone) for _, surface in muscles for bone in bones)


def points_in_other_muscles(muscles):
    """How many of the muscles' surface points lie inside another of them (pairs whose boxes meet)."""
    def meet(a, b):
        return all(a[2 * k] <= b[2 * k + 1] and b[2 * k] <= a[2 * k + 1] for k in range(3))
    return sum(count_inside(first, second) for a, (_, first) in enumerate(muscles)
               for b, (_, second) in enumerate(muscles) if a != b and meet(first.GetBounds(), second.GetBounds()))


def leaves(data):
    """(name, block) of every block of a multiblock, in order."""
    return [(data.GetMetaData(i).Get(data.NAME()), data.GetBlock(i)) for i in range(data.GetNumberOfBlocks())]


class MuscleFromPathTest(unittest.TestCase):
    def made(self, osim, bones=False, **properties):
        reader = simple.OpenSimModelReader(FileName=osim, Scale=1000.0)
        muscles = simple.MuscleFromPath(Input=simple.OutputPort(reader, 3), **properties)
        if bones:
            muscles.Bones = simple.OutputPort(reader, 2)
        with mdtesting.CapturedMessages() as messages:
            muscles.UpdatePipeline()
        return servermanager.Fetch(reader, idx=3), servermanager.Fetch(muscles), messages.text

    def test_a_muscle_gets_a_closed_surface_of_its_volume_and_an_actuator_none(self):
        folder = tempfile.mkdtemp()
        osim = os.path.join(folder, "leg.osim")
        with open(osim, "w") as f:
            f.write(MODEL)
        paths, muscles, messages = self.made(osim)
        # The reader gives the muscle's properties, lengths in mm as every length of its output.
        vastus = mdtesting.block(paths, "vastus")
        self.assertEqual(mdtesting.field(vastus, "max_isometric_force"), 600)
        self.assertAlmostEqual(mdtesting.field(vastus, "optimal_fiber_length"), 300, places=9)
        self.assertAlmostEqual(mdtesting.field(vastus, "tendon_slack_length"), 400, places=9)
        self.assertAlmostEqual(mdtesting.field(vastus, "pennation_angle_at_optimal"), 0.1, places=12)
        self.assertAlmostEqual(mdtesting.field(vastus, "MetresPerLengthUnit"), 0.001, places=15)
        self.assertEqual(vastus.GetFieldData().GetAbstractArray("MuscleType").GetValue(0), "Thelen2003Muscle")
        self.assertIsNone(mdtesting.block(paths, "motor").GetFieldData().GetArray("max_isometric_force"))
        # 600 N at 60 N/cm^2 is 10 cm^2 = 1000 mm^2; times 300 mm: 300,000 mm^3.
        surface = mdtesting.block(muscles, "vastus")
        self.assertEqual(edges(surface), 0)
        self.assertAlmostEqual(volume(surface) / 300000.0, 1.0, places=5)
        self.assertAlmostEqual(mdtesting.field(surface, "EstimatedVolume"), 300000.0, places=6)
        self.assertAlmostEqual(mdtesting.field(surface, "PhysiologicalCrossSectionalArea"), 1000.0, places=9)
        # The belly: the path (1000 mm) less the tendon (400 mm), the tendon shared by both ends.
        self.assertAlmostEqual(mdtesting.field(surface, "BellyStart"), 200.0, places=6)
        self.assertAlmostEqual(mdtesting.field(surface, "BellyEnd"), 800.0, places=6)
        self.assertLessEqual(surface.GetNumberOfPoints(), 600)
        self.assertEqual(path_points_outside(vastus, surface), 0)
        # The path actuator is not a muscle: its block is empty and says why; the muscle is made.
        motor = mdtesting.block(muscles, "motor")
        self.assertEqual(motor.GetNumberOfPoints(), 0)
        self.assertEqual(mdtesting.field(motor, "DeformationFailed"), 1)
        self.assertIn("these paths are not muscles and get no surface (their blocks are left empty): "
                      "motor (PathActuator)", messages)
        self.assertNotIn("ERR", messages)
        # A bone beside the path holds the surface off, and the rest widens to keep the volume.
        bone = vtkCubeSource()
        bone.SetBounds(15, 100, -500, 1500, -100, 100)
        bone.Update()
        triangles = vtkTriangleFilter()
        triangles.SetInputData(bone.GetOutput())
        triangles.Update()
        source = simple.TrivialProducer()
        source.GetClientSideObject().SetOutput(triangles.GetOutput())
        reader = simple.OpenSimModelReader(FileName=osim, Scale=1000.0)
        held = simple.MuscleFromPath(Input=simple.OutputPort(reader, 3), Bones=source)
        held.UpdatePipeline()
        held_vastus = mdtesting.block(servermanager.Fetch(held), "vastus")
        self.assertGreater(mdtesting.field(held_vastus, "PointsHeldByBones"), 0)
        self.assertAlmostEqual(mdtesting.field(held_vastus, "VolumeKept"), 1.0, places=6)
        self.assertLess(mdtesting.points(held_vastus)[:, 0].max(), 15)
        self.assertGreater(mdtesting.points(surface)[:, 0].max(), 15)
        self.assertAlmostEqual(volume(held_vastus) / 300000.0, 1.0, places=5)
        # Half the tension, twice the volume; more points, the same volume.
        _, stronger, _ = self.made(osim, SpecificTension=30.0, NumberOfPoints=3000)
        self.assertAlmostEqual(volume(mdtesting.block(stronger, "vastus")) / 600000.0, 1.0, places=5)

    def test_a_path_without_properties_is_an_error_not_a_crash(self):
        line = vtkLineSource()
        line.SetPoint1(0, 0, 0)
        line.SetPoint2(0, 0, 100)
        line.Update()
        source = simple.TrivialProducer()
        source.GetClientSideObject().SetOutput(line.GetOutput())
        muscles = simple.MuscleFromPath(Input=source)
        with mdtesting.CapturedMessages() as messages:
            muscles.UpdatePipeline()
        self.assertIn("has no max_isometric_force, optimal_fiber_length, tendon_slack_length, MetresPerLengthUnit",
                      messages.text)
        self.assertEqual(servermanager.Fetch(muscles).GetNumberOfPoints(), 0)

    def check_model(self, relative, count):
        if DATA is None or not os.path.isfile(os.path.join(DATA, relative)):
            self.skipTest("OpenSim data not found: set MUSCLEDEFORMATION_DATA_DIR to the folder holding opensim/")
        in_bones, in_others = {}, {}
        for apart in (False, True):
            paths, muscles, messages = self.made(os.path.join(DATA, relative), bones=apart, KeepMusclesApart=apart)
            made = leaves(muscles)
            self.assertEqual(len(made), count)
            self.assertNotIn("ERR", messages)
            worst, cramped = 0.0, []
            for name, surface in made:
                self.assertEqual(edges(surface), 0, name)
                self.assertEqual(path_points_outside(mdtesting.block(paths, name), surface), 0, name)
                # The volume is the estimate, or the share of it kept is said.
                kept = mdtesting.field(surface, "VolumeKept")
                self.assertAlmostEqual(volume(surface) / mdtesting.field(surface, "EstimatedVolume"), kept, places=5)
                worst = max(worst, abs(kept - 1))
                if kept < 0.99:
                    cramped.append(name)
                    self.assertIn(name + " %d %%" % int(100 * kept), messages)
            if not apart:
                self.assertLess(worst, 1e-6)
            in_bones[apart] = points_in_closed_bones(made, self.closed_bones(relative))
            in_others[apart] = points_in_other_muscles(made)
            print("%s, %s: %d muscles, each closed with its path inside; %d surface points inside the model's closed "
                  "bones, %d inside another muscle; volume kept below 99 %% by %s"
                  % (relative, "kept off the bones and apart" if apart else "each alone", len(made), in_bones[apart],
                     in_others[apart], ", ".join(cramped) or "none"))
        # Held off the bones and apart, at most half as many points are in them; those left are
        # where a path itself runs in a bone (an attachment, a via point under the bone's surface)
        # or paths cross or meet.
        self.assertLess(in_bones[True], 0.5 * in_bones[False])
        self.assertLess(in_others[True], 0.5 * in_others[False])

    def closed_bones(self, relative):
        reader = simple.OpenSimModelReader(FileName=os.path.join(DATA, relative), Scale=1000.0)
        bones = servermanager.Fetch(reader, idx=2)
        return [b for _, b in leaves(bones) if b is not None and b.GetNumberOfPoints() > 0 and edges(b) == 0]

    def test_every_muscle_of_gait2392(self):
        self.check_model("opensim/gait2392_walk_forward/subject01_simbody_adjusted.osim", 92)

    def test_every_muscle_of_rajagopal2016(self):
        self.check_model("opensim/rajagopal2016_walk_armless_18musc/subject_walk_armless_18musc.osim", 18)

    def test_every_muscle_of_gait10dof18musc(self):
        self.check_model("opensim/gait10dof18musc_walk/walk_gait1018_subject01.osim", 18)

    def test_gait10dof18musc_walks_with_every_generated_muscle(self):
        """The whole model's muscles made from its paths go through the first frames of its walk
        together (MotionMuscleDeformation, fibres too), each keeping its volume, none going
        into another or deeper into a bone, every frame settled: at 150 points the contact set of
        these crowded muscles cycles, and without the damping of a long settle's cycles (ShapeStep)
        frame 4 does not settle."""
        folder = "opensim/gait10dof18musc_walk/"
        if DATA is None or not os.path.isdir(os.path.join(DATA, folder)):
            self.skipTest("OpenSim data not found: set MUSCLEDEFORMATION_DATA_DIR to the folder holding opensim/")
        reader = simple.OpenSimModelReader(FileName=os.path.join(DATA, folder, "walk_gait1018_subject01.osim"),
                                           MotionFileName=os.path.join(DATA, folder, "walk_gait1018_state_reference.mot"),
                                           Scale=1000.0, ReferenceBody="pelvis", FollowReferenceBody=1,
                                           ConditionalPointFade=10.0)
        muscles = simple.MuscleFromPath(Input=simple.OutputPort(reader, 3), Bones=simple.OutputPort(reader, 2),
                                        NumberOfPoints=150)
        motion = simple.MotionMuscleDeformation(Input=muscles, BonesRest=simple.OutputPort(reader, 2),
                                                BonesMotion=simple.OutputPort(reader, 0),
                                                ActionLinesRest=simple.OutputPort(reader, 3),
                                                ActionLinesMotion=simple.OutputPort(reader, 1), NumberOfFibres=20)
        frames = reader.TimestepValues[:12]
        with mdtesting.CapturedMessages() as messages:
            for t in frames:
                motion.UpdatePipeline(t)
        self.assertNotIn("ERR", messages.text)
        self.assertNotIn("has no fibres", messages.text)
        columns = job.table_columns(servermanager.Fetch(motion, idx=3))
        self.assertEqual(len(columns["Time"]), len(frames))

        def measure(name):
            found = {column.split(" (")[1][:-1]: values for column, values in columns.items()
                     if column.startswith(name + " (")}
            self.assertEqual(len(found), 18, name)
            return [v for values in found.values() for v in values]

        self.assertLess(max(abs(v) for v in measure("VolumeChangePercent")), 1e-4)
        self.assertEqual(max(measure("NewPenetrationCount")), 0)
        self.assertLessEqual(max(measure("MaxNewBonePenetrationDepth")), 0.5)
        self.assertEqual(set(measure("Converged")), {1})
        fibres = leaves(servermanager.Fetch(motion, idx=4))
        self.assertEqual(len(fibres), 18)
        self.assertTrue(all(block is not None and block.GetNumberOfCells() == 20 for _, block in fibres))


if __name__ == "__main__":
    mdtesting.main()
