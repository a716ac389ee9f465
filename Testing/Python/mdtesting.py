# SPDX-License-Identifier: BSD-3-Clause
"""Shared set-up of the pvpython tests: paths, the plugin, captured VTK messages, skipping."""
import os
import shutil
import sys
import unittest

HERE = os.path.dirname(os.path.abspath(__file__))
SOURCE_DIR = os.path.dirname(os.path.dirname(HERE))
sys.path.insert(0, os.path.join(SOURCE_DIR, "Examples"))

import mdexamples  # noqa: E402
from paraview import simple  # noqa: E402
from vtkmodules.vtkCommonCore import vtkOutputWindow, vtkStringOutputWindow  # noqa: E402

import numpy  # noqa: E402
from vtkmodules.util.numpy_support import vtk_to_numpy  # noqa: E402

SKIPPED = 77  # ctest SKIP_RETURN_CODE
# The end of the small knee models of the fuzz and the fault cases: one muscle from ground to the
# shank over a conditional path point, then the model closed.
KNEE_MUSCLE = """ <ForceSet><objects><Thelen2003Muscle name="m"><GeometryPath name="path"><PathPointSet><objects>
  <PathPoint name="a"><socket_parent_frame>/ground</socket_parent_frame><location>0 1 0</location></PathPoint>
  <ConditionalPathPoint name="c"><socket_parent_frame>/bodyset/shank</socket_parent_frame><location>0.1 -0.5 0</location><socket_coordinate>/jointset/knee/angle</socket_coordinate><range>-1 1</range></ConditionalPathPoint>
  <PathPoint name="b"><socket_parent_frame>/bodyset/shank</socket_parent_frame><location>0 -1 0</location></PathPoint>
 </objects></PathPointSet></GeometryPath></Thelen2003Muscle></objects></ForceSet>
</Model></OpenSimDocument>
"""
# An ASCII legacy VTK tetrahedron (closed, outward), a body's mesh file.
TETRAHEDRON = ("# vtk DataFile Version 3.0\ntetrahedron\nASCII\nDATASET POLYDATA\nPOINTS 4 float\n"
               "0 0 0 0.1 0 0 0 0.1 0 0 0 0.1\nPOLYGONS 4 16\n3 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 3\n")
BASELINE_DIR = os.path.join(SOURCE_DIR, "Testing", "Baseline")


def output_dir(name):
    """A fresh folder for what a test writes (never the baseline folder)."""
    root = os.environ.get("MUSCLEDEFORMATION_TEST_OUTPUT") or os.path.join(os.getcwd(), "test-output")
    path = os.path.join(root, name)
    os.makedirs(path, exist_ok=True)
    return path


def points(data):
    """The points of a dataset as an n x 3 float64 array."""
    return vtk_to_numpy(data.GetPoints().GetData()).astype(numpy.float64)


def field(data, name):
    """The value of a one-value field-data array of `data`."""
    array = data.GetFieldData().GetArray(name)
    if array is None:
        raise KeyError(name)
    return array.GetValue(0)


def block(data, name):
    """The block of a multiblock named `name`."""
    for index in range(data.GetNumberOfBlocks()):
        if data.GetMetaData(index).Get(data.NAME()) == name:
            return data.GetBlock(index)
    raise KeyError(name)


def assert_matches_baseline(test, fresh, name, output):
    """Compares the image `fresh` with Testing/Baseline/`name` (vtkTesting, threshold 10), or
    makes it the baseline when MUSCLEDEFORMATION_UPDATE_BASELINES=1."""
    from vtkmodules.vtkTestingRendering import vtkTesting
    baseline = os.path.join(BASELINE_DIR, name)
    if os.environ.get("MUSCLEDEFORMATION_UPDATE_BASELINES") == "1":
        shutil.copyfile(fresh, baseline)
    test.assertTrue(os.path.isfile(baseline), "no baseline %s" % baseline)
    testing = vtkTesting()
    for argument in ("-V", os.path.abspath(baseline), "-T", os.path.abspath(output)):
        testing.AddArgument(argument)
    test.assertEqual(testing.RegressionTest(os.path.abspath(fresh), 10.0), vtkTesting.PASSED,
                     "%s differs from its baseline; see %s" % (name, output))


def landmarks(coordinates, arrays):
    """Landmarks as the deformation filters' Attachments input takes them: a vtkPolyData of
    `coordinates` with a string point array per item of `arrays` (name: the value of every point)."""
    from vtkmodules.vtkCommonCore import vtkPoints, vtkStringArray
    from vtkmodules.vtkCommonDataModel import vtkPolyData
    data = vtkPolyData()
    points = vtkPoints()
    for p in coordinates:
        points.InsertNextPoint(*p)
    data.SetPoints(points)
    for name, value in arrays.items():
        array = vtkStringArray()
        array.SetName(name)
        for _ in coordinates:
            array.InsertNextValue(value)
        data.GetPointData().AddArray(array)
    return data


def load_plugin():
    return mdexamples.load_plugin(explicit=os.environ.get("MUSCLEDEFORMATION_PLUGIN"))


class CapturedMessages:
    """Collects VTK's errors and warnings while in a `with` block."""

    def __enter__(self):
        self.previous = vtkOutputWindow.GetInstance()
        self.window = vtkStringOutputWindow()
        vtkOutputWindow.SetInstance(self.window)
        return self

    def __exit__(self, *exc):
        vtkOutputWindow.SetInstance(self.previous)
        return False

    @property
    def text(self):
        text = self.window.GetOutput()
        # VTK hands back bytes when the messages are not UTF-8 (a file name or a block name of
        # another encoding, quoted in a message).
        return text.decode("utf-8", "replace") if isinstance(text, bytes) else text


def main():
    """Runs the tests of the calling module; exit code 0 only when all passed."""
    program = unittest.main(exit=False, verbosity=2)
    result = program.result
    if result.testsRun == 0:
        sys.exit(1)
    sys.exit(0 if result.wasSuccessful() else 1)
