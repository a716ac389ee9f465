# SPDX-License-Identifier: BSD-3-Clause
"""Helpers shared by the MuscleDeformation example scripts and image tests (pvpython).

Finding and loading the plugin, a fixed render view, screenshots, and writing
every block of an output as a .vtp file.
"""
import glob
import os
import sys

from paraview import simple
from paraview import servermanager

HERE = os.path.dirname(os.path.abspath(__file__))
SOURCE_DIR = os.path.dirname(HERE)

BONE_COLOUR = [0.89, 0.85, 0.79]
MUSCLE_COLOURS = [[0.80, 0.25, 0.22], [0.70, 0.35, 0.55], [0.85, 0.50, 0.20], [0.60, 0.20, 0.30]]
LINE_COLOUR = [0.10, 0.25, 0.75]
CURRENT_LINE_COLOUR = [0.05, 0.55, 0.30]


class QuietStandardError:
    """Holds what C and C++ code writes to the standard error (file descriptor 2) while the block
    runs, in `text`, instead of the terminal: a movie encoder writes a line a frame."""

    def __enter__(self):
        import tempfile
        sys.stderr.flush()
        self._file = tempfile.TemporaryFile(mode="w+b")
        self._saved = os.dup(2)
        os.dup2(self._file.fileno(), 2)
        self.text = ""
        return self

    def __exit__(self, *exc):
        sys.stderr.flush()
        os.dup2(self._saved, 2)
        os.close(self._saved)
        self._file.seek(0)
        self.text = self._file.read().decode(errors="replace")
        self._file.close()
        return False


def find_plugin(explicit=None):
    """Path of MuscleDeformation.so: the argument, $MUSCLEDEFORMATION_PLUGIN, or the build folder."""
    candidates = [explicit, os.environ.get("MUSCLEDEFORMATION_PLUGIN")]
    candidates += sorted(glob.glob(os.path.join(SOURCE_DIR, "build*", "lib", "**", "MuscleDeformation.so"),
                                   recursive=True))
    for candidate in candidates:
        if candidate and os.path.isfile(candidate):
            return os.path.abspath(candidate)
    sys.exit("MuscleDeformation.so not found: build the project first (see README.md), "
             "or pass --plugin / set MUSCLEDEFORMATION_PLUGIN")


def load_plugin(namespace=None, explicit=None):
    """Loads the plugin; its filters become functions of paraview.simple (and of `namespace`)."""
    path = find_plugin(explicit)
    simple.LoadPlugin(path, remote=False, ns=vars(simple))
    if namespace is not None:
        simple.LoadPlugin(path, remote=False, ns=namespace)
    return path


def data_dir(explicit=None):
    """The real data folder (holding lhdl_hip_r), or None when it is absent: the argument, else
    $MUSCLEDEFORMATION_DATA_DIR, else ../shared/data beside the source tree."""
    folder = explicit or os.environ.get("MUSCLEDEFORMATION_DATA_DIR") or \
        os.path.join(SOURCE_DIR, "..", "shared", "data")
    return os.path.abspath(folder) if os.path.isdir(os.path.join(folder, "lhdl_hip_r")) else None


SKIPPED = 77  # the exit code ctest reports as skipped


def lhdl_data_dir(explicit=None, what=None):
    """data_dir(explicit); when the LHDL data is absent, says that `what` (the run, when None) is
    skipped and returns None."""
    data = data_dir(explicit)
    if data is None:
        print("SKIPPED%s: the LHDL data (lhdl_hip_r) was not found; pass --data or set MUSCLEDEFORMATION_DATA_DIR"
              % ("" if what is None else " " + what))
    return data


def named_leaves(data):
    """The leaves of a multiblock by block name."""
    from vtkmodules.vtkCommonDataModel import vtkCompositeDataSet
    result, iterator = {}, data.NewIterator()
    iterator.InitTraversal()
    while not iterator.IsDoneWithTraversal():
        result[iterator.GetCurrentMetaData().Get(vtkCompositeDataSet.NAME())] = iterator.GetCurrentDataObject()
        iterator.GoToNextItem()
    return result


def inside(points, surface):
    """Which points of the dataset `points` lie inside the closed `surface`, by VTK's own test
    (vtkSelectEnclosedPoints), apart from the plugin's: a boolean numpy array."""
    from vtkmodules.util.numpy_support import vtk_to_numpy
    from vtkmodules.vtkFiltersModeling import vtkSelectEnclosedPoints
    select = vtkSelectEnclosedPoints()
    select.SetInputData(points)
    select.SetSurfaceData(surface)
    select.SetTolerance(1e-9)
    select.Update()
    return vtk_to_numpy(select.GetOutput().GetPointData().GetArray("SelectedPoints")).astype(bool)


