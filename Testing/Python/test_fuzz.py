# SPDX-License-Identifier: BSD-3-Clause
"""The fuzz campaign of Testing/Python/fuzz_filters.py in the suite: seeded random malformed input
through every filter, in a child pvpython so that a crash is caught and named, not fatal."""
import os
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

    def test_seeded_malformed_input_never_crashes(self):
        for seed in (1, 2, 3):
            with self.subTest(seed=seed):
                self.run_seed(seed, 100)


if __name__ == "__main__":
    mdtesting.main()
