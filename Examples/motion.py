# SPDX-License-Identifier: BSD-3-Clause
"""Muscles through whole motions with MotionMuscleDeformation (pvpython).

Run with pvpython (under xvfb-run on a machine without a display):

    pvpython Examples/motion.py --output results/motion [--case phantom|hip_flexion|hip_adduction|all]

The phantom goes through a flexion sweep from its rest pose to 30 degrees in 15 frames (its bones
and action lines made time-varying by BoneInterpolation); the LHDL right hip (../shared/data, or
--data / $MUSCLEDEFORMATION_DATA_DIR; skipped when absent) through every frame of
kinematics/hip_flexion.mot and hip_adduction.mot, read by OpenSimModelReader with PlayMotion on
(MoveWithBodies moves the scanned bones, ActionLineGrouping makes the paths the action lines).
For each case it writes into <output>/<case>/: the deformed muscles and the bones at every frame
(<case>_muscles_<k>.vtm, <case>_bones_<k>.vtm) with <case>.pvd, which ParaView opens as one time
series; a picture of every frame (frames/<case>_<k>.png) and, where this ParaView can write one,
a movie (<case>.avi); plots of the measures over time (<case>_measures.png,
<case>_smoothness.png); and figures.json (per-frame time through the filter, and every measure at
every frame).
"""
import argparse
import json
import math
import os
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import mdexamples  # noqa: E402
from paraview import servermanager, simple  # noqa: E402

HIP_CENTRE = (143.48, 243.44, -432.67)


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
    bones = lhdl.producer(lhdl.named_blocks([(n, lhdl.read_surface(folder, n)) for n in lhdl.BONES]),
                          "LHDL bones (rest pose)")
    muscles = lhdl.producer(lhdl.named_blocks([(n, lhdl.read_surface(folder, n)) for n in lhdl.MUSCLES]),
                            "LHDL muscles")
    moved = simple.MoveWithBodies(registrationName="LHDL bones (motion)", Input=bones,
                                  BodyTransforms=simple.OutputPort(reader, 4), BodyOfSurface=lhdl.BODY_OF_SURFACE)
    lines = simple.ActionLineGrouping(registrationName="LHDL action lines", Input=muscles,
                                      Paths=simple.OutputPort(reader, 3), PathsCurrent=simple.OutputPort(reader, 1))
    motion = simple.MotionMuscleDeformation(registrationName="LHDL " + motion_name, Input=muscles, BonesRest=bones,
                                            BonesMotion=moved, ActionLinesRest=simple.OutputPort(lines, 0),
                                            ActionLinesMotion=simple.OutputPort(lines, 1))
    camera = {"direction": (-1.0, -0.55, 0.25), "up": (0.0, 0.0, 1.0),
              "focal": [HIP_CENTRE[0], HIP_CENTRE[1] - 120.0, HIP_CENTRE[2] - 120.0], "distance": 1500.0}
    return motion, camera


def write_multiblock(source, port, path):
    from vtkmodules.vtkIOXML import vtkXMLMultiBlockDataWriter
    writer = vtkXMLMultiBlockDataWriter()
    writer.SetFileName(path)
    writer.SetInputData(servermanager.Fetch(source, idx=port))
    writer.SetDataModeToBinary()
    writer.Write()


def write_pvd(path, entries):
    with open(path, "w") as out:
        out.write('<?xml version="1.0"?>\n<VTKFile type="Collection" version="0.1">\n  <Collection>\n')
        for t, part, name in entries:
            out.write('    <DataSet timestep="%.9g" part="%d" file="%s"/>\n' % (t, part, name))
        out.write('  </Collection>\n</VTKFile>\n')


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


def run_case(name, motion, camera, output, every):
    folder = os.path.join(output, name)
    os.makedirs(os.path.join(folder, "frames"), exist_ok=True)
    times = list(motion.TimestepValues)
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
    mdexamples.set_camera(view, camera["direction"], camera["up"], focal=camera["focal"],
                          distance=camera["distance"])
    entries = []
    for k, t in enumerate(times):
        motion.UpdatePipeline(t)
        muscles_file = "%s_muscles_%03d.vtm" % (name, k)
        bones_file = "%s_bones_%03d.vtm" % (name, k)
        write_multiblock(motion, 0, os.path.join(folder, muscles_file))
        write_multiblock(motion, 1, os.path.join(folder, bones_file))
        entries += [(t, 0, muscles_file), (t, 1, bones_file)]
        if k % every == 0 or k == len(times) - 1:
            mdexamples.screenshot(view, os.path.join(folder, "frames", "%s_%03d.png" % (name, k)), t)
    write_pvd(os.path.join(folder, name + ".pvd"), entries)
    movie = None
    try:
        scene = simple.GetAnimationScene()
        scene.UpdateAnimationUsingDataTimeSteps()
        movie = os.path.join(folder, name + ".avi")
        simple.SaveAnimation(movie, view, ImageResolution=[800, 800], FrameRate=10)
        if not os.path.isfile(movie):
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
    }
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
    return figures


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--output", default=os.path.join(mdexamples.SOURCE_DIR, "results", "motion"))
    parser.add_argument("--plugin", help="path of MuscleDeformation.so (found in build*/ by default)")
    parser.add_argument("--data", help="folder holding lhdl_hip_r (default ../shared/data)")
    parser.add_argument("--case", default="all", choices=["all", "phantom", "hip_flexion", "hip_adduction"])
    parser.add_argument("--every", type=int, default=1, help="a picture every this many frames")
    args = parser.parse_args(argv)
    mdexamples.load_plugin(explicit=args.plugin)
    results = []
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
        results.append(run_case("lhdl_" + name, motion, camera, args.output, args.every))
    return 0 if results else mdexamples.SKIPPED


if __name__ == "__main__":
    sys.exit(main())
