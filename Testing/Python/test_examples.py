# SPDX-License-Identifier: BSD-3-Clause
"""The example scripts run as a user runs them (the batch script also under pvbatch --mpi on two
ranks), and write what they promise."""
import glob
import json
import os
import re
import shutil
import subprocess
import unittest

import mdtesting
import numpy
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
        # A bone where it was at a frame written before (the pelvis at the sweep's end, where it
        # started) is not written again: the series refers to that file. Read back as ParaView
        # reads the series.
        from vtkmodules.vtkIOXML import vtkXMLMultiBlockDataReader
        from vtkmodules.util.numpy_support import vtk_to_numpy
        frames = []
        for k in (0, 15):
            reader = vtkXMLMultiBlockDataReader()
            reader.SetFileName(os.path.join(folder, "phantom_bones_%03d.vtm" % k))
            reader.Update()
            frames.append([vtk_to_numpy(reader.GetOutput().GetBlock(b).GetPoints().GetData()) for b in range(2)])
        with open(os.path.join(folder, "phantom_bones_015.vtm")) as f:
            last = f.read()
        self.assertIn('file="phantom_bones_000/phantom_bones_000_0.vtp"', last)
        self.assertIn('file="phantom_bones_015/phantom_bones_015_1.vtp"', last)
        self.assertTrue(numpy.array_equal(frames[0][0], frames[1][0]))
        self.assertGreater(numpy.abs(frames[0][1] - frames[1][1]).max(), 1.0)
        # Each warning once, not at every frame; the movie encoder's chatter kept out of the log.
        self.assertLessEqual(result.stderr.count("is not rigid"), 3, result.stderr)
        self.assertNotIn("swscaler", result.stderr + result.stdout)
        # The fibres inside their muscles and out of the bones at every frame (VTK's own test).
        self.assertEqual(sum(figures["fibre_points_outside_muscle"].values()), 0)
        self.assertEqual(sum(figures["fibre_points_inside_bone"].values()), 0)
        self.assertEqual(len(figures["measures"]["Time"]), 16)


class LhdlMotionExample(unittest.TestCase):
    def test_the_lhdl_bones_are_written_once_and_replayed_by_the_state_file(self):
        import mdexamples
        data = mdexamples.data_dir()
        if not os.path.isdir(os.path.join(data, "lhdl_hip_r")):
            self.skipTest("the LHDL data set is absent (%s)" % data)
        output = mdtesting.output_dir("example-motion-lhdl")
        result = run_example("motion.py", output, "--case", "hip_flexion", "--data", data, "--frames", "3",
                             "--moment-arm-step", "0", "--every", "100")
        self.assertEqual(result.returncode, 0, result.stdout + result.stderr)
        name = "lhdl_hip_flexion"
        folder = os.path.join(output, name)
        with open(os.path.join(folder, "figures.json")) as f:
            figures = json.load(f)
        # The bones replayed from the written files (rest bones, the bodies' transforms) are those
        # the filter used, to the bit; they are not in the series at every frame.
        self.assertEqual(figures["bones_replay_largest_difference"], 0.0)
        self.assertEqual(glob.glob(os.path.join(folder, name + "_bones_0*")), [])
        with open(os.path.join(folder, name + ".pvd")) as f:
            self.assertEqual(f.read().count("<DataSet "), 6)  # the muscles and the fibres at every frame
        with open(os.path.join(folder, name + "_transforms.pvd")) as f:
            self.assertEqual(f.read().count("<DataSet "), 3)
        # The state file opens them as File > Load State does, searching the case's folder (here
        # moved elsewhere): the muscles, the fibres and the moving bones, at every frame.
        moved = os.path.join(output, "moved")
        shutil.rmtree(moved, ignore_errors=True)
        shutil.copytree(folder, os.path.join(moved, name))
        from paraview import simple
        mdtesting.load_plugin()
        simple.LoadState(os.path.join(moved, name, name + ".pvsm"), data_directory=os.path.join(moved, name))
        bones, series = simple.FindSource("Bones"), simple.FindSource(name + ".pvd")
        self.assertEqual(len(series.TimestepValues), 3)
        femur, pelvis = [], []
        for t in series.TimestepValues:
            bones.UpdatePipeline(t)
            leaves = mdexamples.named_leaves(simple.servermanager.Fetch(bones))
            femur.append(mdtesting.points(leaves["femur_r"]))
            pelvis.append(mdtesting.points(leaves["iliac_r"]))
        self.assertGreater(numpy.abs(femur[0] - femur[2]).max(), 1.0)  # the femur flexes 4 degrees
        self.assertTrue(numpy.array_equal(pelvis[0], pelvis[2]))  # the motion holds the pelvis


def leaves_of(path):
    """Every polydata file under `path`, relative to it."""
    return sorted(os.path.relpath(f, path) for f in glob.glob(os.path.join(path, "**", "*.vtp"), recursive=True))


