# SPDX-License-Identifier: BSD-3-Clause
"""The real ParaView GUI, as the README tells a user to start it, driving the phantom pipeline.

Starts `paraview` (under the display with_display.sh provides) with the plugin found through
PV_PLUGIN_PATH, exactly as the README's command does, runs gui_phantom.py in it (build the
phantom pipeline, apply, step through every time step), and checks what the script saw and its
screenshot of the last step against Testing/Baseline/GuiPhantomInterpolated.png.
"""
import os
import shutil
import subprocess
import sys
import unittest

import mdtesting

HERE = os.path.dirname(os.path.abspath(__file__))


class Gui(unittest.TestCase):
    def test_phantom_pipeline_in_the_paraview_gui(self):
        paraview = shutil.which("paraview")
        plugin = os.environ["MUSCLEDEFORMATION_PLUGIN"]
        output = mdtesting.output_dir("gui")
        for name in ("report.txt", "error.txt", "GuiPhantomInterpolated.png"):
            if os.path.exists(os.path.join(output, name)):
                os.remove(os.path.join(output, name))
        environment = dict(os.environ, PV_PLUGIN_PATH=os.path.dirname(plugin), MUSCLEDEFORMATION_GUI_OUTPUT=output)
        # --dr: no user settings; --exit: quit once the script has run.
        run = subprocess.run([paraview, "--dr", "--script=" + os.path.join(HERE, "gui_phantom.py"), "--exit"],
                             env=environment, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, timeout=300)
        error = os.path.join(output, "error.txt")
        self.assertFalse(os.path.exists(error), open(error).read() if os.path.exists(error) else "")
        self.assertEqual(run.returncode, 0, run.stdout.decode(errors="replace")[-3000:])
        with open(os.path.join(output, "report.txt")) as f:
            report = dict(line.split() for line in f if line.strip())
        # The phantom shows its rest pose (muscles, bones, action lines), the method its muscles,
        # bones, action lines and fibres with the measures in a spreadsheet.
        self.assertEqual(report, {"plugin_loaded": "1", "phantom_shows": "0,1,3",
                                  "method_shows": "0:RenderView,1:RenderView,2:RenderView,3:SpreadSheetView,4:RenderView",
                                  "coloured_by_role": "1", "action_lines_as_tubes": "1",
                                  "surfaces_not_tubes": "1", "time_steps": "5", "points_every_step": "1",
                                  "last_step": "4"})
        mdtesting.assert_matches_baseline(self, os.path.join(output, "GuiPhantomInterpolated.png"),
                                          "GuiPhantomInterpolated.png", output)


if __name__ == "__main__":
    if not shutil.which("paraview") or not os.environ.get("MUSCLEDEFORMATION_PLUGIN"):
        print("SKIPPED: no paraview binary (Debian package paraview) or no MUSCLEDEFORMATION_PLUGIN")
        sys.exit(mdtesting.SKIPPED)
    mdtesting.main()
