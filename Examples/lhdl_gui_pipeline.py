# SPDX-License-Identifier: BSD-3-Clause
"""The LHDL hip pipelines exactly as the README's GUI click paths build them, from the data set's
own files and no Python of ours: OpenSim Model Reader, Legacy VTK readers, Group Datasets, Move
With Bodies, Action Line Grouping, then Interpolated Muscle Deformation (one pose) or, with
--motion, Motion Muscle Deformation (the whole of hip_flexion.mot, Play Motion left on).

    pvpython Examples/lhdl_gui_pipeline.py [--data ../shared/data] [--motion [--frames K]]
                                           [--save-state Examples/LHDL_hip.pvsm]

With --save-state it writes the ParaView state file that Examples/LHDL_hip.pvsm is (with --motion,
Examples/LHDL_hip_motion.pvsm; File > Load State, "Search files under specified directory": the
folder holding lhdl_hip_r): the method's muscles, bones, action lines and fibres in one render
view of the layout, as Apply shows them (coloured by role, the lines as tubes), seen from the
side the README's pictures are, fitted to the muscles, time snapped to the steps. Without it, it
runs the method (60 degrees of hip flexion, 4 steps) or the motion's first K frames (all by
default) and prints each muscle's measures at the last. Exits with code 77 (skipped) when the
data is absent.
"""
import argparse
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import lhdl  # noqa: E402
import mdexamples  # noqa: E402
from paraview import servermanager, simple  # noqa: E402

BONES = ("iliac_r", "sacrum", "femur_r")
MUSCLES = ("gluteus_maximus_r", "gluteus_medius_r", "iliacus_r", "psoas_r")
SETTINGS = dict(Scale=1000.0, ReferenceBody="pelvis", IgnoreUnknownColumns=1, PlayMotion=0, CurrentPoseTime=0.35,
                RestPoseCoordinates="hip_flexion_r=1.5760 hip_adduction_r=-4.7269 hip_rotation_r=-5.2899")


def build(folder, motion=False):
    """The pipeline's proxies, registered under the names the GUI gives them; with `motion` the
    README's motion click path (Play Motion left on, Motion Muscle Deformation)."""
    model = simple.OpenSimModelReader(registrationName="LHDL_hip_r.osim", FileName=os.path.join(folder, "LHDL_hip_r.osim"))
    for name, value in SETTINGS.items():
        if not (motion and name in ("PlayMotion", "CurrentPoseTime")):
            setattr(model, name, value)
    model.MotionFileName = os.path.join(folder, "kinematics", "hip_flexion.mot")
    bones = simple.GroupDatasets(registrationName="Bones", Input=[
        simple.LegacyVTKReader(registrationName=n + ".vtk", FileNames=[os.path.join(folder, n + ".vtk")]) for n in BONES])
    muscles = simple.GroupDatasets(registrationName="Muscles", Input=[
        simple.LegacyVTKReader(registrationName=n + ".vtk", FileNames=[os.path.join(folder, n + ".vtk")]) for n in MUSCLES])
    moved = simple.MoveWithBodies(registrationName="BonesCurrent", Input=bones,
                                  BodyTransforms=simple.OutputPort(model, 4), BodyOfSurface="iliac_r=pelvis; sacrum=pelvis")
    lines = simple.ActionLineGrouping(registrationName="ActionLines", Input=muscles, Paths=simple.OutputPort(model, 3),
                                      PathsCurrent=simple.OutputPort(model, 1))
    landmarks = os.path.join(folder, "attachment_areas_rp_mm.csv")
    if motion:
        method = simple.MotionMuscleDeformation(registrationName="Motion", Input=muscles, BonesRest=bones,
                                                BonesMotion=moved, ActionLinesRest=simple.OutputPort(lines, 0),
                                                ActionLinesMotion=simple.OutputPort(lines, 1),
                                                AttachmentFileName=landmarks)
    else:
        method = simple.InterpolatedMuscleDeformation(registrationName="Method", Input=muscles, BonesRest=bones,
                                                      BonesCurrent=moved, ActionLinesRest=simple.OutputPort(lines, 0),
                                                      ActionLinesCurrent=simple.OutputPort(lines, 1), NumberOfSteps=4,
                                                      AttachmentFileName=landmarks)
    return {"model": model, "bones": bones, "muscles": muscles, "moved": moved, "lines": lines, "method": method,
            "motion": motion}


def save_state(pipeline, path):
    """The pipeline, shown as Apply shows it, as a state file: one render view in the layout, the
    method's muscles, bones, action lines and fibres in it, at the one pose's last step (the
    motion's first frame), the camera fitted to the muscles there."""
    method = pipeline["method"]
    view = mdexamples.state_view()
    view.OrientationAxesVisibility = 1
    controller = servermanager.vtkSMParaViewPipelineControllerWithRendering()
    for port in (0, 1, 2, 4):  # Muscles, Bones, ActionLines, Fibres; the tables in their own views
        controller.Show(method.SMProxy, port, view.SMProxy)
        # What the GUI's Apply does with the plugin's display defaults, written into the state.
        display = simple.GetDisplayProperties(simple.OutputPort(method, port), view)
        mdexamples.colour_by_role(display, view)
        if port == 2:
            display.RenderLinesAsTubes = 1
            display.LineWidth = 4.0
    times = list(method.TimestepValues)
    shown = times[0] if pipeline.get("motion") else times[-1]
    method.UpdatePipeline(shown)
    simple.SetActiveView(view)
    simple.SetActiveSource(method)
    mdexamples.save_state(view, path, lhdl.VIEW_DIRECTION, lhdl.VIEW_UP,
                          mdexamples.padded(simple.OutputPort(method, 0).GetDataInformation().GetBounds()), time=shown)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--plugin", help="path of MuscleDeformation.so (found in build*/ by default)")
    parser.add_argument("--data", help="folder holding lhdl_hip_r (default ../shared/data)")
    parser.add_argument("--motion", action="store_true", help="the motion's click path (Motion Muscle Deformation)")
    parser.add_argument("--frames", type=int, help="with --motion, the motion's first this many frames (all)")
    parser.add_argument("--save-state", help="write the pipeline as a ParaView state file")
    args = parser.parse_args(argv)
    data = mdexamples.lhdl_data_dir(args.data)
    if data is None:
        return mdexamples.SKIPPED
    mdexamples.load_plugin(explicit=args.plugin)
    pipeline = build(os.path.join(data, "lhdl_hip_r"), motion=args.motion)
    if args.save_state:
        save_state(pipeline, args.save_state)
        print("state written to", os.path.abspath(args.save_state))
        return 0
    method = pipeline["method"]
    times = list(method.TimestepValues)[:args.frames] if args.motion else [4]
    for time in times:  # a motion's frames in order, as Play asks for them
        method.UpdatePipeline(time)
    result = servermanager.Fetch(method)
    print("at time", times[-1])
    for index in range(result.GetNumberOfBlocks()):
        fields = result.GetBlock(index).GetFieldData()
        print(result.GetMetaData(index).Get(result.NAME()), {
            name: round(fields.GetArray(name).GetValue(0), 6)
            for name in ("VolumeChangePercent", "MaxStaticShift", "NewBonePenetrationCount", "Converged")})
    return 0


if __name__ == "__main__":
    sys.exit(main())
