# SPDX-License-Identifier: BSD-3-Clause
"""Seconds of MuscleDeformation through pvpython, as a user meets them, at three muscle sizes.

    pvpython Testing/Benchmarks/benchmark_filter_scaling.py [data folder] [levels, e.g. 2 or 0,1,2]

The VHF gluteus maximus (24,220 points) and the same surface subdivided at its edges' midpoints
once (96,874) and twice (387,490), as BenchmarkScaling does in the core. Its action line: the
centroids of five slices along its long axis; the current pose turns it by 10 degrees about its
first point, then by 12 (a second pose, as when a user moves a slider). For each size it prints
the seconds of the first run (the hull and mean value coordinates built), of the second pose (both
kept) and of HullDecimation alone; give levels to measure only some sizes (e.g. 2: the 387k
surface alone, for its peak memory under /usr/bin/time -v). Asserts nothing.
"""
import math
import os
import sys
import time

import numpy
from paraview import simple
from vtkmodules.numpy_interface import dataset_adapter
from vtkmodules.vtkCommonCore import vtkDoubleArray, vtkPoints
from vtkmodules.vtkCommonDataModel import vtkCellArray, vtkPolyData
from vtkmodules.vtkFiltersGeneral import vtkTransformFilter
from vtkmodules.vtkFiltersModeling import vtkLinearSubdivisionFilter
from vtkmodules.vtkIOGeometry import vtkSTLReader

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "Python"))
import mdtesting  # noqa: E402

mdtesting.load_plugin()
data = mdtesting.mdexamples.data_dir(sys.argv[1] if len(sys.argv) > 1 else None)
path = os.path.join(data or "", "vhf_right", "VHF_Right_Muscle_GluteusMaximus_smooth.stl")
if not data or not os.path.exists(path):
    print("skipped: vhf_right/VHF_Right_Muscle_GluteusMaximus_smooth.stl not found (give the data folder)")
    sys.exit(0)


def action_line(muscle, degrees):
    """Slice centroids along the long axis, with CurrentPosition turned by `degrees`."""
    points = dataset_adapter.WrapDataObject(muscle).Points
    centred = points - points.mean(axis=0)
    _, vectors = numpy.linalg.eigh(centred.T @ centred)
    along = centred @ vectors[:, 2]
    slices = numpy.minimum((5 * (along - along.min()) / (along.max() - along.min())).astype(int), 4)
    rest = numpy.array([points[slices == s].mean(axis=0) for s in range(5)])
    axis, angle = vectors[:, 1], math.radians(degrees)
    # Rodrigues' rotation about `axis` through the first point.
    k = numpy.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
    turn = numpy.eye(3) + math.sin(angle) * k + (1 - math.cos(angle)) * k @ k
    current = (rest - rest[0]) @ turn.T + rest[0]
    line = vtkPolyData()
    line_points = vtkPoints()
    moved = vtkDoubleArray()
    moved.SetName("CurrentPosition")
    moved.SetNumberOfComponents(3)
    for p, q in zip(rest, current):
        line_points.InsertNextPoint(*p)
        moved.InsertNextTuple3(*q)
    cells = vtkCellArray()
    cells.InsertNextCell(5)
    for i in range(5):
        cells.InsertCellPoint(i)
    line.SetPoints(line_points)
    line.SetLines(cells)
    line.GetPointData().AddArray(moved)
    return line


levels = [int(level) for level in sys.argv[2].split(",")] if len(sys.argv) > 2 else [0, 1, 2]
reader = vtkSTLReader()
reader.SetFileName(path)
reader.Update()
muscle = vtkPolyData()
muscle.DeepCopy(reader.GetOutput())
print("points    first run s   second pose s   HullDecimation s   (hull + coordinates kept on the second pose)")
for level in range(max(levels) + 1):
    if level:
        subdivide = vtkLinearSubdivisionFilter()
        subdivide.SetInputData(muscle)
        subdivide.SetNumberOfSubdivisions(1)
        subdivide.Update()
        muscle = vtkPolyData()
        muscle.DeepCopy(subdivide.GetOutput())
    if level not in levels:
        continue
    source = simple.TrivialProducer()
    source.GetClientSideObject().SetOutput(muscle)
    lines = simple.TrivialProducer()
    lines.GetClientSideObject().SetOutput(action_line(muscle, 10))
    # HullDecimation first, and gone before the deformation: each filter's peak memory alone.
    hull = simple.HullDecimation(Input=source)
    start = time.perf_counter()
    hull.UpdatePipeline()
    hull_seconds = time.perf_counter() - start
    simple.Delete(hull)
    deformation = simple.MuscleDeformation(Input=source, ActionLines=lines)
    start = time.perf_counter()
    deformation.UpdatePipeline()
    first = time.perf_counter() - start
    lines.GetClientSideObject().SetOutput(action_line(muscle, 12))
    lines.MarkModified(lines)
    start = time.perf_counter()
    deformation.UpdatePipeline()
    second = time.perf_counter() - start
    print("%7d   %10.2f   %12.2f   %14.2f" % (muscle.GetNumberOfPoints(), first, second, hull_seconds))
    for proxy in (deformation, lines, source):
        simple.Delete(proxy)
