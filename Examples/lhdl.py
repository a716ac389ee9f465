# SPDX-License-Identifier: BSD-3-Clause
"""Reading the LHDL right-hip data set (../shared/data/lhdl_hip_r) into the pipeline (pvpython).

The model and its motions come from the data set's own OpenSim files (LHDL_hip_r.osim,
kinematics/*.mot) through OpenSimModelReader; the scanned bones and muscles are the .vtk surfaces
beside it, in mm, in the scan pose (the rest pose), in the pelvis's frame. The femur moves with
the model's femur_r body (MoveWithBodies), the pelvis bones with the pelvis; the muscle paths
become the muscles' action lines by ActionLineGrouping.
"""
import os
import types

from paraview import servermanager, simple
from vtkmodules.vtkCommonDataModel import vtkCompositeDataSet, vtkMultiBlockDataSet, vtkPolyData
from vtkmodules.vtkIOLegacy import vtkPolyDataReader

BONES = ("iliac_r", "sacrum", "femur_r")
MUSCLES = ("gluteus_maximus_r", "gluteus_medius_r", "iliacus_r", "psoas_r")
# The scan pose (femur_transforms.csv, row scan_pose_RP): the rest pose, in degrees.
REST_POSE = "hip_flexion_r=1.5760 hip_adduction_r=-4.7269 hip_rotation_r=-5.2899"
# The bones whose names do not say which body of the model they move with.
BODY_OF_SURFACE = "iliac_r=pelvis; sacrum=pelvis"
# The side every LHDL picture looks from: the right hip from the lateral side (-x), a little from
# the front (-y) and above, z up.
VIEW_DIRECTION, VIEW_UP = (-1.0, -0.55, 0.25), (0.0, 0.0, 1.0)


def read_surface(folder, name):
    reader = vtkPolyDataReader()
    reader.SetFileName(os.path.join(folder, name + ".vtk"))
    reader.Update()
    surface = vtkPolyData()
    surface.DeepCopy(reader.GetOutput())
    return surface


def named_blocks(blocks):
    tree = vtkMultiBlockDataSet()
    for index, (name, data) in enumerate(blocks):
        tree.SetBlock(index, data)
        tree.GetMetaData(index).Set(vtkCompositeDataSet.NAME(), name)
    return tree


def producer(data, name):
    """A pipeline source holding `data` (builtin session)."""
    source = simple.TrivialProducer(registrationName=name)
    source.GetClientSideObject().SetOutput(data)
    source.UpdatePipeline()
    return source


def model_reader(folder, motion="hip_flexion", frame=35, play=False):
    """OpenSimModelReader of the data set's model in mm, in the pelvis's frame, with the scan pose
    as the rest pose, and `motion` (its frame `frame` the current pose when `play` is off)."""
    reader = simple.OpenSimModelReader(
        registrationName="LHDL_hip_r.osim", FileName=os.path.join(folder, "LHDL_hip_r.osim"),
        IgnoreUnknownColumns=1, Scale=1000.0, ReferenceBody="pelvis", RestPoseCoordinates=REST_POSE,
        PlayMotion=1, MotionFileName=os.path.join(folder, "kinematics", motion + ".mot"))
    times = list(reader.TimestepValues)
    if not 0 <= frame < len(times):
        raise ValueError("motion %r has %d frames, not %d" % (motion, len(times), frame + 1))
    reader.CurrentPoseTime = times[frame]
    reader.PlayMotion = 1 if play else 0
    reader.UpdatePipeline()
    return reader


def load(folder, motion="hip_flexion", frame=35):
    """Pipeline sources of the data set in the rest pose and in one frame of a motion:
    {'muscles', 'bones_rest', 'bones_current', 'lines_rest', 'lines_current'}, plus 'frame'
    (motion, index, time, hip_flexion, hip_adduction in degrees) and 'model' (the reader)."""
    reader = model_reader(folder, motion, frame)
    bones = producer(named_blocks([(name, read_surface(folder, name)) for name in BONES]), "LHDL bones (rest pose)")
    muscles = producer(named_blocks([(name, read_surface(folder, name)) for name in MUSCLES]), "LHDL muscles")
    bones_current = simple.MoveWithBodies(registrationName="LHDL bones (current pose)", Input=bones,
                                          BodyTransforms=simple.OutputPort(reader, 4),
                                          BodyOfSurface=BODY_OF_SURFACE)
    lines = simple.ActionLineGrouping(registrationName="LHDL action lines", Input=muscles,
                                      Paths=simple.OutputPort(reader, 3), PathsCurrent=simple.OutputPort(reader, 1))
    pose = servermanager.Fetch(reader, idx=4).GetFieldData()
    value = lambda name: pose.GetArray(name).GetValue(0)  # noqa: E731
    return {
        "frame": types.SimpleNamespace(motion=motion, index=frame, time=value("Time"),
                                       hip_flexion=round(value("hip_flexion_r"), 6),
                                       hip_adduction=round(value("hip_adduction_r"), 6)),
        "model": reader,
        "muscles": muscles,
        "bones_rest": bones,
        "bones_current": bones_current,
        "lines_rest": simple.OutputPort(lines, 0),
        "lines_current": simple.OutputPort(lines, 1),
    }
