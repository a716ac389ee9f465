"""Reading the LHDL right-hip data set (../shared/data/lhdl_hip_r) into the pipeline (pvpython).

Bones, muscles, action lines (action_lines_rp_mm.csv) and femur motions (femur_transforms.csv),
in one frame, in millimetres. A current pose is a frame of a motion: the pelvis bones stay, the
femur and every path point fixed to the femur move by the frame's rigid transform, and a
conditional path point exists only while the hip flexion is inside its range.
"""
import csv
import os

import numpy
from paraview import simple
from vtkmodules.util import numpy_support
from vtkmodules.vtkCommonCore import vtkPoints, vtkStringArray
from vtkmodules.vtkCommonDataModel import vtkCellArray, vtkCompositeDataSet, vtkMultiBlockDataSet, vtkPolyData
from vtkmodules.vtkIOLegacy import vtkPolyDataReader

BONES = ("iliac_r", "sacrum", "femur_r")
MUSCLES = ("gluteus_maximus_r", "gluteus_medius_r", "iliacus_r", "psoas_r")
# The action lines (OpenSim paths) of each muscle.
ACTION_LINES = {
    "gluteus_maximus_r": ("glut_max1_r", "glut_max2_r", "glut_max3_r"),
    "gluteus_medius_r": ("glut_med1_r", "glut_med2_r", "glut_med3_r"),
    "iliacus_r": ("iliacus_r",),
    "psoas_r": ("psoas_r",),
}
MOVING_BODY = "femur_r"


class Frame:
    """One frame of a motion: x_CP = rotation @ x_RP + translation for the femur."""

    def __init__(self, row):
        self.motion = row["motion"]
        self.index = int(row["frame"])
        self.hip_flexion = float(row["hip_flexion_deg"])
        self.hip_adduction = float(row["hip_adduction_deg"])
        self.rotation = numpy.array([float(row["r%d%d" % (i, j)]) for i in range(3) for j in range(3)]).reshape(3, 3)
        self.translation = numpy.array([float(row["tx_mm"]), float(row["ty_mm"]), float(row["tz_mm"])])

    def apply(self, points):
        return points @ self.rotation.T + self.translation


def read_frame(folder, motion, frame):
    with open(os.path.join(folder, "femur_transforms.csv")) as f:
        for row in csv.DictReader(f):
            if row["motion"] == motion and int(row["frame"]) == frame:
                return Frame(row)
    raise ValueError("no frame %d of motion %r in femur_transforms.csv" % (frame, motion))


def rest_pose_frame(folder):
    return read_frame(folder, "scan_pose_RP", 0)


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


def moved(surface, frame):
    out = vtkPolyData()
    out.DeepCopy(surface)
    xyz = numpy_support.vtk_to_numpy(surface.GetPoints().GetData()).astype(numpy.float64)
    points = vtkPoints()
    points.SetData(numpy_support.numpy_to_vtk(frame.apply(xyz), deep=True))
    out.SetPoints(points)
    return out


def read_action_lines(folder, frame):
    """{path name: [(x, y, z), ...]} of the action lines in the pose of `frame`."""
    paths = {}
    with open(os.path.join(folder, "action_lines_rp_mm.csv")) as f:
        for row in csv.DictReader(f):
            if row["point_type"] == "ConditionalPathPoint":
                low, high = float(row["active_min_deg"]), float(row["active_max_deg"])
                if not low <= frame.hip_flexion <= high:
                    continue
            point = numpy.array([float(row["x_mm"]), float(row["y_mm"]), float(row["z_mm"])])
            if row["attached_body"] == MOVING_BODY:
                point = frame.apply(point[None, :])[0]
            paths.setdefault(row["muscle"], []).append((int(row["order"]), point))
    return {name: [p for _, p in sorted(points, key=lambda item: item[0])] for name, points in paths.items()}


def polylines(lines):
    """A polydata of polylines with the cell array ActionLineName."""
    points, cells, names = vtkPoints(), vtkCellArray(), vtkStringArray()
    names.SetName("ActionLineName")
    for name, line in lines:
        cells.InsertNextCell(len(line))
        for p in line:
            cells.InsertCellPoint(points.InsertNextPoint(*p))
        names.InsertNextValue(name)
    out = vtkPolyData()
    out.SetPoints(points)
    out.SetLines(cells)
    out.GetCellData().AddArray(names)
    return out


def producer(data, name):
    """A pipeline source holding `data` (builtin session)."""
    source = simple.TrivialProducer(registrationName=name)
    source.GetClientSideObject().SetOutput(data)
    source.UpdatePipeline()
    return source


def load(folder, motion="hip_flexion", frame=35):
    """Pipeline sources of the data set in the rest pose and in one frame of a motion:
    {'muscles', 'bones_rest', 'bones_current', 'lines_rest', 'lines_current'}, plus 'frame'."""
    current = read_frame(folder, motion, frame)
    rest = rest_pose_frame(folder)
    bones = [(name, read_surface(folder, name)) for name in BONES]
    bones_current = [(name, moved(surface, current) if name == MOVING_BODY else surface) for name, surface in bones]
    muscles = [(name, read_surface(folder, name)) for name in MUSCLES]
    rest_paths, current_paths = read_action_lines(folder, rest), read_action_lines(folder, current)

    def lines_of(paths):
        return named_blocks([(muscle, polylines([(p, paths[p]) for p in ACTION_LINES[muscle]]))
                             for muscle in MUSCLES])

    return {
        "frame": current,
        "muscles": producer(named_blocks(muscles), "LHDL muscles"),
        "bones_rest": producer(named_blocks(bones), "LHDL bones (rest pose)"),
        "bones_current": producer(named_blocks(bones_current), "LHDL bones (current pose)"),
        "lines_rest": producer(lines_of(rest_paths), "LHDL action lines (rest pose)"),
        "lines_current": producer(lines_of(current_paths), "LHDL action lines (current pose)"),
    }
