# SPDX-License-Identifier: BSD-3-Clause
"""The real ParaView GUI, as the README tells a user to start it.

Starts `paraview` (under the display with_display.sh provides) with the plugin found through
PV_PLUGIN_PATH, exactly as the README's command does, and runs a script in it: gui_phantom.py
(build the phantom pipeline, apply, step through every time step) and gui_states.py (open the
LHDL state files Examples/LHDL_hip.pvsm and Examples/LHDL_hip_motion.pvsm on the data set);
checks what each script saw and its screenshots against Testing/Baseline (the README's pictures).
"""
import os
import shutil
import subprocess
import sys
import unittest

import mdtesting

HERE = os.path.dirname(os.path.abspath(__file__))


def run_in_gui(test, script, output, **environment):
    """Runs `script` (in this folder) in the real ParaView GUI, writing to `output`; fails `test`
    with what the GUI said when the script raised or ParaView failed."""
    shutil.rmtree(output, ignore_errors=True)
    os.makedirs(output)
    plugin = os.environ["MUSCLEDEFORMATION_PLUGIN"]
    environment = dict(os.environ, PV_PLUGIN_PATH=os.path.dirname(plugin), MUSCLEDEFORMATION_GUI_OUTPUT=output,
                       MUSCLEDEFORMATION_SOURCE_DIR=mdtesting.SOURCE_DIR, **environment)
    # --dr: no user settings; --exit: quit once the script has run.
    run = subprocess.run([shutil.which("paraview"), "--dr", "--script=" + os.path.join(HERE, script), "--exit"],
                         env=environment, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, timeout=600)
    error = os.path.join(output, "error.txt")
    test.assertFalse(os.path.exists(error), open(error).read() if os.path.exists(error) else "")
    test.assertEqual(run.returncode, 0, run.stdout.decode(errors="replace")[-3000:])


def read_report(path):
    with open(path) as f:
        return dict(line.split() for line in f if line.strip())


class Gui(unittest.TestCase):
    def test_phantom_pipeline_in_the_paraview_gui(self):
        output = mdtesting.output_dir("gui")
        run_in_gui(self, "gui_phantom.py", output)
        report = read_report(os.path.join(output, "report.txt"))
        # The phantom shows its rest pose (muscles, bones, action lines), the method its muscles,
        # bones, action lines and fibres with the measures in a spreadsheet.
        self.assertEqual(report, {"plugin_loaded": "1", "phantom_shows": "0,1,3",
                                  "method_shows": "0:RenderView,1:RenderView,2:RenderView,3:SpreadSheetView,4:RenderView",
                                  "coloured_by_role": "1", "action_lines_as_tubes": "1",
                                  "surfaces_not_tubes": "1", "time_steps": "5", "points_every_step": "1",
                                  "last_step": "4"})
        mdtesting.assert_matches_baseline(self, os.path.join(output, "GuiPhantomInterpolated.png"),
                                          "GuiPhantomInterpolated.png", output)

    def test_the_lhdl_state_files_open_as_the_readme_pictures_them(self):
        import mdexamples
        data = mdexamples.data_dir()
        if not os.path.isdir(os.path.join(data, "lhdl_hip_r")):
            self.skipTest("the LHDL data set is absent (%s)" % data)
        # One render view in the layout; the method's muscles, bones, action lines and fibres in it,
        # coloured by role, the lines as tubes; time snapped to the steps (5 of the one pose's
        # method, 36 frames of hip_flexion).
        for state, name, steps in (("LHDL_hip.pvsm", "GuiLhdlMethodState", 5),
                                   ("LHDL_hip_motion.pvsm", "GuiLhdlMotionState", 36)):
            output = mdtesting.output_dir(name)
            run_in_gui(self, "gui_states.py", output, MUSCLEDEFORMATION_DATA_DIR=data, MUSCLEDEFORMATION_GUI_STATE=state)
            report = read_report(os.path.join(output, "report.txt"))
            self.assertEqual(report, {"render_views": "1", "in_layout": "1", "visible": "1,1,1,1",
                                      "coloured_by_role": "1", "action_lines_as_tubes": "1",
                                      "snap_to_time_steps": "1", "time_steps": str(steps), "muscles": "True"}, name)
            mdtesting.assert_matches_baseline(self, os.path.join(output, "state.png"), name + ".png", output)


if __name__ == "__main__":
    if not shutil.which("paraview") or not os.environ.get("MUSCLEDEFORMATION_PLUGIN"):
        print("SKIPPED: no paraview binary (Debian package paraview) or no MUSCLEDEFORMATION_PLUGIN")
        sys.exit(mdtesting.SKIPPED)
    mdtesting.main()
