"""Run inside the real ParaView GUI by test_gui.py (paraview --test-script=... --exit).

Builds the phantom pipeline as a GUI user would (the plugin loaded by PV_PLUGIN_PATH, as the
README says, not by this script), applies it, steps through every time step of the whole method,
and writes what it saw to $MUSCLEDEFORMATION_GUI_OUTPUT: report.txt (one "key value" per line)
and a screenshot of the last step, GuiPhantomInterpolated.png; or error.txt.
"""
import os
import traceback

from paraview import simple, servermanager

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
    muscles = simple.Show(simple.OutputPort(method, 0), view)
    bones = simple.Show(simple.OutputPort(method, 1), view)
    for representation in (muscles, bones):
        representation.ColorArrayName = ["POINTS", ""]
    muscles.DiffuseColor = [0.8, 0.25, 0.2]
    bones.DiffuseColor = [0.9, 0.88, 0.8]
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
    with open(os.path.join(output, "report.txt"), "w") as f:
        for key, value in report.items():
            f.write("%s %s\n" % (key, value))


# The GUI keeps a script's exceptions to its own output window: write them where the test looks.
try:
    run()
except Exception:
    with open(os.path.join(output, "error.txt"), "w") as f:
        f.write(traceback.format_exc())
