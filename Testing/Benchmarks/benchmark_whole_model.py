# SPDX-License-Identifier: BSD-3-Clause
"""Seconds a frame of a whole OpenSim model's generated muscles through its motion, through the
filters in pvpython, as a user meets them.

    pvpython Testing/Benchmarks/benchmark_whole_model.py [data folder] [model] [points] [frames]

model: gait2392 (92 muscles, subject01_walk1), rajagopal2016 (18, its walk) or gait10dof18musc
(18, its walk; the default); points: MuscleFromPath's NumberOfPoints (150); frames: how many of
the motion's frames, from the first (30; 0 for all). The pipeline is the README's: the reader
(millimetres, walking in place on the pelvis, conditional path points faded over 10 degrees),
MuscleFromPath, MotionMuscleDeformation without fibres. Prints the surfaces' seconds, the first
frame's (from the rest pose), the mean, median and largest of the others', the first frame not
settled (MeasuresOverTime's Converged 0) and the range of every muscle's VolumeChangePercent and
MaxNewPenetrationDepth at the last frame. Asserts nothing. Set MUSCLEDEFORMATION_PLUGIN to
compare two builds side by side.
"""
import os
import statistics
import sys
import time

from paraview import servermanager, simple

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "Python"))
import mdtesting  # noqa: E402  (puts Examples/ on the path)
import motion as job  # noqa: E402  Examples/motion.py: the main job's pipeline and its helpers

MODELS = {
    "gait2392": ("gait2392_walk_forward", "subject01_simbody_adjusted.osim", "subject01_walk1_Kinematics_q.mot"),
    "rajagopal2016": ("rajagopal2016_walk_armless_18musc", "subject_walk_armless_18musc.osim",
                      "subject_walk_armless_coordinates.mot"),
    "gait10dof18musc": ("gait10dof18musc_walk", "walk_gait1018_subject01.osim", "walk_gait1018_state_reference.mot"),
}

mdtesting.load_plugin()
data = mdtesting.mdexamples.data_dir(sys.argv[1] if len(sys.argv) > 1 else None)
name = sys.argv[2] if len(sys.argv) > 2 else "gait10dof18musc"
points = int(sys.argv[3]) if len(sys.argv) > 3 else 150
frames = int(sys.argv[4]) if len(sys.argv) > 4 else 30
folder, model_file, motion_file = MODELS[name]
model_path = os.path.join(data or "", "opensim", folder, model_file)
if not data or not os.path.exists(model_path):
    print("skipped: opensim/%s/%s not found (give the data folder)" % (folder, model_file))
    sys.exit(0)

reader = simple.OpenSimModelReader(FileName=model_path, Scale=1000.0,
                                   MotionFileName=os.path.join(data, "opensim", folder, motion_file),
                                   ReferenceBody="pelvis", FollowReferenceBody=1, ConditionalPointFade=10.0)
muscles = simple.MuscleFromPath(Input=simple.OutputPort(reader, 3), Bones=simple.OutputPort(reader, 2),
                                NumberOfPoints=points)
motion = simple.MotionMuscleDeformation(Input=muscles, BonesRest=simple.OutputPort(reader, 2),
                                        BonesMotion=simple.OutputPort(reader, 0),
                                        ActionLinesRest=simple.OutputPort(reader, 3),
                                        ActionLinesMotion=simple.OutputPort(reader, 1), NumberOfFibres=0)
times = reader.TimestepValues
count = len(times) if frames <= 0 else min(frames, len(times))
start = time.perf_counter()
muscles.UpdatePipeline()
print("%s, %d points a muscle: surfaces %.2f s" % (name, points, time.perf_counter() - start), flush=True)
seconds = []
for k in range(count):
    start = time.perf_counter()
    motion.UpdatePipeline(times[k])
    seconds.append(time.perf_counter() - start)
    print("frame %d %.2f s" % (k, seconds[-1]), flush=True)
rest = seconds[1:] or [0.0]
print("first frame %.2f s; frames 1-%d: mean %.3f s, median %.3f s, largest %.2f s, total %.1f s"
      % (seconds[0], count - 1, statistics.mean(rest), statistics.median(rest), max(rest), sum(rest)))
columns = job.table_columns(servermanager.Fetch(motion, idx=3))
converged = [column for name, column in columns.items() if name.startswith("Converged (")]
unsettled = [r for r in range(count) if min(column[r] for column in converged) == 0]
print("first frame not settled:", unsettled[0] if unsettled else "none")
surfaces = servermanager.Fetch(motion)
for array in ("VolumeChangePercent", "MaxNewPenetrationDepth"):
    values = [surfaces.GetBlock(b).GetFieldData().GetArray(array).GetValue(0)
              for b in range(surfaces.GetNumberOfBlocks())
              if surfaces.GetBlock(b) and surfaces.GetBlock(b).GetFieldData().GetArray(array)]
    print("%s over %d muscles at frame %d: %.3g to %.3g" % (array, len(values), count - 1, min(values), max(values)))
