# SPDX-License-Identifier: BSD-3-Clause
"""Rendered views of the phantom compared with committed baselines (made with Mesa llvmpipe).

Set MUSCLEDEFORMATION_UPDATE_BASELINES=1 to write new baselines after a deliberate change.
"""
import os
import unittest

import mdtesting
import mdexamples
import phantom_interpolation
from paraview import simple

mdtesting.load_plugin()
SIZE = (600, 600)


class Images(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.output = mdtesting.output_dir("images")
        cls.pipeline = mdexamples.interpolation_pipeline(phantom_interpolation.phantom_inputs(60.0), 4, "Rigid")
        cls.view = mdexamples.make_view(SIZE)

    @classmethod
    def tearDownClass(cls):
        mdexamples.close_view(cls.view)

    def compare(self, name, time=None):
        fresh = mdexamples.screenshot(self.view, os.path.join(self.output, name), time=time)
        mdtesting.assert_matches_baseline(self, fresh, name, self.output)

    def test_rest_pose(self):
        mdexamples.show_pose(self.view, self.pipeline, "rest")
        phantom_interpolation.lateral_camera(self.view)
        self.compare("PhantomRestPose.png")

    def test_current_pose_femur_sweeps_into_the_rectus_femoris(self):
        mdexamples.show_pose(self.view, self.pipeline, "current")
        phantom_interpolation.lateral_camera(self.view)
        self.compare("PhantomCurrentPose60.png")

    def test_phantom_deformed_in_one_pass_at_60_degrees(self):
        mdexamples.show_deformed(self.view, self.pipeline)
        phantom_interpolation.lateral_camera(self.view)
        self.compare("PhantomDeformed60.png")

    def test_middle_step_rigid_against_linear(self):
        """Step 2 of 4: the rigid femur (bone colour) and the linear one (red), shorter by 13 %."""
        mdexamples.show_steps(self.view, self.pipeline)
        linear = simple.BoneInterpolation(Input=self.pipeline["bones_rest"],
                                          CurrentPose=self.pipeline["bones_current"],
                                          NumberOfSteps=4, InterpolationMode="Linear")
        mdexamples.show_surface(linear, self.view, [0.85, 0.2, 0.2], opacity=0.5)
        phantom_interpolation.lateral_camera(self.view)
        self.compare("PhantomStep2RigidAndLinear.png", time=2)
        simple.Hide(linear, self.view)
        simple.Delete(linear)


class SwallowedMuscle(Images):
    """Paper Figs. 5-6 on the phantom at 30 degrees: the femur sweeps into the rectus femoris.
    In one pass the swallowed part stays in the bone and is thrown out flat against it ("fixed on
    the bone"); in 8 steps the femur pushes the muscle along and it lies along the bone."""

    @classmethod
    def setUpClass(cls):
        cls.output = mdtesting.output_dir("images")
        cls.pipeline = mdexamples.interpolation_pipeline(phantom_interpolation.phantom_inputs(30.0), 8, "Rigid")
        cls.view = mdexamples.make_view(SIZE)

    def test_one_pass(self):
        mdexamples.show_method(self.view, self.pipeline, "one_pass")
        phantom_interpolation.lateral_camera(self.view)
        self.compare("PhantomOnePass30.png", time=1)

    def test_interpolated(self):
        mdexamples.show_method(self.view, self.pipeline)
        phantom_interpolation.lateral_camera(self.view)
        self.compare("PhantomInterpolated30.png", time=8)

    # The views of the 60-degree pipeline are not repeated here.
    test_rest_pose = test_current_pose_femur_sweeps_into_the_rectus_femoris = None
    test_phantom_deformed_in_one_pass_at_60_degrees = test_middle_step_rigid_against_linear = None


if __name__ == "__main__":
    mdtesting.main()
