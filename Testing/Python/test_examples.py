# SPDX-License-Identifier: BSD-3-Clause
"""The example scripts run as a user runs them, and write what they promise."""
import glob
import json
import os
import shutil
import subprocess
import unittest

import mdtesting
from vtkmodules.vtkIOImage import vtkPNGReader
from vtkmodules.vtkIOXML import vtkXMLPolyDataReader

EXAMPLES = os.path.join(mdtesting.SOURCE_DIR, "Examples")


def run_example(script, output, *arguments):
    # Inside pvpython, sys.executable is not pvpython.
    pvpython = os.environ.get("MUSCLEDEFORMATION_PVPYTHON") or shutil.which("pvpython")
    command = [pvpython, os.path.join(EXAMPLES, script), "--output", output] + list(arguments)
    plugin = os.environ.get("MUSCLEDEFORMATION_PLUGIN")
    if plugin:
        command += ["--plugin", plugin]
    return subprocess.run(command, capture_output=True, text=True)


def non_white_fraction(png):
    reader = vtkPNGReader()
    reader.SetFileName(png)
    reader.Update()
    from vtkmodules.util.numpy_support import vtk_to_numpy
    pixels = vtk_to_numpy(reader.GetOutput().GetPointData().GetScalars())
    return float((pixels[:, :3].min(axis=1) < 250).mean())


class PhantomExample(unittest.TestCase):
    def test_writes_pictures_of_every_step_meshes_and_figures(self):
        output = mdtesting.output_dir("example-phantom")
        result = run_example("phantom_interpolation.py", output, "--steps", "3", "--flexion", "45")
        self.assertEqual(result.returncode, 0, result.stdout + result.stderr)
        self.assertIn(os.path.abspath(output), result.stdout)
        pictures = sorted(glob.glob(os.path.join(output, "phantom_*.png")))
        # rest, current, hulls, one-pass deformation, 4 steps of the bones, 4 of the whole method, one-pass resolved
        self.assertEqual(len(pictures), 4 + 4 + 4 + 1, pictures)
        for picture in pictures:
            self.assertGreater(non_white_fraction(picture), 0.02, picture)
        with open(os.path.join(output, "figures.json")) as f:
            figures = json.load(f)
        self.assertEqual(figures["number_of_steps"], 3)
        self.assertAlmostEqual(figures["steps"][3]["rotation_degrees_of_rigid_fit_per_block"]["Femur"], 45.0)
        for name, hull in figures["hulls"].items():
            self.assertEqual(hull["PointsOutsideHull"], 0, name)
            self.assertEqual(hull["HullSelfIntersections"], 0, name)
        for name, deformed in figures["deformation_one_pass"].items():
            self.assertLess(abs(deformed["VolumeChangePercent"]), 0.05, name)
            self.assertEqual(deformed["FlippedTriangleCount"], 0, name)
            self.assertEqual(deformed["Converged"], 1, name)
        self.assertTrue(os.path.isfile(os.path.join(output, "muscles_deformed_one_pass_RectusFemoris.vtp")))
        method = figures["interpolation_method"]
        self.assertEqual([step["step"] for step in method["steps"]], [0, 1, 2, 3])
        for name, measures in method["steps"][-1]["muscles"].items():
            self.assertLessEqual(abs(measures["VolumeChangePercent"]), 0.1, name)
            self.assertLessEqual(measures["MaxNewBonePenetrationDepth"], 0.5, name)
        self.assertTrue(os.path.isfile(os.path.join(output, "muscles_method_step_3_RectusFemoris.vtp")))
        reader = vtkXMLPolyDataReader()
        reader.SetFileName(os.path.join(output, "bones_step_3_Femur.vtp"))
        reader.Update()
        self.assertGreater(reader.GetOutput().GetNumberOfPolys(), 1000)


class MotionExample(unittest.TestCase):
    def test_the_phantom_through_a_sweep_writes_a_time_series_pictures_plots_and_figures(self):
        output = mdtesting.output_dir("example-motion")
        result = run_example("motion.py", output, "--case", "phantom")
        self.assertEqual(result.returncode, 0, result.stdout + result.stderr)
        folder = os.path.join(output, "phantom")
        with open(os.path.join(folder, "figures.json")) as f:
            figures = json.load(f)
        self.assertEqual(figures["frames"], 16)
        self.assertEqual(figures["frames_computed"], 16)  # each frame once, the pictures and plots from the cache
        self.assertLess(figures["largest_abs_volume_change_percent"], 1e-4)
        self.assertEqual(figures["largest_bone_penetration"], 0.0)
        self.assertTrue(figures["every_frame_converged"])
        self.assertLess(figures["largest_smoothness_ratio"], 6.0)  # measured 4.2: the rectus femoris at 28-30 degrees
        pictures = sorted(glob.glob(os.path.join(folder, "frames", "phantom_*.png")))
        self.assertEqual(len(pictures), 16)
        for picture in pictures[::5] + figures["plots"]:
            self.assertGreater(non_white_fraction(picture), 0.01, picture)
        with open(os.path.join(folder, "phantom.pvd")) as f:
            series = f.read()
        self.assertEqual(series.count("<DataSet "), 48)  # the muscles, the bones and the fibres at every frame
        for name in ("phantom_muscles_015.vtm", "phantom_bones_015.vtm", "phantom_fibres_015.vtm"):
            self.assertTrue(os.path.isfile(os.path.join(folder, name)), name)
        # The fibres inside their muscles and out of the bones at every frame (VTK's own test).
        self.assertEqual(sum(figures["fibre_points_outside_muscle"].values()), 0)
        self.assertEqual(sum(figures["fibre_points_inside_bone"].values()), 0)
        self.assertEqual(len(figures["measures"]["Time"]), 16)


if __name__ == "__main__":
    mdtesting.main()