def same_surfaces(a, b):
    """Whether two written surfaces hold the same points, cells and arrays, bit for bit (the arrays
    of seconds apart: times differ from run to run)."""
    from vtkmodules.util.numpy_support import vtk_to_numpy
    data = []
    for path in (a, b):
        reader = vtkXMLPolyDataReader()
        reader.SetFileName(path)
        reader.Update()
        data.append(reader.GetOutput())
    if not numpy.array_equal(vtk_to_numpy(data[0].GetPoints().GetData()), vtk_to_numpy(data[1].GetPoints().GetData())):
        return False
    if not numpy.array_equal(vtk_to_numpy(data[0].GetPolys().GetData()), vtk_to_numpy(data[1].GetPolys().GetData())):
        return False
    for attributes in ("GetPointData", "GetFieldData"):
        first, second = getattr(data[0], attributes)(), getattr(data[1], attributes)()
        for i in range(first.GetNumberOfArrays()):
            name = first.GetArrayName(i)
            if "Seconds" in name or first.GetArray(i) is None:
                continue
            if second.GetArray(name) is None or not numpy.array_equal(
                    vtk_to_numpy(first.GetArray(i)), vtk_to_numpy(second.GetArray(name)), equal_nan=True):
                return False
    return True


class ReadmeExample(unittest.TestCase):
    def test_the_readmes_pvpython_script_runs_as_it_stands(self):
        with open(os.path.join(mdtesting.SOURCE_DIR, "README.md")) as f:
            blocks = re.findall(r"```python\n(.*?)```", f.read(), re.S)
        scripts = [b for b in blocks if b.startswith("from paraview.simple import *")]
        self.assertEqual(len(scripts), 1, "the README's complete pvpython script")
        plugin = os.environ.get("MUSCLEDEFORMATION_PLUGIN")
        script = scripts[0]
        if plugin:  # the README's relative path is where the set-up commands build it
            script = re.sub(r'LoadPlugin\("[^"]*"', 'LoadPlugin(%r' % plugin, script)
        path = os.path.join(mdtesting.output_dir("example-readme"), "readme.py")
        with open(path, "w") as f:
            f.write(script)
        pvpython = os.environ.get("MUSCLEDEFORMATION_PVPYTHON") or shutil.which("pvpython")
        result = subprocess.run([pvpython, path], capture_output=True, text=True, cwd=mdtesting.SOURCE_DIR,
                                timeout=300)
        self.assertEqual(result.returncode, 0, result.stdout + result.stderr)
        self.assertIn("16 frames of measures", result.stdout)


class BatchExample(unittest.TestCase):
    def test_trials_spread_over_two_ranks_give_what_one_process_gives(self):
        mpiexec, pvbatch = shutil.which("mpiexec"), shutil.which("pvbatch")
        if not mpiexec or not pvbatch:
            self.skipTest("mpiexec or pvbatch not found")
        output = mdtesting.output_dir("example-batch")
        trials = os.path.join(output, "trials.json")
        with open(trials, "w") as f:
            json.dump([{"name": "sweep_20", "kind": "phantom", "frames": 4, "flexion": 20.0},
                       {"name": "sweep_30", "kind": "phantom", "frames": 4, "flexion": 30.0},
                       {"name": "broken", "kind": "opensim", "model": "missing.osim", "motion": "missing.mot"}], f)
        # pvpython (built with MPI) started MPI alone: its Open MPI variables would make mpiexec
        # take itself for a child of this process.
        environment = {k: v for k, v in os.environ.items() if not k.startswith(("OMPI_", "PMIX_", "OPAL_"))}
        environment.update(OMP_NUM_THREADS="1", OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1",
                           OMPI_MCA_rmaps_base_oversubscribe="1")
        script = [os.path.join(EXAMPLES, "batch.py"), "--trials", trials]
        plugin = os.environ.get("MUSCLEDEFORMATION_PLUGIN")
        script += ["--plugin", plugin] if plugin else []
        summaries = {}
        for ranks in (1, 2):
            folder = os.path.join(output, "ranks_%d" % ranks)
            launch = [pvbatch] if ranks == 1 else [mpiexec, "-n", "2", pvbatch, "--mpi", "--symmetric"]
            result = subprocess.run(launch + script + ["--output", folder], capture_output=True, text=True,
                                    env=environment, timeout=500)
            self.assertEqual(result.returncode, 0, result.stdout + result.stderr)
            with open(os.path.join(folder, "summary.json")) as f:
                summaries[ranks] = json.load(f)
        self.assertEqual(summaries[2]["ranks"], 2)
        trials = summaries[2]["trials"]
        self.assertEqual([trials[name]["rank"] for name in ("sweep_20", "sweep_30", "broken")], [0, 1, 0])
        self.assertIn("missing.osim", trials["broken"]["error"])  # one bad trial does not stop the others
        for name in ("sweep_20", "sweep_30"):
            self.assertEqual(trials[name]["frames"], 5)
            self.assertTrue(trials[name]["every_frame_settled"], name)
            self.assertLess(trials[name]["max_abs_volume_change_percent"], 1e-4)
            self.assertEqual(trials[name]["max_new_bone_penetration_depth"], 0.0)
        one, two = (os.path.join(output, "ranks_%d" % ranks) for ranks in (1, 2))
        written = leaves_of(one)
        self.assertEqual(len(written), 2 * 5 * 3)  # two trials, five frames, three muscles
        self.assertEqual(written, leaves_of(two))
        for path in written:
            self.assertTrue(same_surfaces(os.path.join(one, path), os.path.join(two, path)), path)


if __name__ == "__main__":
    mdtesting.main()