def make_view(size=(900, 900)):
    """A render view with a white background and no orientation axes."""
    view = simple.CreateView("RenderView")
    view.ViewSize = list(size)
    view.OrientationAxesVisibility = 0
    if hasattr(view, "UseColorPaletteForBackground"):
        view.UseColorPaletteForBackground = 0
    view.Background = [1.0, 1.0, 1.0]
    view.EnableRenderOnInteraction = 0
    return view


def _show(source, view, port):
    """Shows `source` (a proxy, or simple.OutputPort(proxy, k), whose Port is k) or its `port`."""
    return simple.Show(source if port is None else simple.OutputPort(source, port), view)


def _show_in_colour(source, view, colour, port):
    """Shows `source` as a surface in one colour (no colour map)."""
    display = _show(source, view, port)
    display.Representation = "Surface"
    display.ColorArrayName = ['POINTS', '']
    display.AmbientColor = colour
    display.DiffuseColor = colour
    return display


def show_surface(source, view, colour, opacity=1.0, port=None):
    display = _show_in_colour(source, view, colour, port)
    display.Opacity = opacity
    display.Specular = 0.2
    return display


def show_lines(source, view, colour, port=None, width=4.0):
    display = _show_in_colour(source, view, colour, port)
    display.LineWidth = width
    display.RenderLinesAsTubes = 1
    return display


def hide_all(view):
    for representation in view.Representations:
        representation.Visibility = 0


def close_view(view):
    """Deletes the view while the display is still there (at interpreter exit it is not)."""
    simple.Delete(view)


def set_camera(view, direction=(1.0, 0.0, 0.0), up=(0.0, 0.0, 1.0), zoom=1.0, focal=None, distance=None,
               bounds=None):
    """Looks from the side `direction` points to: at `focal` from `distance` when given (the
    same framing for every picture of a series), fitted to `bounds` (xmin, xmax, ..., zmax) when
    given, else fitted to what is shown."""
    length = sum(c * c for c in direction) ** 0.5
    unit = [c / length for c in direction]
    view.CameraViewUp = list(up)
    view.CameraViewAngle = 30
    if focal is not None and distance is not None:
        view.CameraFocalPoint = list(focal)
        view.CameraPosition = [focal[i] + distance * unit[i] for i in range(3)]
        return
    view.CameraPosition = unit
    view.CameraFocalPoint = [0.0, 0.0, 0.0]
    if bounds is not None:
        view.ResetCamera(*bounds)
    else:
        view.ResetCamera(False)
    view.GetActiveCamera().Zoom(zoom)


def padded(bounds, share=0.1):
    """`bounds` (xmin, xmax, ..., zmax) grown by `share` of their largest extent on every side."""
    margin = share * max(bounds[2 * a + 1] - bounds[2 * a] for a in range(3))
    return [b - margin if i % 2 == 0 else b + margin for i, b in enumerate(bounds)]


def state_view():
    """A render view in a layout of its own, for a state file: a state whose view is in no layout
    opens in the GUI as a blank window."""
    layout = simple.CreateLayout("Layout #1")
    view = simple.CreateView("RenderView")
    simple.AssignViewToLayout(view=view, layout=layout, hint=0)
    return view


def colour_by_role(display, view):
    """`display` coloured by the cell array Role with the plugin's categorical colours (what the
    GUI's Apply does with the plugin's display defaults), without a colour legend."""
    simple.ColorBy(display, ("CELLS", "Role"))
    display.SetScalarBarVisibility(view, False)


def save_state(view, path, direction, up, bounds, time=None):
    """The session as the state file `path`: time snapped to the data's steps (at `time` when
    given), `view` looking from `direction` fitted to `bounds`. Deletes `view` after: a view left
    to the interpreter's exit fails in X."""
    scene = simple.GetAnimationScene()
    scene.UpdateAnimationUsingDataTimeSteps()
    scene.PlayMode = "Snap To TimeSteps"
    if time is not None:
        scene.AnimationTime = time
    simple.Render(view)  # the first render fits the camera to everything: fit it after
    set_camera(view, direction, up, bounds=bounds)
    simple.Render(view)
    simple.SaveState(path)
    simple.Delete(view)


def screenshot(view, path, time=None):
    if time is not None:
        view.ViewTime = time
    simple.Render(view)
    simple.SaveScreenshot(path, view, ImageResolution=list(view.ViewSize))
    return path


