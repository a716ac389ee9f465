# SPDX-License-Identifier: BSD-3-Clause
"""Seconds of InterpolatedMuscleDeformation through pvpython as a GUI user changes its settings.

    pvpython Testing/Benchmarks/benchmark_method_settings.py [data folder]

The LHDL hip (four muscles, flexion frame 35, as the main job) through the whole method, with
each DeformationMesh: solved on the muscles' surfaces (Muscle surface, the default), the first run
and a change of NumberOfSteps; solved on hulls (Hull (paper)), the first run (rest-pose hulls and mappings
built), then a change of NumberOfSteps, of BoneContactWeight and of ConvergenceTolerance (hulls
kept: only the steps are computed), then of HullTargetNumberOfPoints (every hull built again).
Then MuscleDeformation (one pass) on each DeformationMesh, a first run and a run again.
Prints each run's seconds (FilterTests counts the hulls:
InterpolatedMuscleDeformationFilter.RestHullsAreKept...). Asserts nothing.
"""
import os
import sys
import time

from paraview import simple

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "Python"))
sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "Examples"))
import mdtesting  # noqa: E402

mdtesting.load_plugin()
data = mdtesting.mdexamples.data_dir(sys.argv[1] if len(sys.argv) > 1 else None)
folder = os.path.join(data or "", "lhdl_hip_r")
if not data or not os.path.isdir(folder):
    print("skipped: lhdl_hip_r not found (give the data folder)")
    sys.exit(0)
import lhdl  # noqa: E402

inputs = lhdl.load(folder)
for source in inputs.values():
    if hasattr(source, "UpdatePipeline"):
        source.UpdatePipeline()
runs = {
    "Muscle surface": [("first run", None, None), ("NumberOfSteps 4 -> 3", "NumberOfSteps", 3)],
    "Hull (paper)": [("first run", None, None), ("NumberOfSteps 4 -> 3", "NumberOfSteps", 3),
                     ("BoneContactWeight 0.5 -> 0.25", "BoneContactWeight", 0.25),
                     ("ConvergenceTolerance 0.01 -> 0.005", "ConvergenceTolerance", 0.005),
                     ("HullTargetNumberOfPoints 250 -> 200", "HullTargetNumberOfPoints", 200)],
}
print("LHDL hip, frame %d (%.1f degrees of flexion), 4 muscles" % (inputs["frame"].index, inputs["frame"].hip_flexion))
for mesh, changes in runs.items():
    method = simple.InterpolatedMuscleDeformation(
        Input=inputs["muscles"], BonesRest=inputs["bones_rest"], BonesCurrent=inputs["bones_current"],
        ActionLinesRest=inputs["lines_rest"], ActionLinesCurrent=inputs["lines_current"], NumberOfSteps=4,
        DeformationMesh=mesh)
    print("DeformationMesh %s:" % mesh)
    for label, name, value in changes:
        if name:
            setattr(method, name, value)
        start = time.perf_counter()
        method.UpdatePipeline(method.TimestepValues[-1])
        seconds = time.perf_counter() - start
        print("  %-36s %6.2f s" % (label, seconds))
    simple.Delete(method)

# The one pass (MuscleDeformation) on each mesh: the first run builds the rest-pose work (hulls
# and mappings, or full-mesh energies), a second run keeps it.
matching = simple.ActionLineMatching(Input=inputs["lines_rest"], CurrentPose=inputs["lines_current"])
for mesh in ("Hull (paper)", "Muscle surface"):
    deformation = simple.MuscleDeformation(Input=inputs["muscles"], ActionLines=simple.OutputPort(matching, 0),
                                           Obstacles=[inputs["bones_current"]], DeformationMesh=mesh)
    print("MuscleDeformation, DeformationMesh %s:" % mesh)
    for label, iterations in (("first run", 200), ("MaximumNumberOfIterations 200 -> 199", 199)):
        deformation.MaximumNumberOfIterations = iterations  # the second run keeps the rest-pose work
        start = time.perf_counter()
        deformation.UpdatePipeline()
        seconds = time.perf_counter() - start
        print("  %-36s %6.2f s" % (label, seconds))
    simple.Delete(deformation)
