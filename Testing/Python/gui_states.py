# SPDX-License-Identifier: BSD-3-Clause
"""Run inside the real ParaView GUI by test_gui.py (paraview --script=... --exit).

Opens the LHDL state file Examples/$MUSCLEDEFORMATION_GUI_STATE as the README tells a user to
(File > Load State, "Search files under specified directory": the folder holding lhdl_hip_r, here
in $MUSCLEDEFORMATION_DATA_DIR), the plugin loaded by PV_PLUGIN_PATH, and writes what it showed to
$MUSCLEDEFORMATION_GUI_OUTPUT: report.txt (one "key value" per line) and a screenshot state.png of
the view as loaded; or error.txt.
"""
import os
import sys

from paraview import simple

sys.path.insert(0, os.path.join(os.environ["MUSCLEDEFORMATION_SOURCE_DIR"], "Testing", "Python"))
import gui_report  # noqa: E402

output = os.environ["MUSCLEDEFORMATION_GUI_OUTPUT"]
source = os.environ["MUSCLEDEFORMATION_SOURCE_DIR"]
data = os.path.join(os.environ["MUSCLEDEFORMATION_DATA_DIR"], "lhdl_hip_r")
state = os.environ["MUSCLEDEFORMATION_GUI_STATE"]


def run():
    simple.LoadState(os.path.join(source, "Examples", state), data_directory=data)
    views = simple.GetRenderViews()
    view = views[0]
    scene = simple.GetAnimationScene()
    method = simple.FindSource("Motion" if "motion" in state else "Method")
    shown = [simple.GetDisplayProperties(simple.OutputPort(method, port), view) for port in (0, 1, 2, 4)]
    report = {
        "render_views": len(views),
        "in_layout": int(simple.GetLayout(view) is not None),
        "visible": ",".join(str(int(d.Visibility)) for d in shown),
        "coloured_by_role": int(all(d.ColorArrayName[1] == "Role" for d in shown)),
        "action_lines_as_tubes": int(shown[2].RenderLinesAsTubes == 1 and shown[2].LineWidth > 1),
        "snap_to_time_steps": int(scene.PlayMode == "Snap To TimeSteps"),
        "time_steps": len(method.TimestepValues),
        "muscles": simple.OutputPort(method, 0).GetDataInformation().GetNumberOfPoints() > 0,
    }
    simple.SaveScreenshot(os.path.join(output, "state.png"), view, ImageResolution=[600, 600])
    return report


gui_report.finish(run, output)
