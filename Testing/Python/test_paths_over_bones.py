# SPDX-License-Identifier: BSD-3-Clause
"""PathsOverBones as a pvpython user runs it on the LHDL hip (skipped, exit 77, without the data): the
reader's paths kept out of the scanned bones through both motions, at least as long as the
straight paths, moving no further between frames than the bones do, with moment arms from the
reader's stepped poses that agree with OpenSim 3.3's where the paths do not wrap."""
import json
import os
import sys
import unittest

import mdtesting
import mdexamples
import numpy
from paraview import servermanager, simple
from vtkmodules.vtkCommonDataModel import vtkPolyData

mdtesting.load_plugin()
DATA = mdexamples.data_dir()
BONES = ("iliac_r", "sacrum", "femur_r")
PER = 16  # PointsPerSegment + 1


leaves = mdexamples.named_leaves
field = mdtesting.field


def inside(points, surface):
    """Which of `points` (n x 3) lie inside the closed `surface`."""
    from vtkmodules.util.numpy_support import numpy_to_vtk
    from vtkmodules.vtkCommonCore import vtkPoints
    vtk_points = vtkPoints()
    vtk_points.SetData(numpy_to_vtk(numpy.ascontiguousarray(points), deep=True))
    cloud = vtkPolyData()
    cloud.SetPoints(vtk_points)
    return mdexamples.inside(cloud, surface)


def polyline_length(points):
    return float(numpy.sum(numpy.linalg.norm(numpy.diff(points, axis=0), axis=1)))


@unittest.skipIf(DATA is None or not os.path.isdir(os.path.join(DATA or "", "lhdl_hip_r")), "LHDL data not found")
class LhdlPathsOverBones(unittest.TestCase):
    def run_motion(self, motion):
        import lhdl
        folder = os.path.join(DATA, "lhdl_hip_r")
        reader = lhdl.model_reader(folder, motion, 0, play=True)
        reader.ConditionalPointFade = 10.0
        reader.MomentArmStep = 1.0
        bones = lhdl.producer(lhdl.named_blocks([(n, lhdl.read_surface(folder, n)) for n in BONES]), "bones")
        moved = simple.MoveWithBodies(Input=bones, BodyTransforms=simple.OutputPort(reader, 4),
                                      BodyOfSurface=lhdl.BODY_OF_SURFACE)
        over = simple.PathsOverBones(Input=simple.OutputPort(reader, 1), Bones=moved)
        frames = []
        for t in reader.TimestepValues:
            over.UpdatePipeline(t)
            paths = leaves(servermanager.Fetch(over))
            surfaces = leaves(servermanager.Fetch(moved))
            frames.append((t, paths, surfaces))
        table = servermanager.Fetch(reader, idx=6)
        for proxy in (over, moved, bones, reader):
            simple.Delete(proxy)
        return frames, table

    def check_motion(self, motion):
        frames, table = self.run_motion(motion)
        self.assertGreater(len(frames), 30)
        largest_step, largest_bone_step = {}, 0.0
        last = None
        wrapped = set()
        for k, (t, paths, surfaces) in enumerate(frames):
            candidates, labels = {}, {}
            for name, path in paths.items():
                points = mdtesting.points(path)
                self.assertEqual((len(points) - 1) % PER, 0)
                self.assertGreaterEqual(field(path, "PathLength"), field(path, "StraightPathLength") - 1e-9)
                if field(path, "PathLength") > field(path, "StraightPathLength") + 1e-3:
                    wrapped.add(name)
                # Between two of the path's own points that lie outside a bone, no point is in it.
                own = points[::PER]
                for bone, surface in surfaces.items():
                    own_in = inside(own, surface)
                    free = [i for i in range(len(points)) if i % PER and not own_in[i // PER] and not own_in[i // PER + 1]]
                    candidates.setdefault(bone, []).extend(points[i] for i in free)
                    labels.setdefault(bone, []).extend("%s point %d" % (name, i) for i in free)
                if last is not None:
                    step = numpy.max(numpy.linalg.norm(points - mdtesting.points(last[1][name]), axis=1))
                    largest_step[name] = max(largest_step.get(name, 0.0), float(step))
            for bone, points in candidates.items():
                entered = [labels[bone][i] for i in numpy.flatnonzero(inside(numpy.array(points), surfaces[bone]))]
                self.assertEqual(entered, [], "%s at %s: in %s" % (motion, t, bone))
            if last is not None:
                femur = mdtesting.points(surfaces["femur_r"]) - mdtesting.points(last[2]["femur_r"])
                largest_bone_step = max(largest_bone_step, float(numpy.max(numpy.linalg.norm(femur, axis=1))))
            last = (t, paths, surfaces)
        self.assertIn("iliacus_r", wrapped)  # over the iliac fossa, at every frame
        for name, step in largest_step.items():
            self.assertLessEqual(step, largest_bone_step, "%s %s jumps between frames" % (motion, name))
        # Moment arms from the stepped poses (r = -dL/dq) against the reader's (OpenSim's
        # definition, straight paths), where the path does not wrap; not of the psoas and the
        # iliacus, whose conditional points fade here (ConditionalPointFade) and not in the table.
        coordinate = "hip_flexion_r" if motion == "hip_flexion" else "hip_adduction_r"
        step = numpy.radians(1.0)
        compared = 0
        for k, (t, paths, surfaces) in enumerate(frames):
            for name, path in paths.items():
                above = mdtesting.vtk_to_numpy(path.GetPointData().GetArray("PointsAt(%s+)" % coordinate))
                below = mdtesting.vtk_to_numpy(path.GetPointData().GetArray("PointsAt(%s-)" % coordinate))
                if name in ("psoas_r", "iliacus_r") or any(
                        polyline_length(p) > polyline_length(p[::PER]) + 1e-3 for p in (above, below)):
                    continue
                arm = -(polyline_length(above) - polyline_length(below)) / (2 * step)
                reader_arm = table.GetColumnByName("MomentArm(%s, %s)" % (name, coordinate)).GetValue(k)
                self.assertAlmostEqual(arm, reader_arm, delta=0.05, msg="%s %s at %s" % (motion, name, t))
                compared += 1
        self.assertGreater(compared, 100)

    def test_hip_flexion(self):
        self.check_motion("hip_flexion")

    def test_hip_adduction(self):
        self.check_motion("hip_adduction")


if __name__ == "__main__":
    if DATA is None or not os.path.isdir(os.path.join(DATA, "lhdl_hip_r")):
        # Every test here needs the data: ctest reports the file skipped, not passed.
        print("SKIPPED: the LHDL data was not found (set MUSCLEDEFORMATION_DATA_DIR)")
        sys.exit(mdtesting.SKIPPED)
    mdtesting.main()
