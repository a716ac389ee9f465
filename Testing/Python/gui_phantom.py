# SPDX-License-Identifier: BSD-3-Clause
"""Run inside the real ParaView GUI by test_gui.py (paraview --test-script=... --exit).

Builds the phantom pipeline as a GUI user would (the plugin loaded by PV_PLUGIN_PATH, as the
README says, not by this script), applies it, steps through every time step of the whole method,
and writes what it saw to $MUSCLEDEFORMATION_GUI_OUTPUT: report.txt (one "key value" per line)
and a screenshot of the last step, GuiPhantomInterpolated.png; or error.txt.
"""
import os
import sys

from paraview import simple, servermanager

sys.path.insert(0, os.path.join(os.environ["MUSCLEDEFORMATION_SOURCE_DIR"], "Testing", "Python"))
import gui_report  # noqa: E402

output = os.environ["MUSCLEDEFORMATION_GUI_OUTPUT"]


def run():
    report = {}
    report["plugin_loaded"] = int(hasattr(simple, "InterpolatedMuscleDeformation"))
    phantom = simple.MusculoskeletalPhantom(Flexion=30.0)
    method = simple.InterpolatedMuscleDeformation(
        Input=simple.OutputPort(phantom, 0), BonesRest=simple.OutputPort(phantom, 1),
        BonesCurrent=simple.OutputPort(phantom, 2), ActionLinesRest=simple.OutputPort(phantom, 3),
        ActionLinesCurrent=simple.OutputPort(phantom, 4), NumberOfSteps=4)
    view = simple.GetActiveViewOrCreate("RenderView")
    view.OrientationAxesVisibility = 0
    # What Apply shows: the GUI shows every output port in its preferred view, as here (the
    # controller pqApplyBehavior uses), then hides the filter's inputs.
    controller = servermanager.vtkSMParaViewPipelineControllerWithRendering()

    def apply_shows(source):
        views = {}
        for port in range(source.GetNumberOfOutputPorts()):
            shown_in = controller.ShowInPreferredView(source.SMProxy, port, view.SMProxy)
            views[port] = shown_in.GetXMLName() if shown_in else "none"
        return views

    phantom_views = apply_shows(phantom)
    report["phantom_shows"] = ",".join(str(p) for p, v in sorted(phantom_views.items()) if v == "RenderView")
    for port in range(5):
        simple.Hide(simple.OutputPort(phantom, port), view)
    method_views = apply_shows(method)
    report["method_shows"] = ",".join("%d:%s" % (p, v) for p, v in sorted(method_views.items()))
    simple.SetActiveView(view)
    # The plugin's default display, nothing set here: coloured by role (array Role, the plugin's
    # categorical colour map), action lines as tubes.
    shown = [simple.GetDisplayProperties(simple.OutputPort(method, port), view) for port in (0, 1, 2)]
    report["coloured_by_role"] = int(all(r.ColorArrayName[1] == "Role" and r.LookupTable is not None and
                                         r.LookupTable.InterpretValuesAsCategories == 1 for r in shown))
    report["action_lines_as_tubes"] = int(shown[2].RenderLinesAsTubes == 1 and shown[2].LineWidth > 1)
    report["surfaces_not_tubes"] = int(shown[0].RenderLinesAsTubes == 0)
    scene = simple.GetAnimationScene()
    scene.UpdateAnimationUsingDataTimeSteps()
    times = list(method.TimestepValues)
    report["time_steps"] = len(times)
    points = []
    for t in times:
        scene.AnimationTime = t
        simple.Render(view)
        points.append(method.GetDataInformation().GetNumberOfPoints())
    report["points_every_step"] = int(len(set(points)) == 1 and points[0] > 0)
    report["last_step"] = int(servermanager.Fetch(method).GetBlock(0).GetFieldData().GetArray("InterpolationStep").GetValue(0))
    view.CameraPosition = [800.0, 0.0, -100.0]
    view.CameraFocalPoint = [0.0, 0.0, -100.0]
    view.CameraViewUp = [0.0, 0.0, 1.0]
    view.ResetCamera()
    simple.SaveScreenshot(os.path.join(output, "GuiPhantomInterpolated.png"), view, ImageResolution=[600, 600])
    return report


gui_report.finish(run, output)
