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


if __name__ == "__main__":
    mdtesting.main()
