# SPDX-License-Identifier: BSD-3-Clause
"""The interpolation method and the static intersection resolution as a pvpython user drives them."""
import unittest

import numpy
import mdtesting
from paraview import servermanager, simple
from vtkmodules.util.numpy_support import vtk_to_numpy

mdtesting.load_plugin()

MUSCLES = ("Iliopsoas", "GluteusMaximus", "RectusFemoris")


points = mdtesting.points
block = mdtesting.block


field = mdtesting.field


class Interpolation(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.phantom = simple.MusculoskeletalPhantom(Flexion=30)
        cls.phantom.UpdatePipeline()

    def method(self, **properties):
        port = lambda k: simple.OutputPort(self.phantom, k)  # noqa: E731
        values = dict(Input=port(0), BonesRest=port(1), BonesCurrent=port(2), ActionLinesRest=port(3),
                      ActionLinesCurrent=port(4))
        values.update(properties)
        return simple.InterpolatedMuscleDeformation(**values)

    def test_names_and_defaults(self):
        method = simple.InterpolatedMuscleDeformation()
        self.assertEqual(method.NumberOfSteps, 4)
        self.assertEqual(method.BoneInterpolationMode, "Rigid")
        self.assertEqual(method.DeformationMesh, "Muscle surface")
        self.assertEqual(method.HullMode, "Refit")
        self.assertEqual(method.PreserveVolume, 1)
        self.assertAlmostEqual(method.BoneContactWeight, 0.5)
        resolve = simple.IntersectionResolve()
        self.assertAlmostEqual(resolve.DeformableShare, 0.6)
        simple.Delete(resolve)
        # The phantom opens at 30 degrees, where the method at its default 4 steps turns no
        # triangle over (at 60 it turns 5 of the rectus femoris's over): the best case first.
        phantom = simple.MusculoskeletalPhantom()
        self.assertEqual(phantom.Flexion, 30)
        simple.Delete(phantom)
        simple.Delete(method)

    def test_every_step_is_a_time_step_with_every_measure(self):
        method = self.method(NumberOfSteps=2)
        with mdtesting.CapturedMessages() as messages:
            method.UpdatePipelineInformation()
            self.assertEqual(list(method.TimestepValues), [0.0, 1.0, 2.0])
            method.UpdatePipeline(0)
        # The phantom's rectus femoris runs from a point fixed below the hip to the knee, so its
        # action line passes through the femur as the hip flexes: the one thing said, by name.
        said = [line for line in messages.text.splitlines() if line.strip() and not line.startswith("Warning: In ")]
        # First, how the muscles are attached: the phantom gives no landmarks, and its muscles'
        # ends lie clear of the bones, so none is attached (each said by name).
        report = [line for line in said if "attachment area" in line]
        self.assertEqual(report[0], "InterpolatedMuscleDeformation, attachment areas:")
        for name in MUSCLES:
            self.assertIn("  muscle '%s': no attachment area (it moves with its action lines only)" % name, report)
        said = [line for line in said if line not in report]
        # Then the fibres each muscle got (100 by default), between its ends along its lines.
        fibres = said[said.index("InterpolatedMuscleDeformation, fibres:"):][:len(MUSCLES) + 1]
        for name in MUSCLES:
            self.assertIn("  muscle '%s': 100 fibres from its end along its action lines to its end along its "
                          "action lines" % name, fibres)
        said = [line for line in said if line not in fibres]
        self.assertEqual(len(said), 1, messages.text)
        self.assertIn("muscle 'RectusFemoris' crosses bone 'Femur'", said[0])
        rest = servermanager.Fetch(simple.OutputPort(self.phantom, 0))
        first = servermanager.Fetch(method)
        for name in MUSCLES:
            self.assertTrue(numpy.array_equal(points(block(first, name)), points(block(rest, name))), name)
            self.assertEqual(field(block(first, name), "InterpolationStep"), 0)
        elapsed = field(block(first, "RectusFemoris"), "ElapsedSeconds")
        method.UpdatePipeline(2)
        last = servermanager.Fetch(method)
        for name in MUSCLES:
            muscle = block(last, name)
            self.assertEqual(field(muscle, "InterpolationStep"), 2, name)
            self.assertEqual(field(muscle, "NumberOfSteps"), 2, name)
            self.assertLessEqual(abs(field(muscle, "VolumeChangePercent")), 0.1, name)
            self.assertLessEqual(field(muscle, "MaxNewBonePenetrationDepth"), 0.5, name)
            for measure in ("NewPenetrationCount", "MaxNewPenetrationDepth", "MaxStaticShift", "SharpEdgeCount",
                            "FlippedTriangleCount", "NumberOfIterations", "ElapsedSeconds", "HullSeconds"):
                field(muscle, measure)
            displacement = vtk_to_numpy(muscle.GetPointData().GetArray("Displacement"))
            self.assertTrue(numpy.allclose(points(block(rest, name)) + displacement, points(muscle)), name)
            self.assertIsNotNone(muscle.GetPointData().GetArray("StaticShift"), name)
        # Solved on the surfaces, contact is a constraint: nothing is left for the static
        # resolution to move (on the hull it is: see the test below).
        for name in MUSCLES:
            self.assertEqual(field(block(last, name), "MaxStaticShift"), 0.0, name)
        # Every step was computed once: the run behind step 2 is the one behind step 0.
        self.assertEqual(field(block(last, "RectusFemoris"), "ElapsedSeconds"), elapsed)
        simple.Delete(method)

    def test_on_the_hull_bones_push_the_muscle_unless_the_contact_weight_is_zero(self):
        # The femur sweeps into the rectus femoris: pushed along by it, the muscle needs a far
        # shorter static resolution than with the paper's step (here 6.5 against 11.5 mm).
        shifts = {}
        for weight in (0.5, 0.0):
            method = self.method(NumberOfSteps=4, DeformationMesh="Hull (paper)", BoneContactWeight=weight)
            method.UpdatePipeline(4)
            muscle = block(servermanager.Fetch(method), "RectusFemoris")
            shifts[weight] = field(muscle, "MaxStaticShift")
            self.assertLessEqual(abs(field(muscle, "VolumeChangePercent")), 0.1)
            self.assertLessEqual(field(muscle, "MaxNewBonePenetrationDepth"), 0.5)
            simple.Delete(method)
        self.assertLess(shifts[0.5], 0.75 * shifts[0.0])

    def test_on_the_muscle_surface_the_hull_is_no_part_of_the_answer(self):
        # Issue 13: solved on the hull, the hull's size changes the muscles; solved on the
        # muscles' own surfaces, it changes nothing, and no point enters a bone or
        # another muscle. Also no sharper, no more folded than on the hull (measured on the
        # rectus femoris: 0 sharp edges and flips against 54 and 0).
        def last_points(**properties):
            method = self.method(NumberOfSteps=4, **properties)
            method.UpdatePipeline(4)
            result = servermanager.Fetch(method)
            simple.Delete(method)
            return {name: block(result, name) for name in MUSCLES}

        surface = last_points(DeformationMesh="Muscle surface", HullTargetNumberOfPoints=250)
        coarse = last_points(DeformationMesh="Muscle surface", HullTargetNumberOfPoints=150)
        hull = last_points(DeformationMesh="Hull (paper)", HullTargetNumberOfPoints=250)
        hull_coarse = last_points(DeformationMesh="Hull (paper)", HullTargetNumberOfPoints=150)
        for name in MUSCLES:
            self.assertTrue(numpy.array_equal(points(surface[name]), points(coarse[name])), name)
            self.assertEqual(field(surface[name], "NewPenetrationCount"), 0, name)
            self.assertEqual(field(surface[name], "MaxStaticShift"), 0.0, name)
            self.assertLess(abs(field(surface[name], "VolumeChangePercent")), 1e-4, name)
            self.assertEqual(field(surface[name], "Converged"), 1, name)
            for measure in ("SharpEdgeCount", "FlippedTriangleCount"):
                self.assertLessEqual(field(surface[name], measure), field(hull[name], measure), name)
        apart = max(numpy.abs(points(hull[name]) - points(hull_coarse[name])).max() for name in MUSCLES)
        self.assertGreater(apart, 0.1)  # on the hull the hull's size shows (measured: millimetres)

    def test_a_motion_of_zero_length_returns_the_input(self):
        port = lambda k: simple.OutputPort(self.phantom, k)  # noqa: E731
        method = self.method(BonesCurrent=port(1), ActionLinesCurrent=port(3))
        with mdtesting.CapturedMessages() as messages:
            method.UpdatePipeline(4)
        self.assertIn("zero length", messages.text)
        rest = servermanager.Fetch(port(0))
        result = servermanager.Fetch(method)
        for name in MUSCLES:
            self.assertTrue(numpy.array_equal(points(block(result, name)), points(block(rest, name))), name)
        simple.Delete(method)

    def test_bad_input_names_the_input(self):
        port = lambda k: simple.OutputPort(self.phantom, k)  # noqa: E731
        # Muscles without action lines: surfaces given as lines.
        method = self.method(ActionLinesRest=port(0), ActionLinesCurrent=port(0))
        with mdtesting.CapturedMessages() as messages:
            method.UpdatePipeline(1)
        self.assertIn("ActionLinesRest block 'Iliopsoas' has no polylines", messages.text)
        simple.Delete(method)
        # Bone blocks that do not pair.
        method = self.method(BonesCurrent=port(0))
        with mdtesting.CapturedMessages() as messages:
            method.UpdatePipeline(1)
        self.assertIn("BonesRest block 'Pelvis' has no block of the same name in BonesCurrent", messages.text)
        method.BonesCurrent = port(2)
        with mdtesting.CapturedMessages() as messages:
            method.UpdatePipeline(1)
        self.assertNotIn("ERROR", messages.text)
        simple.Delete(method)


class StaticResolution(unittest.TestCase):
    def test_the_one_pass_result_comes_out_of_the_femur_and_rest_overlap_stays(self):
        phantom = simple.MusculoskeletalPhantom(Flexion=30)
        port = lambda k: simple.OutputPort(phantom, k)  # noqa: E731
        matching = simple.ActionLineMatching(Input=port(3), CurrentPose=port(4))
        deformed = simple.MuscleDeformation(Input=port(0), ActionLines=simple.OutputPort(matching, 0),
                                            Obstacles=[port(2)])
        resolve = simple.IntersectionResolve(Input=deformed, Obstacles=[port(2)], InputRest=port(0),
                                             ObstaclesRest=[port(1)])
        with mdtesting.CapturedMessages() as messages:
            resolve.UpdatePipeline()
        self.assertNotIn("ERROR", messages.text)
        before = servermanager.Fetch(deformed)
        after = servermanager.Fetch(resolve)
        rectus = block(after, "RectusFemoris")
        self.assertGreater(field(rectus, "PenetratingPointCount"), 100)
        self.assertGreater(field(rectus, "MaxStaticShift"), 10.0)
        for name in MUSCLES:
            muscle = block(after, name)
            self.assertEqual(field(muscle, "NewPenetrationCount"), 0, name)
            shift = vtk_to_numpy(muscle.GetPointData().GetArray("StaticShift"))
            self.assertTrue(numpy.allclose(points(block(before, name)) + shift, points(muscle)), name)
        # Without the rest pose, overlap the scans had would move too: never less.
        resolve.InputRest = None
        resolve.ObstaclesRest = []
        resolve.UpdatePipeline()
        everything = servermanager.Fetch(resolve)
        for name in MUSCLES:
            self.assertGreaterEqual(field(block(everything, name), "PenetratingPointCount"),
                                    field(block(after, name), "PenetratingPointCount"), name)
        for proxy in (resolve, deformed, matching, phantom):
            simple.Delete(proxy)


if __name__ == "__main__":
    mdtesting.main()
