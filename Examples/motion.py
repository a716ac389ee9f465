# SPDX-License-Identifier: BSD-3-Clause
"""Muscles through whole motions with MotionMuscleDeformation (pvpython).

Run with pvpython (under xvfb-run on a machine without a display):

    pvpython Examples/motion.py --output results/motion [--case phantom|hip_flexion|hip_adduction|all]

The phantom goes through a flexion sweep from its rest pose to 30 degrees in 15 frames (its bones
and action lines made time-varying by BoneInterpolation); the LHDL right hip (../shared/data, or
--data / $MUSCLEDEFORMATION_DATA_DIR; skipped when absent) through every frame of
kinematics/hip_flexion.mot and hip_adduction.mot, read by OpenSimModelReader with PlayMotion on
(MoveWithBodies moves the scanned bones, ActionLineGrouping makes the paths the action lines).
For each case it writes into <output>/<case>/: the deformed muscles, their fibres and the bones at
every frame (<case>_muscles_<k>.vtm, <case>_fibres_<k>.vtm, <case>_bones_<k>.vtm) with <case>.pvd,
which ParaView opens as one time series. The LHDL hip's bones move rigidly with the model's
bodies: they are written once, at rest (<case>_bones_rest.vtm), with the bodies' transforms at
every frame (<case>_transforms.pvd, the reader's BodyTransforms), and <case>.pvsm opens the
muscles, the fibres and the bones replayed by MoveWithBodies (File > Load State, searching the
case's folder); figures.json says how far the replayed bones lie from those the filter used (0).
Also a picture of every frame (frames/<case>_<k>.png) and, where this ParaView can write one,
a movie (<case>.avi); plots of the measures over time (<case>_measures.png,
<case>_smoothness.png); and figures.json (per-frame time through the filter, and every measure at
every frame). For the LHDL hip, per muscle, a plot of its straight paths' moment arms (the
reader's MomentArms table) against the joint angle beside Blemker & Delp 2005's range
(<motion>_moment_arm_<muscle>.png), and in figures.json the share of poses inside that range;
the motion filter's MomentArms table as <motion>_moment_arms.csv. The fibres' moment arms come
from each frame stepped by +-1 degree in its coordinate (the reader's MomentArmStep; about three
times a frame's cost, --moment-arm-step 0 for differences between frames instead).
The LHDL paths' conditional points fade over 10 degrees (ConditionalPointFade), so
the lines move continuously. The LHDL muscles are attached to their bones by the data set's own landmarks
(attachment_areas_rp_mm.csv, AttachmentFileName); figures.json gives, per muscle, the largest slip
at those landmarks over the motion (the muscle surface point next to each landmark against where
the landmark's bone carries it), and the largest step of a muscle point between two frames
against the median of those steps.
With --paths-over-bones the LHDL paths are first kept out of the scanned bones (PathsOverBones,
--path-points-per-segment points between each two of a path's own): no action line then runs
through a bone, and the muscles are driven by the paths over the bones; off by default, the model's
own straight paths (docs/DESIGN.md, "Paths over the bones", compares the two).
"""
import argparse
import csv
import json
import math
import os
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import mdexamples  # noqa: E402
import numpy  # noqa: E402
from paraview import servermanager, simple  # noqa: E402
from vtkmodules.util.numpy_support import vtk_to_numpy  # noqa: E402


def phantom_pipeline(frames=15, flexion=30.0):
    phantom = simple.MusculoskeletalPhantom(registrationName="Phantom", Flexion=flexion)
    bones = simple.BoneInterpolation(registrationName="Phantom bones over the sweep",
                                     Input=simple.OutputPort(phantom, 1), CurrentPose=simple.OutputPort(phantom, 2),
                                     NumberOfSteps=frames)
    lines = simple.BoneInterpolation(registrationName="Phantom action lines over the sweep",
                                     Input=simple.OutputPort(phantom, 3), CurrentPose=simple.OutputPort(phantom, 4),
                                     NumberOfSteps=frames)
    motion = simple.MotionMuscleDeformation(registrationName="Phantom motion", Input=simple.OutputPort(phantom, 0),
                                            BonesRest=simple.OutputPort(phantom, 1), BonesMotion=bones,
                                            ActionLinesRest=simple.OutputPort(phantom, 3), ActionLinesMotion=lines)
    return motion, {"direction": (1.0, -0.4, 0.3), "up": (0.0, 0.0, 1.0), "focal": None, "distance": None}


