# SPDX-License-Identifier: BSD-3-Clause
"""What fibres cost a frame through MotionMuscleDeformation in pvpython, side by side.

    pvpython Testing/Benchmarks/benchmark_fibres.py [data folder] [motion: hip_flexion | hip_adduction] [rounds]
                                                    [moment-arm step, degrees]

The main job's LHDL pipeline (Examples/motion.py: four muscles, the data set's landmarks, via
points faded over 10 degrees) through every frame of the motion, as a user scrubbing it meets
them (each frame from the last), with NumberOfFibres 100 (the default: fibres carried to every
frame, their lengths and moment arms) and 0 (none), alternated `rounds` times (default 2) in one
process so that both meet the same machine. The reader's MomentArmStep is the main job's (1 degree:
each frame also deformed to two stepped poses a coordinate, fibres carried to each) unless given;
0 deforms each frame once. Prints each run's milliseconds a frame after the
first (mean, median, range) and the preparation (the first frame, with the fibres made); last,
the mean difference, of the whole frame and of its time beside the deformation's own (steadier).
Asserts nothing.
"""
import os
import statistics
import sys
import time

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "Examples"))
import mdexamples  # noqa: E402

mdexamples.load_plugin()
from paraview import servermanager  # noqa: E402

import motion as job  # noqa: E402

data = mdexamples.data_dir(sys.argv[1] if len(sys.argv) > 1 else None)
motion_name = sys.argv[2] if len(sys.argv) > 2 else "hip_flexion"
rounds = int(sys.argv[3]) if len(sys.argv) > 3 else 2
if len(sys.argv) > 4:
    job.MOMENT_ARM_STEP[0] = float(sys.argv[4])
if not data or not os.path.isdir(os.path.join(data, "lhdl_hip_r")):
    print("skipped: lhdl_hip_r not found (give the data folder)")
    sys.exit(0)
motion, _ = job.lhdl_pipeline(data, motion_name)
motion.UpdatePipelineInformation()
times = list(motion.TimestepValues)
means = {100: [], 0: []}
beside = {100: [], 0: []}  # a frame's time beside the deformation's own (the fibres are carried there)
for round_index in range(rounds):
    for fibres in (100, 0):
        motion.NumberOfFibres = fibres  # starts the motion again (the energies are kept)
        seconds = []
        for t in times:
            began = time.time()
            motion.UpdatePipeline(t)
            seconds.append(time.time() - began)
        later = [1000 * s for s in seconds[1:]]
        means[fibres].append(statistics.mean(later))
        core = job.table_columns(servermanager.Fetch(motion, idx=3))["FrameSeconds"][1:]
        beside[fibres].append(statistics.mean(later) - 1000 * statistics.mean(core))
        print("round %d, NumberOfFibres %3d: first frame %.2f s; then %.1f ms a frame on average, median %.1f (%.0f-%.0f); "
              "the deformation's own %.1f ms" % (round_index + 1, fibres, seconds[0], statistics.mean(later),
                                                 statistics.median(later), min(later), max(later),
                                                 1000 * statistics.mean(core)))
print("%s, %d frames: fibres cost %.1f ms a frame on average (%.1f with, %.1f without, means over %d rounds)"
      % (motion_name, len(times), statistics.mean(means[100]) - statistics.mean(means[0]), statistics.mean(means[100]),
         statistics.mean(means[0]), rounds))
# The deformation's own time varies from run to run by more than the fibres cost; what the frame
# spends beside it holds the fibres and little else, so its difference is the steadier figure.
print("%s: beside the deformation's own time, %.1f ms a frame with fibres, %.1f without: fibres cost %.1f ms"
      % (motion_name, statistics.mean(beside[100]), statistics.mean(beside[0]),
         statistics.mean(beside[100]) - statistics.mean(beside[0])))
