# SPDX-License-Identifier: BSD-3-Clause
"""The LHDL example on the real right-hip data; skipped (exit 77) when the data is absent."""
import glob
import json
import os
import sys
import unittest

import mdtesting
import mdexamples
from test_examples import run_example, non_white_fraction

DATA = mdexamples.data_dir()


class LhdlExample(unittest.TestCase):
    def test_sixty_degrees_of_hip_flexion(self):
        output = mdtesting.output_dir("example-lhdl")
        result = run_example("lhdl_hip_interpolation.py", output, "--motion", "hip_flexion", "--frame", "35")
        self.assertEqual(result.returncode, 0, result.stdout + result.stderr)
        pictures = sorted(glob.glob(os.path.join(output, "lhdl_*.png")))
        # rest, current, hulls, one-pass deformation, 5 steps of the bones, 5 of the whole method, one-pass resolved
        self.assertEqual(len(pictures), 4 + 5 + 5 + 1)
        for picture in pictures:
            self.assertGreater(non_white_fraction(picture), 0.02, picture)
        with open(os.path.join(output, "figures.json")) as f:
            figures = json.load(f)
        self.assertEqual(figures["hip_flexion_degrees"], 60.0)
        last = figures["steps"][-1]
        self.assertAlmostEqual(last["rotation_degrees_of_rigid_fit_per_block"]["femur_r"], 58.598, places=2)
        self.assertLess(last["rotation_degrees_of_rigid_fit_per_block"]["iliac_r"], 1e-9)
        self.assertEqual(set(figures["hulls"]), {"gluteus_maximus_r", "gluteus_medius_r", "iliacus_r", "psoas_r"})
        for name, hull in figures["hulls"].items():
            self.assertEqual(hull["PointsOutsideHull"], 0, name)
            self.assertEqual(hull["HullSelfIntersections"], 0, name)
        self.assertEqual(set(figures["deformation_one_pass"]), set(figures["hulls"]))
        for name, deformed in figures["deformation_one_pass"].items():
            self.assertLessEqual(abs(deformed["VolumeChangePercent"]), 0.05, name)
            self.assertEqual(deformed["FlippedTriangleCount"], 0, name)
            self.assertEqual(deformed["Converged"], 1, name)
        # The whole method in 4 steps against the one-pass method (docs/DESIGN.md, "Measures").
        method = figures["interpolation_method"]
        self.assertEqual(method["number_of_steps"], 4)
        final, one_pass = method["steps"][-1]["muscles"], figures["one_pass_method"]
        self.assertEqual(set(final), set(figures["hulls"]))
        for name, measures in final.items():
            self.assertLessEqual(abs(measures["VolumeChangePercent"]), 0.1, name)
            self.assertLessEqual(measures["MaxNewBonePenetrationDepth"], 0.5, name)
        # The inputs come from the OpenSim files through OpenSimModelReader, which places the
        # femur within 3e-4 mm of femur_transforms.csv; the largest static shift (one point's) is
        # sensitive to such differences (BENCHMARKS.md: 0.27 to 0.51 of the one-pass figure under
        # 1e-7 perturbations): here 9.5 against 18.2 mm in the paper's one pass (0.52), sharp
        # edges 315 against 434, flipped triangles 31 against 62.
        self.assertLessEqual(max(m["MaxStaticShift"] for m in final.values()),
                             0.6 * max(m["MaxStaticShift"] for m in one_pass.values()))
        self.assertLess(sum(m["SharpEdgeCount"] for m in final.values()),
                        sum(m["SharpEdgeCount"] for m in one_pass.values()))
        self.assertLess(sum(m["FlippedTriangleCount"] for m in final.values()),
                        sum(m["FlippedTriangleCount"] for m in one_pass.values()))
        self.assertTrue(os.path.isfile(os.path.join(output, "muscles_method_step_4_iliacus_r.vtp")))
        # psoas and iliacus lose their conditional via point beyond 40 and 54 degrees of flexion.
        rest, current = figures["action_line_points_rest"], figures["action_line_points_current"]
        matched = figures["matched_action_line_points"]
        self.assertEqual((rest["psoas_r"], current["psoas_r"]), (5, 4))
        self.assertEqual((rest["iliacus_r"], current["iliacus_r"]), (5, 4))
        self.assertEqual((rest["gluteus_maximus_r"], current["gluteus_maximus_r"]), (12, 12))
        for muscle, count in matched.items():
            # Every point kept, the two ends of every line shared.
            lines = 3 if muscle.startswith("gluteus") else 1
            self.assertGreaterEqual(count, max(rest[muscle], current[muscle]), muscle)
            self.assertLessEqual(count, rest[muscle] + current[muscle] - 2 * lines, muscle)


if __name__ == "__main__":
    if DATA is None:
        print("SKIPPED: the LHDL data was not found (set MUSCLEDEFORMATION_DATA_DIR)")
        sys.exit(mdtesting.SKIPPED)
    mdtesting.main()