def write_blocks(source, folder, prefix, port=None, time=None):
    """Writes every polydata block of an output as <prefix>_<block>.vtp; returns the paths."""
    from vtkmodules.vtkCommonDataModel import vtkMultiBlockDataSet, vtkPolyData, vtkCompositeDataSet
    from vtkmodules.vtkIOXML import vtkXMLPolyDataWriter

    # simple.OutputPort(proxy, k) is a proxy whose Port is k.
    port = getattr(source, "Port", 0) if port is None else port
    if time is not None:
        source.UpdatePipeline(time)
    data = servermanager.Fetch(source, idx=port)
    os.makedirs(folder, exist_ok=True)
    written = []

    def write(polydata, name):
        writer = vtkXMLPolyDataWriter()
        path = os.path.join(folder, "%s_%s.vtp" % (prefix, name) if name else "%s.vtp" % prefix)
        writer.SetFileName(path)
        writer.SetInputData(polydata)
        writer.SetDataModeToBinary()
        writer.Write()
        written.append(path)

    if isinstance(data, vtkPolyData):
        write(data, "")
    elif isinstance(data, vtkMultiBlockDataSet):
        for index in range(data.GetNumberOfBlocks()):
            block = data.GetBlock(index)
            name = data.GetMetaData(index).Get(vtkCompositeDataSet.NAME()) if data.HasMetaData(index) else None
            if isinstance(block, vtkPolyData):
                write(block, name or str(index))
    return written


def interpolation_pipeline(inputs, steps=4, mode="Rigid"):
    """ActionLineMatching and BoneInterpolation (bones, and matched action lines) on `inputs`, a
    dict of output ports: muscles, bones_rest, bones_current, lines_rest, lines_current."""
    pipeline = dict(inputs)
    pipeline["matching"] = simple.ActionLineMatching(Input=inputs["lines_rest"],
                                                     CurrentPose=inputs["lines_current"])
    pipeline["bones"] = simple.BoneInterpolation(Input=inputs["bones_rest"],
                                                 CurrentPose=inputs["bones_current"],
                                                 NumberOfSteps=steps, InterpolationMode=mode)
    # Matched action lines carry their current position: no CurrentPose needed. Their points
    # move with different bodies, so they are interpolated linearly.
    pipeline["lines"] = simple.BoneInterpolation(Input=simple.OutputPort(pipeline["matching"], 0),
                                                 NumberOfSteps=steps, InterpolationMode="Linear")
    # The whole method (the paper's interpolation, each step solved on the muscles' own surfaces:
    # the default DeformationMesh), and
    # the one-pass method as the paper has it to compare with: one step on the hull, the same
    # static resolution and measures, and the paper's deformation step, in which bones only stop
    # points (BoneContactWeight 0; the method's own step lets them push the muscle).
    method_inputs = dict(Input=inputs["muscles"], BonesRest=inputs["bones_rest"],
                         BonesCurrent=inputs["bones_current"], ActionLinesRest=inputs["lines_rest"],
                         ActionLinesCurrent=inputs["lines_current"], BoneInterpolationMode=mode)
    pipeline["interpolated"] = simple.InterpolatedMuscleDeformation(NumberOfSteps=steps, **method_inputs)
    pipeline["one_pass"] = simple.InterpolatedMuscleDeformation(NumberOfSteps=1, DeformationMesh="Hull (paper)",
                                                                BoneContactWeight=0.0, AttachmentAreas="Off",
                                                                **method_inputs)
    pipeline["hulls"] = simple.HullDecimation(Input=inputs["muscles"])
    # One pass RP -> CP (the paper's original method), every muscle together, bones in the CP.
    pipeline["deformation"] = simple.MuscleDeformation(Input=inputs["muscles"],
                                                       ActionLines=simple.OutputPort(pipeline["matching"], 0),
                                                       Obstacles=[inputs["bones_current"]],
                                                       Hull=pipeline["hulls"])
    return pipeline


def show_pose(view, pipeline, pose):
    """Bones, muscles (rest pose) and action lines in pose 'rest' or 'current'."""
    hide_all(view)
    show_surface(pipeline["bones_" + pose], view, BONE_COLOUR)
    show_surface(pipeline["muscles"], view, MUSCLE_COLOURS[0], opacity=0.45)
    show_lines(pipeline["lines_" + pose], view, LINE_COLOUR if pose == "rest" else CURRENT_LINE_COLOUR)