def lhdl_pipeline(data, motion_name):
    import lhdl
    folder = os.path.join(data, "lhdl_hip_r")
    reader = lhdl.model_reader(folder, motion_name, 0, play=True)
    # The psoas's and the iliacus's via points go at 40 and 54 degrees of flexion: faded over 10
    # degrees, their lines, and the muscles, move continuously instead of jumping there.
    reader.ConditionalPointFade = CONDITIONAL_POINT_FADE
    reader.MomentArmStep = MOMENT_ARM_STEP[0]
    READERS[motion_name] = reader
    bones = lhdl.producer(lhdl.named_blocks([(n, lhdl.read_surface(folder, n)) for n in lhdl.BONES]),
                          "LHDL bones (rest pose)")
    muscles = lhdl.producer(lhdl.named_blocks([(n, lhdl.read_surface(folder, n)) for n in lhdl.MUSCLES]),
                            "LHDL muscles")
    BONES_AT_REST[motion_name] = bones
    moved = simple.MoveWithBodies(registrationName="LHDL bones (motion)", Input=bones,
                                  BodyTransforms=simple.OutputPort(reader, 4), BodyOfSurface=lhdl.BODY_OF_SURFACE)
    paths_rest, paths_now = simple.OutputPort(reader, 3), simple.OutputPort(reader, 1)
    if PATHS_OVER_BONES[0]:
        # The paths kept out of the bones (at rest over the rest pose's bones, in the motion over
        # the moved ones): no action line then runs through a bone.
        paths_rest = simple.PathsOverBones(registrationName="LHDL paths over the bones (rest pose)",
                                           Input=paths_rest, Bones=bones,
                                           PointsPerSegment=PATHS_OVER_BONES[1])
        paths_now = simple.PathsOverBones(registrationName="LHDL paths over the bones (motion)",
                                          Input=paths_now, Bones=moved,
                                          PointsPerSegment=PATHS_OVER_BONES[1])
    lines = simple.ActionLineGrouping(registrationName="LHDL action lines", Input=muscles,
                                      Paths=paths_rest, PathsCurrent=paths_now)
    motion = simple.MotionMuscleDeformation(registrationName="LHDL " + motion_name, Input=muscles, BonesRest=bones,
                                            BonesMotion=moved, ActionLinesRest=simple.OutputPort(lines, 0),
                                            ActionLinesMotion=simple.OutputPort(lines, 1),
                                            AttachmentFileName=os.path.join(folder, LANDMARKS))
    # Framed on the muscles over the whole motion (the bones reach far beyond them).
    camera = {"direction": lhdl.VIEW_DIRECTION, "up": lhdl.VIEW_UP, "focal": None, "distance": None,
              "frame_muscles": True}
    return motion, camera


LANDMARKS = "attachment_areas_rp_mm.csv"
READERS = {}  # motion name: the model reader playing it (its MomentArms table)
BONES_AT_REST = {}  # motion name: the bones' rest-pose source (their replay's input)
FRAMES = [None]  # --frames: the first this many frames of each motion (all)
CONDITIONAL_POINT_FADE = 10.0  # degrees
MOMENT_ARM_STEP = [1.0]  # degrees (--moment-arm-step)
PATHS_OVER_BONES = [False, 15]  # --paths-over-bones, --path-points-per-segment
# The data set's names for the muscles and the bones its landmarks lie on (the iliotibial tract's,
# on the tibia, is on no bone of the scan and left out).
LANDMARK_MUSCLES = {"R_Glut_Max": "gluteus_maximus_r", "R_Glut_Med": "gluteus_medius_r", "R_Iliacus": "iliacus_r",
                    "R_Psoas_maj": "psoas_r"}
LANDMARK_BONES = {"pelvis": "iliac_r", "femur_r": "femur_r"}


def leaf_points(data):
    """{block name: its points as a numpy array} of a multiblock."""
    return {name: vtk_to_numpy(leaf.GetPoints().GetData()).astype(float)
            for name, leaf in mdexamples.named_leaves(data).items()}


def rigid_fit(rest, now):
    """R, t with now ~ R rest + t (least squares)."""
    a, b = rest.mean(axis=0), now.mean(axis=0)
    u, _, vt = numpy.linalg.svd((rest - a).T @ (now - b))
    d = numpy.sign(numpy.linalg.det(vt.T @ u.T))
    rotation = vt.T @ numpy.diag([1.0, 1.0, d]) @ u.T
    return rotation, b - rotation @ a


class LandmarkSlip:
    """The slip at the data set's attachment landmarks, frame by frame: for each landmark, the rest
    muscle point nearest it, against where the landmark's bone carries that point."""

    def __init__(self, table, muscles_rest, bones_rest):
        self.bones_rest = bones_rest
        self.probes = []  # (muscle, point, bone)
        with open(table) as f:
            for row in csv.DictReader(f):
                muscle, bone = LANDMARK_MUSCLES.get(row["muscle_group"]), LANDMARK_BONES.get(row["attached_to"])
                if muscle not in muscles_rest or bone not in bones_rest:
                    continue
                mark = numpy.array([float(row[c]) for c in ("x_mm", "y_mm", "z_mm")])
                point = int(numpy.argmin(((muscles_rest[muscle] - mark) ** 2).sum(axis=1)))
                self.probes.append((muscle, point, bone))
        self.muscles_rest = muscles_rest
        self.worst = {}

    def add_frame(self, muscles, bones):
        carried = {b: rigid_fit(self.bones_rest[b], bones[b]) for b in set(p[2] for p in self.probes)}
        for muscle, point, bone in self.probes:
            rotation, translation = carried[bone]
            expected = rotation @ self.muscles_rest[muscle][point] + translation
            slip = float(numpy.linalg.norm(muscles[muscle][point] - expected))
            self.worst[muscle] = max(self.worst.get(muscle, 0.0), slip)


