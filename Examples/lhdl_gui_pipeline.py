# SPDX-License-Identifier: BSD-3-Clause
"""The LHDL hip pipeline exactly as the README's GUI click path builds it, from the data set's
own files and no Python of ours: OpenSim Model Reader, Legacy VTK readers, Group Datasets, Move
With Bodies, Action Line Grouping, Interpolated Muscle Deformation.

    pvpython Examples/lhdl_gui_pipeline.py [--data ../shared/data] [--save-state Examples/LHDL_hip.pvsm]

With --save-state it writes the ParaView state file that Examples/LHDL_hip.pvsm is (File > Load
State, "Search files under specified directory": the folder holding lhdl_hip_r). Without it, it
runs the method (60 degrees of hip flexion, 4 steps) and prints each muscle's measures. Exits
with code 77 (skipped) when the data is absent.
"""
import argparse
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import mdexamples  # noqa: E402
from paraview import servermanager, simple  # noqa: E402

BONES = ("iliac_r", "sacrum", "femur_r")
MUSCLES = ("gluteus_maximus_r", "gluteus_medius_r", "iliacus_r", "psoas_r")
SETTINGS = dict(Scale=1000.0, ReferenceBody="pelvis", IgnoreUnknownColumns=1, PlayMotion=0, CurrentPoseTime=0.35,
                RestPoseCoordinates="hip_flexion_r=1.5760 hip_adduction_r=-4.7269 hip_rotation_r=-5.2899")


def build(folder):
    """The pipeline's proxies, registered under the names the GUI gives them."""
    model = simple.OpenSimModelReader(registrationName="LHDL_hip_r.osim", FileName=os.path.join(folder, "LHDL_hip_r.osim"))
    for name, value in SETTINGS.items():
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
    method = simple.InterpolatedMuscleDeformation(registrationName="Method", Input=muscles, BonesRest=bones,
                                                  BonesCurrent=moved, ActionLinesRest=simple.OutputPort(lines, 0),
                                                  ActionLinesCurrent=simple.OutputPort(lines, 1), NumberOfSteps=4,
                                                  AttachmentFileName=os.path.join(folder, "attachment_areas_rp_mm.csv"))
    return {"model": model, "bones": bones, "muscles": muscles, "moved": moved, "lines": lines, "method": method}


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--plugin", help="path of MuscleDeformation.so (found in build*/ by default)")
    parser.add_argument("--data", help="folder holding lhdl_hip_r (default ../shared/data)")
    parser.add_argument("--save-state", help="write the pipeline as a ParaView state file")
    args = parser.parse_args(argv)
    data = mdexamples.lhdl_data_dir(args.data)
    if data is None:
        return mdexamples.SKIPPED
    mdexamples.load_plugin(explicit=args.plugin)
    pipeline = build(os.path.join(data, "lhdl_hip_r"))
    if args.save_state:
        view = simple.CreateView("RenderView")
        simple.Show(pipeline["method"], view)
        simple.Show(pipeline["moved"], view)
        simple.Show(simple.OutputPort(pipeline["lines"], 1), view)
        simple.SaveState(args.save_state)
        print("state written to", os.path.abspath(args.save_state))
        return 0
    pipeline["method"].UpdatePipeline(4)
    result = servermanager.Fetch(pipeline["method"])
    for index in range(result.GetNumberOfBlocks()):
        fields = result.GetBlock(index).GetFieldData()
        print(result.GetMetaData(index).Get(result.NAME()), {
            name: round(fields.GetArray(name).GetValue(0), 6)
            for name in ("VolumeChangePercent", "MaxStaticShift", "NewBonePenetrationCount", "Converged")})
    return 0


if __name__ == "__main__":
    sys.exit(main())