def show_hulls(view, pipeline):
    """The muscles with their coarse hulls as wireframes, over the rest-pose bones."""
    hide_all(view)
    show_surface(pipeline["bones_rest"], view, BONE_COLOUR, opacity=0.35)
    show_surface(pipeline["muscles"], view, MUSCLE_COLOURS[0])
    display = _show_in_colour(pipeline["hulls"], view, LINE_COLOUR, None)
    display.Representation = "Wireframe"
    display.LineWidth = 1.5


def show_deformed(view, pipeline):
    """The muscles deformed in one pass to the current pose, with the current-pose bones and
    action lines, and the rest-pose muscles faintly."""
    hide_all(view)
    show_surface(pipeline["bones_current"], view, BONE_COLOUR)
    show_surface(pipeline["muscles"], view, MUSCLE_COLOURS[1], opacity=0.15)
    show_surface(pipeline["deformation"], view, MUSCLE_COLOURS[0])
    show_lines(pipeline["lines_current"], view, CURRENT_LINE_COLOUR)


def show_steps(view, pipeline):
    """Interpolated bones and action lines (their time is the step) over the rest-pose muscles."""
    hide_all(view)
    show_surface(pipeline["bones"], view, BONE_COLOUR)
    show_surface(pipeline["muscles"], view, MUSCLE_COLOURS[0], opacity=0.3)
    show_lines(pipeline["lines"], view, LINE_COLOUR)


def show_method(view, pipeline, result="interpolated"):
    """A result of the whole method (its time is the step) with the bones and action lines of
    the same step; the one-pass result is shown with the current-pose bones."""
    hide_all(view)
    show_surface(pipeline["bones"] if result == "interpolated" else pipeline["bones_current"], view, BONE_COLOUR)
    show_surface(pipeline["muscles"], view, MUSCLE_COLOURS[1], opacity=0.12)
    show_surface(pipeline[result], view, MUSCLE_COLOURS[0])
    show_lines(pipeline["lines"] if result == "interpolated" else pipeline["lines_current"], view,
               CURRENT_LINE_COLOUR)


METHOD_MEASURES = ("VolumeChangePercent", "NewPenetrationCount", "MaxNewPenetrationDepth", "NewBonePenetrationCount",
                   "MaxNewBonePenetrationDepth", "MaxStaticShift", "StepStaticShift", "SharpEdgeCount",
                   "FlippedTriangleCount", "NumberOfIterations", "Converged", "HullSeconds", "StepSeconds",
                   "ElapsedSeconds")


def method_figures(source, time):
    """{muscle: {measure: value}} of an InterpolatedMuscleDeformation output at step `time`."""
    source.UpdatePipeline(time)
    data = servermanager.Fetch(source)
    return {name: {field: _field_value(data, field).get(name) for field in METHOD_MEASURES}
            for name in _field_value(data, "VolumeChangePercent")}


def method_summary(figures):
    """Lines comparing the whole method's last step with the one-pass method, per muscle."""
    method = figures["interpolation_method"]
    final, one_pass = method["steps"][-1]["muscles"], figures["one_pass_method"]
    lines = ["%-18s %22s %22s %14s %12s" % ("muscle (N = %d)" % method["number_of_steps"],
                                            "MaxStaticShift 1 / N", "SharpEdgeCount 1 / N", "dV % (N)",
                                            "seconds 1 / N")]
    for name in sorted(final):
        a, b = one_pass[name], final[name]
        lines.append("%-18s %10.2f / %9.2f %10d / %9d %14.5f %5.1f / %4.1f" % (
            name, a["MaxStaticShift"], b["MaxStaticShift"], a["SharpEdgeCount"], b["SharpEdgeCount"],
            b["VolumeChangePercent"], a["ElapsedSeconds"], b["ElapsedSeconds"]))
    return "\n".join(lines)


def _field_value(data, name):
    """{block name: value} of a one-value field-data array, for the blocks that have it."""
    from vtkmodules.vtkCommonDataModel import vtkCompositeDataSet, vtkMultiBlockDataSet

    if isinstance(data, vtkMultiBlockDataSet):
        blocks = [(data.GetMetaData(i).Get(vtkCompositeDataSet.NAME()) if data.HasMetaData(i) else str(i),
                   data.GetBlock(i)) for i in range(data.GetNumberOfBlocks())]
    else:
        blocks = [("", data)]
    values = {}
    for block_name, block in blocks:
        array = block.GetFieldData().GetArray(name) if block is not None else None
        if array is not None:
            values[block_name] = array.GetValue(0)
    return values


