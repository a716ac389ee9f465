# SPDX-License-Identifier: BSD-3-Clause
"""Fibres and their moment arms as a pvpython user gets them from MotionMuscleDeformation: the
main job's LHDL pipeline (Examples/motion.py) through hip_flexion.mot, checked by VTK's own
point-in-surface test, against Modenese & Kohout 2020's 100-fibre model of the same cadaver
(literature/, an external model) and for continuity. Skipped without the data."""
import json
import os
import statistics
import unittest

import mdtesting
import mdexamples
import motion as job  # Examples/motion.py: the main job's pipeline and checks
from paraview import servermanager

mdtesting.load_plugin()
DATA = mdexamples.data_dir()
MUSCLES = ("gluteus_maximus_r", "gluteus_medius_r", "iliacus_r", "psoas_r")


@unittest.skipIf(DATA is None or not os.path.isdir(os.path.join(DATA or "", "lhdl_hip_r")),
                 "real data not found: set MUSCLEDEFORMATION_DATA_DIR to the folder holding lhdl_hip_r and literature")
class FibresThroughHipFlexion(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.motion, _ = job.lhdl_pipeline(DATA, "hip_flexion")
        cls.motion.UpdatePipelineInformation()
        cls.times = list(cls.motion.TimestepValues)
        cls.outside, cls.in_bone, cls.counts = [], [], []
        for t in cls.times:
            cls.motion.UpdatePipeline(t)
            fibres = servermanager.Fetch(cls.motion, idx=4)
            outside, in_bone = job.fibre_check(fibres, servermanager.Fetch(cls.motion, idx=0),
                                               servermanager.Fetch(cls.motion, idx=1))
            cls.outside.append(outside)
            cls.in_bone.append(in_bone)
            cls.counts.append({fibres.GetMetaData(b).Get(fibres.NAME()): fibres.GetBlock(b).GetNumberOfLines()
                               for b in range(fibres.GetNumberOfBlocks())})
        arms = servermanager.Fetch(cls.motion, idx=5)
        cls.table = job.table_columns(arms)
        cls.arms_from = arms.GetFieldData().GetAbstractArray("MomentArmsFrom").GetValue(0)

    def test_a_hundred_fibres_a_muscle_inside_it_and_out_of_the_bones_at_every_frame(self):
        for k, counts in enumerate(self.counts):
            self.assertEqual(counts, {m: 100 for m in MUSCLES}, "frame %d" % k)
            for muscle in MUSCLES:
                self.assertEqual(self.in_bone[k][muscle], 0, "%s frame %d" % (muscle, k))
                # The iliacus folds over itself from 52 degrees on (its action line crosses the iliac
                # bone, issue 49): ray parity counts its doubly covered fold as outside, where the
                # plugin's winding number (BenchmarkMotion) finds every fibre point inside.
                folded = muscle == "iliacus_r" and self.table["hip_flexion_r"][k] >= 51.5
                if not folded:
                    self.assertEqual(self.outside[k][muscle], 0, "%s frame %d" % (muscle, k))
                else:
                    self.assertLess(self.outside[k][muscle], 30, "%s frame %d" % (muscle, k))

    def test_lengths_move_continuously(self):
        for muscle in MUSCLES:
            lengths = self.table["FibreLength(%s)" % muscle]
            steps = sorted(abs(b - a) for a, b in zip(lengths, lengths[1:]))
            print("[ measured ] %s: median fibre length %.1f to %.1f mm; largest step %.2f mm, %.2fx the median step"
                  % (muscle, lengths[0], lengths[-1], steps[-1], steps[-1] / steps[len(steps) // 2]))
            self.assertLess(steps[-1], 2.0 * steps[len(steps) // 2], muscle)
            low, high = self.table["FibreLengthMin(%s)" % muscle], self.table["FibreLengthMax(%s)" % muscle]
            self.assertTrue(all(lo <= m <= hi for lo, m, hi in zip(low, lengths, high)), muscle)

    def test_moment_arms_have_the_anatomical_sign_and_the_size_of_another_model_of_this_cadaver(self):
        """Psoas and iliacus flex the hip, the gluteus maximus extends it; each muscle's median
        fibre moment arm within 10 mm of Modenese & Kohout 2020's 100-fibre model at most frames
        and 25 mm at every frame it gives (measured: 0.5-7 mm apart at the median frame, 21 mm at
        the most, the gluteus maximus at -10 degrees; their fibres were made from templates and
        moved by a blend of the bones' motions, not deformed)."""
        path = os.path.join(DATA, "literature", "lhpbuilder_fibres_hip_flexion.json")
        if not os.path.isfile(path):
            self.skipTest("%s is absent" % path)
        with open(path) as f:
            theirs = json.load(f)
        angles = self.table["hip_flexion_r"]
        self.assertEqual([round(a, 6) for a in angles], [round(a, 6) for a in theirs["angle_deg"]])
        for muscle in MUSCLES:
            ours = self.table["FibreMomentArm(%s, hip_flexion_r)" % muscle]
            other = theirs["muscles"][muscle]["moment_arm_mm_central_difference"]["median"]
            differences = [abs(a - b) for a, b in zip(ours, other) if b is not None]
            print("[ measured ] %s: fibres' median moment arm %.1f to %.1f mm; against Modenese & Kohout 2020 "
                  "median %.1f mm, largest %.1f mm apart" % (muscle, min(ours), max(ours),
                                                             statistics.median(differences), max(differences)))
            sign = -1 if muscle == "gluteus_maximus_r" else 1
            if muscle != "gluteus_medius_r":  # flexes or extends with the fibres' share: no sign
                self.assertTrue(all(sign * v > 0 for v in ours), muscle)
            self.assertLess(statistics.median(differences), 10.0, muscle)
            self.assertLess(max(differences), 25.0, muscle)

    def test_moment_arms_from_stepped_poses_pass_smoothly_through_the_via_points_fades(self):
        """The main job steps every frame by +-1 degree of flexion (the reader's MomentArmStep):
        the psoas's and the iliacus's via points, which fade over 40-50 and 54-64 degrees, add
        nothing to their fibres' median moment arm, which changes between neighbouring frames by
        under 2 mm (differences between frames put the fade's slope in: the psoas's rose by 8 mm
        at 44 degrees, 3-5 mm a frame)."""
        self.assertEqual(self.arms_from, "stepped poses")
        for muscle in ("psoas_r", "iliacus_r"):
            arms = self.table["FibreMomentArm(%s, hip_flexion_r)" % muscle]
            steps = [abs(b - a) for a, b in zip(arms, arms[1:])]
            print("[ measured ] %s: the fibres' median moment arm changes by at most %.2f mm between frames"
                  % (muscle, max(steps)))
            self.assertLess(max(steps), 2.0, muscle)


if __name__ == "__main__":
    mdtesting.main()
