# SPDX-License-Identifier: BSD-3-Clause
"""The fuzz campaign of Testing/Python/fuzz_filters.py in the suite: seeded random malformed input
through every filter, in a child pvpython so that a crash is caught and named, not fatal."""
import os
import resource
import subprocess
import sys
import unittest

import mdtesting

PVPYTHON = os.environ.get("MUSCLEDEFORMATION_PVPYTHON", "pvpython")
SCRIPT = os.path.join(mdtesting.HERE, "fuzz_filters.py")


class Fuzz(unittest.TestCase):
    def run_seed(self, seed, count):
        try:
            result = subprocess.run([PVPYTHON, SCRIPT, str(seed), str(count)], capture_output=True, text=True,
                                    timeout=240, env=dict(os.environ))
        except subprocess.TimeoutExpired as e:
            out = e.stdout.decode() if isinstance(e.stdout, bytes) else (e.stdout or "")
            cases = [line for line in out.splitlines() if line.startswith("case ")]
            self.fail("seed %d hung in %s" % (seed, cases[-1] if cases else "set-up"))
        cases = [line for line in result.stdout.splitlines() if line.startswith("case ")]
        self.assertEqual(result.returncode, 0, "seed %d: exit %d in %s\n%s" % (
            seed, result.returncode, cases[-1] if cases else "set-up", result.stderr[-3000:]))
        summary = [line for line in result.stdout.splitlines() if line.startswith("fuzz: ")]
        self.assertEqual(summary[-1].split()[1], str(count), result.stdout[-2000:])
        print(summary[-1])

    def test_the_fault_campaigns_cases_end_in_a_message_or_a_correct_result(self):
        """Testing/Python/fault_cases.py in a child pvpython whose address space is capped at
        8 GiB: a mesh file that lies about its size, a model nested 20,000 deep, NaN and infinity
        through the OpenSim filters... each must be an error naming the input, or a correct result."""
        def cap():
            resource.setrlimit(resource.RLIMIT_AS, (8 << 30, 8 << 30))
        script = os.path.join(mdtesting.HERE, "fault_cases.py")
        try:
            result = subprocess.run([PVPYTHON, script], capture_output=True, text=True, timeout=400,
                                    env=dict(os.environ), preexec_fn=cap)
        except subprocess.TimeoutExpired as e:
            out = e.stdout.decode() if isinstance(e.stdout, bytes) else (e.stdout or "")
            cases = [line for line in out.splitlines() if line.startswith("case ")]
            self.fail("hung in %s" % (cases[-1] if cases else "set-up"))
        lines = result.stdout.splitlines()
        cases = [line for line in lines if line.startswith("case ")]
        failures = [line for line in lines if line.startswith("FAIL ")]
        self.assertEqual(failures, [])
        self.assertEqual(result.returncode, 0, "exit %d in %s\n%s" % (
            result.returncode, cases[-1] if cases else "set-up", result.stderr[-3000:]))
        self.assertGreaterEqual(len(cases), 23)
        print([line for line in lines if " passed, " in line][-1])

    def test_seeded_malformed_input_never_crashes(self):
        for seed in (1, 2, 3):
            with self.subTest(seed=seed):
                self.run_seed(seed, 100)


if __name__ == "__main__":
    mdtesting.main()
