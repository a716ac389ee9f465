# SPDX-License-Identifier: BSD-3-Clause
"""What the scripts test_gui.py runs inside the real ParaView GUI share: how they report."""
import os
import traceback


def finish(run, output):
    """Runs `run` (which returns a dict of what it saw) and writes it to `output`/report.txt, one
    "key value" per line; or, where it raises, the traceback to `output`/error.txt (the GUI keeps
    a script's exceptions to its own output window, where the test cannot see them)."""
    try:
        report = run()
        with open(os.path.join(output, "report.txt"), "w") as f:
            for key, value in report.items():
                f.write("%s %s\n" % (key, value))
    except Exception:
        with open(os.path.join(output, "error.txt"), "w") as f:
            f.write(traceback.format_exc())