def step_ratios(frames):
    """Per muscle: the largest step of any of its points between two frames against the median of
    each transition's largest step."""
    ratios = {}
    for name in frames[0]:
        steps = sorted(float(numpy.linalg.norm(b[name] - a[name], axis=1).max()) for a, b in zip(frames, frames[1:]))
        ratios[name] = steps[-1] / steps[len(steps) // 2] if steps and steps[len(steps) // 2] > 0 else 0.0
    return ratios


def muscle_bounds(motion, times):
    """The box of the muscles over every frame (from the filter's cache), with a tenth of its
    size around it."""
    box = [math.inf, -math.inf] * 3
    for t in times:
        motion.UpdatePipeline(t)
        frame = [0.0] * 6
        servermanager.Fetch(motion, idx=0).GetBounds(frame)
        box = [min(box[i], frame[i]) if i % 2 == 0 else max(box[i], frame[i]) for i in range(6)]
    return mdexamples.padded(box)


def write_raw(writer, path, data, smallest=False):
    """`data` as `path` by the XML `writer`: raw binary appended data (not base64), compressed
    with zlib or, `smallest`, with LZMA (a sixth smaller on these surfaces, and much slower to
    write: trials over MPI ranks took 45 % longer)."""
    writer.SetFileName(path)
    writer.SetInputData(data)
    writer.SetDataModeToAppended()
    writer.EncodeAppendedDataOff()
    if smallest:
        writer.SetCompressorTypeToLZMA()
    writer.Write()


def write_multiblock(source, port, path, written=None, single=(), smallest=False):
    """Output `port` of `source` as `path` (.vtm) and a folder of .vtp beside it (`write_raw`,
    `smallest`). With `written` (a dict kept over the frames of one series), a block
    whose points and cells are those of a file written before, bit for bit, is not written again:
    the .vtm refers to that file, so a bone that does not move is written once a motion. The point
    arrays named in `single` are written in single precision (arrays to colour by; the points
    themselves keep double precision)."""
    from vtkmodules.vtkCommonCore import vtkFloatArray
    from vtkmodules.vtkCommonDataModel import vtkPolyData
    from vtkmodules.vtkIOXML import vtkXMLMultiBlockDataWriter, vtkXMLPolyDataWriter
    data = servermanager.Fetch(source, idx=port)
    blocks = [data.GetBlock(i) for i in range(data.GetNumberOfBlocks())]
    for block in blocks:
        for name in single:
            array = block.GetPointData().GetArray(name) if block else None
            if array is not None:
                narrowed = vtkFloatArray()
                narrowed.DeepCopy(array)
                narrowed.SetName(name)
                block.GetPointData().AddArray(narrowed)
    if written is None or not all(isinstance(b, vtkPolyData) for b in blocks):
        write_raw(vtkXMLMultiBlockDataWriter(), path, data, smallest)
        return
    import hashlib
    from xml.sax.saxutils import quoteattr
    from vtkmodules.util.numpy_support import vtk_to_numpy
    stem = os.path.splitext(os.path.basename(path))[0]
    entries = []
    for i, block in enumerate(blocks):
        name = data.GetMetaData(i).Get(data.NAME()) if data.HasMetaData(i) else str(i)
        digest = hashlib.sha1()
        for array in (block.GetPoints().GetData() if block.GetPoints() else None, block.GetPolys().GetData()):
            if array is not None:
                digest.update(vtk_to_numpy(array).tobytes())
        key = (i, name, digest.digest())
        if key not in written:
            file = "%s/%s_%d.vtp" % (stem, stem, i)
            os.makedirs(os.path.join(os.path.dirname(path), stem), exist_ok=True)
            write_raw(vtkXMLPolyDataWriter(), os.path.join(os.path.dirname(path), file), block, smallest)
            written[key] = file
        entries.append('    <DataSet index="%d" name=%s file=%s/>\n' % (i, quoteattr(name), quoteattr(written[key])))
    with open(path, "w") as out:
        out.write('<?xml version="1.0"?>\n<VTKFile type="vtkMultiBlockDataSet" version="1.0" '
                  'byte_order="LittleEndian" header_type="UInt32">\n  <vtkMultiBlockDataSet>\n')
        out.write("".join(entries))
        out.write("  </vtkMultiBlockDataSet>\n</VTKFile>\n")


def write_pvd(path, entries):
    with open(path, "w") as out:
        out.write('<?xml version="1.0"?>\n<VTKFile type="Collection" version="0.1">\n  <Collection>\n')
        for t, part, name in entries:
            out.write('    <DataSet timestep="%.9g" part="%d" file="%s"/>\n' % (t, part, name))
        out.write('  </Collection>\n</VTKFile>\n')


def write_table(source, port, t, path):
    """Output `port` of `source` (a table) at time `t` as `path` (.vtt, `write_raw`)."""
    from vtkmodules.vtkCommonDataModel import vtkTable
    from vtkmodules.vtkIOXML import vtkXMLTableWriter
    source.UpdatePipeline(t)
    # A copy without the fetched table's time: VTK 9.2's table writer leaves the time value it
    # would add empty, which makes the file unreadable.
    fetched = servermanager.Fetch(source, idx=port)
    table = vtkTable()
    table.GetRowData().ShallowCopy(fetched.GetRowData())
    table.GetFieldData().ShallowCopy(fetched.GetFieldData())
    table.GetFieldData().RemoveArray("TimeValue")
    write_raw(vtkXMLTableWriter(), path, table)


def replay(folder, name):
    """The bones of case `name` replayed from what run_case wrote into `folder`: the rest bones
    moved by the bodies' transforms at each frame (MoveWithBodies, as the pipeline moved them)."""
    import lhdl
    rest = simple.XMLMultiBlockDataReader(registrationName=name + "_bones_rest.vtm",
                                          FileName=[os.path.join(folder, name + "_bones_rest.vtm")])
    transforms = simple.PVDReader(registrationName=name + "_transforms.pvd",
                                  FileName=os.path.join(folder, name + "_transforms.pvd"))
    return simple.MoveWithBodies(registrationName="Bones", Input=rest, BodyTransforms=transforms,
                                 BodyOfSurface=lhdl.BODY_OF_SURFACE), (rest, transforms)


def replay_check(motion, folder, name, times):
    """The largest distance, over every frame and bone point, between the bones replayed from the
    written files (`replay`) and those the motion filter used at that frame (its output 1)."""
    moved, sources = replay(folder, name)
    largest = 0.0
    for t in times:
        motion.UpdatePipeline(t)
        moved.UpdatePipeline(t)
        used = leaf_points(servermanager.Fetch(motion, idx=1))
        again = leaf_points(servermanager.Fetch(moved))
        for bone, points in used.items():
            largest = max(largest, float(numpy.abs(points - again[bone]).max()))
    for proxy in (moved,) + sources:
        simple.Delete(proxy)
    return largest


def write_replay_state(folder, name, camera):
    """<case>.pvsm in `folder`: the case's muscles and fibres (<case>.pvd) and its bones replayed
    (`replay`), coloured by role, from the side and at the framing of the case's pictures; written
    from a session of its own (every proxy in the session goes into a state)."""
    simple.ResetSession()
    series = simple.PVDReader(registrationName=name + ".pvd", FileName=os.path.join(folder, name + ".pvd"))
    moved, _ = replay(folder, name)
    view = mdexamples.state_view()
    mdexamples.colour_by_role(simple.Show(series, view), view)  # the muscles and fibres, as the filter wrote them
    bones = simple.Show(moved, view)  # the scans' bones, which carry no role
    bones.ColorArrayName = ["POINTS", ""]
    bones.DiffuseColor = mdexamples.BONE_COLOUR
    mdexamples.save_state(view, os.path.join(folder, name + ".pvsm"), camera["direction"], camera["up"],
                          camera.get("bounds"))


def table_columns(table):
    columns = {}
    for c in range(table.GetNumberOfColumns()):
        array = table.GetColumn(c)
        columns[table.GetColumnName(c)] = [array.GetValue(r) for r in range(table.GetNumberOfRows())]
    return columns


def plot(motion, path, pattern, title):
    """The columns of MeasuresOverTime whose names contain `pattern`, against Time."""
    names = list(table_columns(servermanager.Fetch(motion, idx=3)))
    view = simple.CreateView("XYChartView")
    view.ViewSize = [900, 500]
    view.ChartTitle = title
    view.LeftAxisTitle = pattern
    view.BottomAxisTitle = "Time"
    display = simple.Show(simple.OutputPort(motion, 3), view)
    display.UseIndexForXAxis = 0
    display.XArrayName = "Time"
    display.SeriesVisibility = [name for name in names if pattern in name]
    simple.Render(view)
    simple.SaveScreenshot(path, view, ImageResolution=[900, 500])
    simple.Delete(view)
    return path


# The data set's muscles, the model's paths of each, and their names in the literature files.
MUSCLE_PATHS = {"psoas_r": ["psoas_r"], "iliacus_r": ["iliacus_r"],
                "gluteus_maximus_r": ["glut_max1_r", "glut_max2_r", "glut_max3_r"],
                "gluteus_medius_r": ["glut_med1_r", "glut_med2_r", "glut_med3_r"]}


def interpolated(curve, angle):
    """A digitised curve [[angle, value], ...] (sorted) at `angle`; None outside it."""
    if not curve or angle < curve[0][0] or angle > curve[-1][0]:
        return None
    for (a0, v0), (a1, v1) in zip(curve, curve[1:]):
        if a0 <= angle <= a1:
            return v0 if a1 == a0 else v0 + (angle - a0) / (a1 - a0) * (v1 - v0)
    return curve[-1][1]


def share_inside(values, lower, upper):
    """Percent of the poses where Blemker's range is defined and the value known that lie inside it."""
    covered = [(v, lo, up) for v, lo, up in zip(values, lower, upper)
               if lo is not None and up is not None and v is not None and not math.isnan(v)]
    return 100.0 * sum(min(lo, up) <= v <= max(lo, up) for v, lo, up in covered) / max(1, len(covered))


def moment_arm_plots(motion, reader, data, motion_name, folder):
    """Per muscle, against the joint angle: the moment arms of its fibres (the motion filter's
    MomentArms table: median and range over the fibres), of Modenese & Kohout 2020's 100-fibre
    model of the same cadaver (literature/lhpbuilder_fibres_*.json) and of the model's straight
    paths (the reader's MomentArms table), beside Blemker & Delp 2005's range of fibre moment arms
    (literature/blemker2005_envelopes.json); and for each, the share of poses, inside the angles
    Blemker's curves cover, where it lies inside that range."""
    from vtkmodules.vtkCommonCore import vtkDoubleArray
    from vtkmodules.vtkCommonDataModel import vtkTable
    literature = os.path.join(data, "literature")
    envelopes = os.path.join(literature, "blemker2005_envelopes.json")
    if not os.path.isfile(envelopes):
        print("no moment-arm plots: %s is absent" % envelopes)
        return {}, []
    with open(envelopes) as f:
        blemker = json.load(f)["muscles"]
    others_file = os.path.join(literature, "lhpbuilder_fibres_%s.json" % motion_name)
    others = None
    if os.path.isfile(others_file):
        with open(others_file) as f:
            others = json.load(f)
    coordinate = {"hip_flexion": "hip_flexion_r", "hip_adduction": "hip_adduction_r"}[motion_name]
    paths = table_columns(servermanager.Fetch(reader, idx=6))
    fibres = table_columns(servermanager.Fetch(motion, idx=5))
    # The motion filter's MomentArms table as it is, for a user's own plots and statistics.
    with open(os.path.join(folder, "%s_moment_arms.csv" % motion_name), "w", newline="") as f:
        writer = csv.writer(f)
        writer.writerow(list(fibres))
        writer.writerows(zip(*fibres.values()))
    angles = fibres[coordinate]
    path_angles = paths[coordinate]
    inside = {"fibres": {}, "modenese_kohout_2020_fibres": {}, "straight_paths": {}}
    plots = []
    for muscle, muscle_paths in MUSCLE_PATHS.items():
        band = blemker[muscle][coordinate]
        upper = [interpolated(band["upper"], a) for a in angles]
        lower = [interpolated(band["lower"], a) for a in angles]
        columns = {"%s (deg)" % coordinate: angles,
                   "Blemker 2005 upper": [float("nan") if u is None else u for u in upper],
                   "Blemker 2005 lower": [float("nan") if v is None else v for v in lower]}
        median = fibres.get("FibreMomentArm(%s, %s)" % (muscle, coordinate))
        if median:
            columns["fibres, median"] = median
            columns["fibres, min"] = fibres["FibreMomentArmMin(%s, %s)" % (muscle, coordinate)]
            columns["fibres, max"] = fibres["FibreMomentArmMax(%s, %s)" % (muscle, coordinate)]
            inside["fibres"][muscle] = share_inside(median, lower, upper)
        if others:
            theirs = others["muscles"][muscle]["moment_arm_mm_central_difference"]["median"]
            curve = [[a, v] for a, v in zip(others["angle_deg"], theirs) if v is not None]
            at = [interpolated(curve, a) for a in angles]
            columns["Modenese & Kohout 2020 fibres, median"] = [float("nan") if v is None else v for v in at]
            inside["modenese_kohout_2020_fibres"][muscle] = share_inside(at, lower, upper)
        shares = []
        for path in muscle_paths:
            curve = list(zip(path_angles, paths["MomentArm(%s, %s)" % (path, coordinate)]))
            at = [interpolated(curve, a) for a in angles]
            columns["%s (straight path)" % path] = [float("nan") if v is None else v for v in at]
            shares.append(share_inside(at, lower, upper))
        inside["straight_paths"][muscle] = sum(shares) / len(shares)
        table = vtkTable()
        for column_name, values in columns.items():
            array = vtkDoubleArray()
            array.SetName(column_name)
            for v in values:
                array.InsertNextValue(v)
            table.AddColumn(array)
        source = simple.PVTrivialProducer(registrationName="%s moment arms" % muscle)
        source.GetClientSideObject().SetOutput(table)
        view = simple.CreateView("XYChartView")
        view.ViewSize = [700, 450]
        view.ChartTitle = "%s, %s: moment arms against Blemker 2005's range" % (muscle, motion_name)
        view.LeftAxisTitle = "moment arm (mm)"
        view.BottomAxisTitle = "%s (deg)" % coordinate
        display = simple.Show(source, view)
        display.UseIndexForXAxis = 0
        display.XArrayName = "%s (deg)" % coordinate
        series = [n for n in columns if n != "%s (deg)" % coordinate]
        display.SeriesVisibility = series
        # Blemker's range grey, the fibres green (their range dashed), Modenese & Kohout's blue,
        # the straight paths orange to brown.
        style = {"Blemker 2005 upper": ((0.45, 0.45, 0.45), 2, "1"), "Blemker 2005 lower": ((0.45, 0.45, 0.45), 2, "1"),
                 "fibres, median": ((0.1, 0.6, 0.1), 4, "1"), "fibres, min": ((0.1, 0.6, 0.1), 1, "2"),
                 "fibres, max": ((0.1, 0.6, 0.1), 1, "2"),
                 "Modenese & Kohout 2020 fibres, median": ((0.15, 0.35, 0.85), 3, "1")}
        straight = [n for n in series if n.endswith("(straight path)")]
        for i, name in enumerate(straight):
            shade = i / max(1, len(straight) - 1)
            style[name] = ((0.95 - 0.4 * shade, 0.55 - 0.3 * shade, 0.1), 2, "3")
        display.SeriesColor = [x for name in series for x in [name] + ["%g" % c for c in style[name][0]]]
        display.SeriesLineThickness = [x for name in series for x in (name, str(style[name][1]))]
        display.SeriesLineStyle = [x for name in series for x in (name, style[name][2])]
        view.LegendLocation = "BottomRight" if band["upper"][0][1] > 0 else "TopRight"
        simple.Render(view)
        path_png = os.path.join(folder, "%s_moment_arm_%s.png" % (motion_name, muscle))
        simple.SaveScreenshot(path_png, view, ImageResolution=[700, 450])
        simple.Delete(view)
        simple.Delete(source)
        plots.append(path_png)
    return inside, plots


def fibre_length_figures(table):
    """Per muscle: the median fibre length at the first and the last frame, and the largest change
    of the median between two frames against its median change."""
    columns = table_columns(table)
    result = {}
    for key, values in columns.items():
        if not key.startswith("FibreLength("):
            continue
        steps = sorted(abs(b - a) for a, b in zip(values, values[1:]))
        median = steps[len(steps) // 2] if steps else 0.0
        result[key[len("FibreLength("):-1]] = {"first_mm": values[0], "last_mm": values[-1],
                                               "largest_step_against_median": steps[-1] / median if median else 0.0}
    return result


def fibre_check(fibres, muscles, bones):
    """Fibre points outside their muscle and inside a bone at one frame, by VTK's own test
    (vtkSelectEnclosedPoints), apart from the plugin's."""
    leaves, inside = mdexamples.named_leaves, mdexamples.inside
    outside, in_bone = {}, {}
    muscle_leaves, bone_leaves = leaves(muscles), leaves(bones)
    for name, polylines in leaves(fibres).items():
        outside[name] = int((~inside(polylines, muscle_leaves[name])).sum())
        in_bone[name] = int(sum(inside(polylines, bone).sum() for bone in bone_leaves.values()))
    return outside, in_bone


def run_case(name, motion, camera, output, every, landmarks=None):
    folder = os.path.join(output, name)
    os.makedirs(os.path.join(folder, "frames"), exist_ok=True)
    times = list(motion.TimestepValues)[:FRAMES[0]]
    # Every frame through the filter first, timed as a user meets it (each frame from the last).
    seconds = []
    start = time.time()
    for t in times:
        began = time.time()
        motion.UpdatePipeline(t)
        seconds.append(time.time() - began)
    total = time.time() - start
    # Then the pictures and meshes, every frame from the filter's cache.
    view = mdexamples.make_view((800, 800))
    mdexamples.show_surface(motion, view, mdexamples.BONE_COLOUR, port=1)
    simple.Show(simple.OutputPort(motion, 0), view).Representation = "Surface"
    mdexamples.show_lines(motion, view, mdexamples.LINE_COLOUR, port=2, width=3.0)
    view.ViewTime = times[0]
    bounds = muscle_bounds(motion, times) if camera.get("frame_muscles") else None
    camera["bounds"] = bounds
    mdexamples.set_camera(view, camera["direction"], camera["up"], focal=camera["focal"],
                          distance=camera["distance"], bounds=bounds)
    entries = []
    slip = None
    if landmarks:
        slip = LandmarkSlip(landmarks, leaf_points(servermanager.Fetch(motion.Input)),
                            leaf_points(servermanager.Fetch(motion.BonesRest)))
    muscle_frames = []
    bones_written = {}  # a bone that does not move is written once
    motion_name = name[len("lhdl_"):]
    replayed = motion_name in BONES_AT_REST  # the bones written once, with the bodies' transforms
    if replayed:
        write_multiblock(BONES_AT_REST[motion_name], 0, os.path.join(folder, name + "_bones_rest.vtm"), smallest=True)
        transforms = []
    fibres_outside, fibres_in_bone = {}, {}
    for k, t in enumerate(times):
        motion.UpdatePipeline(t)
        muscles = servermanager.Fetch(motion, idx=0)
        bones = servermanager.Fetch(motion, idx=1)
        muscle_frames.append(leaf_points(muscles))
        if slip:
            slip.add_frame(muscle_frames[-1], leaf_points(bones))
        outside, in_bone = fibre_check(servermanager.Fetch(motion, idx=4), muscles, bones)
        for muscle in outside:
            fibres_outside[muscle] = fibres_outside.get(muscle, 0) + outside[muscle]
            fibres_in_bone[muscle] = fibres_in_bone.get(muscle, 0) + in_bone[muscle]
        muscles_file = "%s_muscles_%03d.vtm" % (name, k)
        bones_file = "%s_bones_%03d.vtm" % (name, k)
        fibres_file = "%s_fibres_%03d.vtm" % (name, k)
        write_multiblock(motion, 0, os.path.join(folder, muscles_file), single=("Displacement",), smallest=True)
        write_multiblock(motion, 4, os.path.join(folder, fibres_file), smallest=True)
        entries += [(t, 0, muscles_file), (t, 2, fibres_file)]
        if replayed:
            transforms_file = "%s_transforms_%03d.vtt" % (name, k)
            write_table(READERS[motion_name], 4, t, os.path.join(folder, transforms_file))
            transforms.append((t, 0, transforms_file))
        else:
            write_multiblock(motion, 1, os.path.join(folder, bones_file), bones_written, smallest=True)
            entries.append((t, 1, bones_file))
        if k % every == 0 or k == len(times) - 1:
            mdexamples.screenshot(view, os.path.join(folder, "frames", "%s_%03d.png" % (name, k)), t)
    write_pvd(os.path.join(folder, name + ".pvd"), entries)
    replay_difference = None
    if replayed:
        write_pvd(os.path.join(folder, name + "_transforms.pvd"), transforms)
        replay_difference = replay_check(motion, folder, name, times)
    movie = None
    try:
        scene = simple.GetAnimationScene()
        scene.UpdateAnimationUsingDataTimeSteps()
        movie = os.path.join(folder, name + ".avi")
        with mdexamples.QuietStandardError() as encoder:  # the encoder's chatter, one line a frame
            simple.SaveAnimation(movie, view, ImageResolution=[800, 800], FrameRate=10)
        if not os.path.isfile(movie):
            print("no movie written: " + encoder.text.strip())
            movie = None
    except Exception as error:  # noqa: BLE001 - ParaView built without a movie writer
        print("no movie written (%s): the PNG frames are the animation" % error)
        movie = None
    mdexamples.close_view(view)
    plots = [plot(motion, os.path.join(folder, name + "_measures.png"), "NumberOfIterations",
                  "%s: settle iterations per frame" % name),
             plot(motion, os.path.join(folder, name + "_smoothness.png"), "SmoothnessRatio",
                  "%s: smoothness (second difference against the bones' and lines')" % name)]
    motion.UpdatePropertyInformation()
    table = table_columns(servermanager.Fetch(motion, idx=3))
    later = seconds[1:]
    figures = {
        "case": name, "frames": len(times), "first_frame_seconds": seconds[0],
        "per_frame_ms_mean": 1000.0 * sum(later) / max(1, len(later)),
        "per_frame_ms_min": 1000.0 * min(later) if later else 0.0,
        "per_frame_ms_max": 1000.0 * max(later) if later else 0.0,
        "total_seconds_every_frame": total,
        "frames_computed": motion.GetProperty("FramesComputed").GetData(),
        "cache_megabytes": motion.GetProperty("CacheMegabytes").GetData(),
        "movie": movie, "plots": plots, "measures": table,
        "largest_step_against_median": step_ratios(muscle_frames),
        "fibre_points_outside_muscle": fibres_outside,
        "fibre_points_inside_bone": fibres_in_bone,
        "fibre_lengths": fibre_length_figures(servermanager.Fetch(motion, idx=5)),
    }
    if replay_difference is not None:
        figures["bones_replay_largest_difference"] = replay_difference
    if slip:
        figures["largest_landmark_slip_mm"] = slip.worst
        figures["landmark_probes"] = len(slip.probes)
        reader = READERS[name[len("lhdl_"):]]
        data = os.path.dirname(os.path.dirname(landmarks))
        inside, arm_plots = moment_arm_plots(motion, reader, data, name[len("lhdl_"):], folder)
        figures["moment_arm_inside_blemker2005_percent"] = inside
        figures["plots"] += arm_plots
    finite = lambda values: [v for v in values if not math.isnan(v)]  # noqa: E731
    worst = {
        "largest_abs_volume_change_percent": max(abs(v) for key, values in table.items()
                                                 if key.startswith("VolumeChangePercent") for v in values),
        "largest_bone_penetration": max(v for key, values in table.items()
                                        if key.startswith("MaxNewBonePenetrationDepth") for v in values),
        "largest_smoothness_ratio": max([v for key, values in table.items()
                                         if key.startswith("SmoothnessRatio") for v in finite(values)] or [0.0]),
        "every_frame_converged": all(v == 1.0 for key, values in table.items()
                                     if key.startswith("Converged") for v in values),
    }
    figures.update(worst)
    with open(os.path.join(folder, "figures.json"), "w") as out:
        json.dump(figures, out, indent=2)
    print("%s: %d frames; first frame %.2f s, then %.0f ms a frame on average (%.0f-%.0f) through the filter; "
          "largest |dV| %.1e %%, bone penetration %.3f, smoothness ratio %.2f, all converged: %s; written to %s"
          % (name, len(times), seconds[0], figures["per_frame_ms_mean"], figures["per_frame_ms_min"],
             figures["per_frame_ms_max"], worst["largest_abs_volume_change_percent"],
             worst["largest_bone_penetration"], worst["largest_smoothness_ratio"], worst["every_frame_converged"],
             folder))
    if slip:
        print("  largest slip at the data set's %d attachment landmarks (mm): %s" % (
            len(slip.probes), ", ".join("%s %.2f" % item for item in sorted(slip.worst.items()))))
    print("  fibre points outside their muscle / inside a bone over every frame (vtkSelectEnclosedPoints): %s" % (
        ", ".join("%s %d / %d" % (m, fibres_outside[m], fibres_in_bone[m]) for m in sorted(fibres_outside))))
    for who, shares in figures.get("moment_arm_inside_blemker2005_percent", {}).items():
        print("  moment arms inside Blemker 2005's range, %s: %s (%% of poses; mean %.0f)" % (
            who, ", ".join("%s %.0f" % item for item in shares.items()), sum(shares.values()) / max(1, len(shares))))
    print("  largest step of a muscle point between frames against its median: %s" % ", ".join(
        "%s %.1fx" % item for item in sorted(figures["largest_step_against_median"].items())))
    return figures


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--output", default=os.path.join(mdexamples.SOURCE_DIR, "results", "motion"))
    parser.add_argument("--plugin", help="path of MuscleDeformation.so (found in build*/ by default)")
    parser.add_argument("--data", help="folder holding lhdl_hip_r (default ../shared/data)")
    parser.add_argument("--case", default="all", choices=["all", "phantom", "hip_flexion", "hip_adduction"])
    parser.add_argument("--every", type=int, default=1, help="a picture every this many frames")
    parser.add_argument("--moment-arm-step", type=float, default=MOMENT_ARM_STEP[0],
                        help="degrees: the LHDL fibres' moment arms from each frame stepped by +- this much in "
                             "its coordinate (OpenSimModelReader's MomentArmStep); 0: from differences between frames")
    parser.add_argument("--paths-over-bones", action="store_true",
                        help="the LHDL paths kept out of the bones (PathsOverBones) before they become action lines")
    parser.add_argument("--path-points-per-segment", type=int, default=PATHS_OVER_BONES[1],
                        help="with --paths-over-bones: PathsOverBones' PointsPerSegment")
    parser.add_argument("--frames", type=int, help="the first this many frames of each motion (all)")
    args = parser.parse_args(argv)
    FRAMES[0] = args.frames
    MOMENT_ARM_STEP[0] = args.moment_arm_step
    PATHS_OVER_BONES[:] = [args.paths_over_bones, args.path_points_per_segment]
    mdexamples.load_plugin(explicit=args.plugin)
    results = []
    replays = []  # (folder, case, camera): each LHDL case's state file, written once every case ran
    if args.case in ("all", "phantom"):
        motion, camera = phantom_pipeline()
        results.append(run_case("phantom", motion, camera, args.output, args.every))
    for name in ("hip_flexion", "hip_adduction"):
        if args.case not in ("all", name):
            continue
        data = mdexamples.lhdl_data_dir(args.data, name)
        if data is None:
            continue
        motion, camera = lhdl_pipeline(data, name)
        results.append(run_case("lhdl_" + name, motion, camera, args.output, args.every,
                                landmarks=os.path.join(data, "lhdl_hip_r", LANDMARKS)))
        replays.append((os.path.join(args.output, "lhdl_" + name), "lhdl_" + name, camera))
    for folder, case, camera in replays:
        write_replay_state(folder, case, camera)
    return 0 if results else mdexamples.SKIPPED


if __name__ == "__main__":
    sys.exit(main())