def run(pipeline, view, camera, output, prefix):
    """Pictures of both poses and of every step, the meshes as .vtp, and figures.json."""
    os.makedirs(output, exist_ok=True)
    bones, lines, matching = pipeline["bones"], pipeline["lines"], pipeline["matching"]
    bones.UpdatePipelineInformation()
    steps = int(list(bones.TimestepValues)[-1])
    images = []
    for pose in ("rest", "current"):
        show_pose(view, pipeline, pose)
        camera(view)
        images.append(screenshot(view, os.path.join(output, "%s_%s.png" % (prefix, pose))))
    show_hulls(view, pipeline)
    camera(view)
    images.append(screenshot(view, os.path.join(output, "%s_hulls.png" % prefix)))
    show_deformed(view, pipeline)
    camera(view)
    images.append(screenshot(view, os.path.join(output, "%s_deformed_one_pass.png" % prefix)))
    show_steps(view, pipeline)
    camera(view)
    figures = {"number_of_steps": steps, "steps": []}
    for step in range(steps + 1):
        images.append(screenshot(view, os.path.join(output, "%s_step_%d.png" % (prefix, step)), time=step))
        bones.UpdatePipeline(step)
        data = servermanager.Fetch(bones)
        figures["steps"].append({
            "step": step,
            "rotation_degrees_of_rigid_fit_per_block": _field_value(data, "RotationAngleDegrees"),
            "rigid_fit_max_residual_per_block": _field_value(data, "RigidFitMaxResidual"),
        })
        write_blocks(bones, output, "bones_step_%d" % step, time=step)
        write_blocks(lines, output, "action_lines_step_%d" % step, time=step)
    write_blocks(pipeline["muscles"], output, "muscles_rest")
    write_blocks(pipeline["hulls"], output, "hull")
    hulls = servermanager.Fetch(pipeline["hulls"])
    figures["hulls"] = {
        name: {field: _field_value(hulls, field).get(name)
               for field in ("HullVolumeRatio", "PointsOutsideHull", "HullSelfIntersections", "ElapsedSeconds")}
        for name in _field_value(hulls, "HullVolumeRatio")}
    write_blocks(pipeline["deformation"], output, "muscles_deformed_one_pass")
    deformed = servermanager.Fetch(pipeline["deformation"])
    figures["deformation_one_pass"] = {
        name: {field: _field_value(deformed, field).get(name)
               for field in ("VolumeChangePercent", "NumberOfIterations", "Converged", "FlippedTriangleCount",
                             "PointsFrozenInObstacles", "PointsStoppedAtObstacles", "RestActionLineSamplesInside",
                             "CurrentActionLineSamplesInside", "DeformationSeconds", "ElapsedSeconds")}
        for name in _field_value(deformed, "VolumeChangePercent")}
    # The whole method: every step, then the one-pass method for comparison.
    method, one_pass = pipeline["interpolated"], pipeline["one_pass"]
    method.UpdatePipelineInformation()
    method_steps = int(list(method.TimestepValues)[-1])
    figures["interpolation_method"] = {"number_of_steps": method_steps, "steps": []}
    show_method(view, pipeline)
    camera(view)
    for step in range(method_steps + 1):
        images.append(screenshot(view, os.path.join(output, "%s_method_step_%d.png" % (prefix, step)), time=step))
        figures["interpolation_method"]["steps"].append({"step": step, "muscles": method_figures(method, step)})
        write_blocks(method, output, "muscles_method_step_%d" % step, time=step)
    show_method(view, pipeline, "one_pass")
    camera(view)
    images.append(screenshot(view, os.path.join(output, "%s_one_pass_resolved.png" % prefix), time=1))
    figures["one_pass_method"] = method_figures(one_pass, 1)
    write_blocks(one_pass, output, "muscles_one_pass_resolved", time=1)
    write_blocks(pipeline["bones_rest"], output, "bones_rest")
    write_blocks(pipeline["bones_current"], output, "bones_current")
    write_blocks(matching, output, "action_lines_matched_rest", port=0)
    write_blocks(matching, output, "action_lines_matched_current", port=1)
    for key, source, port in (("action_line_points_rest", pipeline["lines_rest"], None),
                              ("action_line_points_current", pipeline["lines_current"], None),
                              ("matched_action_line_points", matching, 0)):
        data = servermanager.Fetch(source, idx=getattr(source, "Port", 0) if port is None else port)
        figures[key] = {data.GetMetaData(b).Get(data.NAME()): data.GetBlock(b).GetNumberOfPoints()
                        for b in range(data.GetNumberOfBlocks())}
    return images, figures
