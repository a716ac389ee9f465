# SPDX-License-Identifier: BSD-3-Clause
"""Many trials at once: each (model, motion, surfaces) trial through MotionMuscleDeformation,
the trials spread over MPI ranks with ParaView's own MPI.

    mpiexec -n 2 pvbatch --mpi --symmetric Examples/batch.py --trials trials.json --output results/batch

(or with pvpython / pvbatch alone: one process does every trial). `--symmetric` runs the script on
every rank; each rank takes trials rank, rank + ranks, ... in the file's order, and runs them
alone (its pipeline on a controller of its own rank only, so that no filter waits for another
rank). Set OMP_NUM_THREADS=1 for one thread a rank. The trials file is a JSON list; each trial
has a "name" (its output folder) and a "kind":

- "phantom": the musculoskeletal phantom through a flexion sweep ("frames", 15; "flexion", 30);
- "lhdl": the LHDL right hip ("data", else $MUSCLEDEFORMATION_DATA_DIR or ../shared/data) through
  "motion" (hip_flexion or hip_adduction, from its kinematics/ folder), as Examples/motion.py runs it;
- "opensim": an OpenSim "model" through its "motion" (paths relative to the trials file), the
  muscles made from the model's paths (MuscleFromPath, "points" a muscle, 600), the model kept
  still about "reference_body" if given.

"frames" computes only the first that many frames of a motion (the phantom's: its sweep's steps,
computed with its rest pose as frame 0). Each rank writes, per trial, into
<output>/<name>/: the muscles at every frame (<name>_muscles_<k>.vtm) with <name>.pvd, and
figures.json (per frame: the seconds through the filter, and every measure of MeasuresOverTime).
When every rank is done, rank 0 writes <output>/summary.json: per trial its rank, frames,
seconds, the largest |VolumeChangePercent|, NewPenetrationCount and MaxNewBonePenetrationDepth
over its frames and muscles, and whether every frame settled. A trial that fails is reported with
its error; the other trials go on.
"""
import argparse
import json
import os
import sys
import time
import traceback

from vtkmodules.vtkParallelCore import vtkMultiProcessController

WORLD = vtkMultiProcessController.GetGlobalController()
RANK = WORLD.GetLocalProcessId() if WORLD else 0
RANKS = WORLD.GetNumberOfProcesses() if WORLD else 1
if RANKS > 1:
    # Each rank its own pipeline: ParaView splits a pipeline over the global controller's ranks
    # (and gathers it again to fetch), so every rank gets a controller of its own process alone.
    vtkMultiProcessController.SetGlobalController(WORLD.PartitionController(RANK, 0))

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import mdexamples  # noqa: E402
import motion as motion_example  # noqa: E402
from paraview import servermanager, simple  # noqa: E402


def opensim_pipeline(trial, folder):
    def path(key):
        found = os.path.join(folder, trial[key])
        if not os.path.isfile(found):
            raise RuntimeError("its %s %s is not found" % (key, found))
        return found

    reader = simple.OpenSimModelReader(registrationName=trial["name"] + " model", FileName=path("model"),
                                       MotionFileName=path("motion"), Scale=1000.0,
                                       ConditionalPointFade=motion_example.CONDITIONAL_POINT_FADE)
    if trial.get("reference_body"):
        reader.ReferenceBody = trial["reference_body"]
        reader.FollowReferenceBody = 1
    muscles = simple.MuscleFromPath(registrationName=trial["name"] + " muscles", Input=simple.OutputPort(reader, 3),
                                    Bones=simple.OutputPort(reader, 2), NumberOfPoints=int(trial.get("points", 600)))
    return simple.MotionMuscleDeformation(registrationName=trial["name"], Input=muscles,
                                          BonesRest=simple.OutputPort(reader, 2),
                                          BonesMotion=simple.OutputPort(reader, 0),
                                          ActionLinesRest=simple.OutputPort(reader, 3),
                                          ActionLinesMotion=simple.OutputPort(reader, 1))


def pipeline(trial, folder):
    kind = trial.get("kind")
    if kind == "phantom":
        return motion_example.phantom_pipeline(int(trial.get("frames", 15)), float(trial.get("flexion", 30.0)))[0]
    if kind == "lhdl":
        data = mdexamples.data_dir(trial.get("data"))
        if data is None:
            raise RuntimeError("the LHDL data is not found (give \"data\" or set MUSCLEDEFORMATION_DATA_DIR)")
        name = trial["motion"][:-4] if trial["motion"].endswith(".mot") else trial["motion"]
        return motion_example.lhdl_pipeline(data, name)[0]
    if kind == "opensim":
        return opensim_pipeline(trial, folder)
    raise RuntimeError("unknown kind %r (phantom, lhdl or opensim)" % kind)


def worst(columns, measure, absolute=False):
    values = [v for name, c in columns.items() if name.startswith(measure + " (") for v in c]
    values = [abs(v) for v in values] if absolute else values
    return max(values) if values else None


def run_trial(trial, folder, output):
    """Runs one trial; returns its summary."""
    out = os.path.join(output, trial["name"])
    os.makedirs(out, exist_ok=True)
    start = time.time()
    source = pipeline(trial, folder)
    source.UpdatePipelineInformation()
    times = list(source.TimestepValues) or [0.0]
    if "frames" in trial and trial.get("kind") != "phantom":
        times = times[:int(trial["frames"])]
    seconds, entries = [], []
    for k, t in enumerate(times):
        tick = time.time()
        source.UpdatePipeline(t)
        seconds.append(time.time() - tick)
        name = "%s_muscles_%d.vtm" % (trial["name"], k)
        motion_example.write_multiblock(source, 0, os.path.join(out, name))
        entries.append((t, 0, name))
    motion_example.write_pvd(os.path.join(out, trial["name"] + ".pvd"), entries)
    columns = motion_example.table_columns(servermanager.Fetch(source, idx=3))
    with open(os.path.join(out, "figures.json"), "w") as f:
        json.dump({"frame_seconds": seconds, "measures": columns}, f, indent=1, sort_keys=True)
    converged = [v for name, c in columns.items() if name.startswith("Converged (") for v in c]
    if not converged:
        raise RuntimeError("no muscle was deformed (the filters' messages say why)")
    return {"rank": RANK, "frames": len(times), "seconds": time.time() - start,
            "mean_frame_seconds": sum(seconds) / len(seconds),
            "max_abs_volume_change_percent": worst(columns, "VolumeChangePercent", True),
            "max_new_penetration_count": worst(columns, "NewPenetrationCount"),
            "max_new_bone_penetration_depth": worst(columns, "MaxNewBonePenetrationDepth"),
            "every_frame_settled": min(converged) == 1}


def release_pipelines():
    """Deletes every source, consumers first, so that a rank's memory does not grow trial by trial."""
    sources = list(simple.GetSources().values())
    while sources:
        consumed = {proxy.GetConsumerProxy(i) for proxy in sources for i in range(proxy.GetNumberOfConsumers())}
        free = [proxy for proxy in sources if proxy.SMProxy not in consumed] or sources
        for proxy in free:
            simple.Delete(proxy)
        sources = [proxy for proxy in sources if proxy not in free]


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--trials", required=True, help="the trials, a JSON list")
    parser.add_argument("--output", required=True, help="the folder to write into")
    parser.add_argument("--plugin", help="MuscleDeformation.so (else found beside the source tree)")
    args = parser.parse_args(argv)
    mdexamples.load_plugin(explicit=args.plugin)
    with open(args.trials) as f:
        trials = json.load(f)
    folder = os.path.dirname(os.path.abspath(args.trials))
    os.makedirs(args.output, exist_ok=True)
    for index in range(RANK, len(trials), RANKS):
        trial = trials[index]
        try:
            report = run_trial(trial, folder, args.output)
        except Exception as error:  # one trial's failure is reported, the others go on
            traceback.print_exc()
            report = {"rank": RANK, "error": str(error)}
        finally:
            release_pipelines()
        with open(os.path.join(args.output, "trial_%d.json" % index), "w") as f:
            json.dump(report, f, indent=1, sort_keys=True)
        print("rank %d: trial %r: %s" % (RANK, trial.get("name"), report), flush=True)
    if RANKS > 1:
        # pvbatch finalises MPI through the global controller: give it back the world's.
        vtkMultiProcessController.SetGlobalController(WORLD)
        WORLD.Barrier()
    if RANK == 0:
        summary = {}
        for index, trial in enumerate(trials):
            with open(os.path.join(args.output, "trial_%d.json" % index)) as f:
                summary[trial.get("name", str(index))] = json.load(f)
            os.remove(os.path.join(args.output, "trial_%d.json" % index))
        with open(os.path.join(args.output, "summary.json"), "w") as f:
            json.dump({"ranks": RANKS, "trials": summary}, f, indent=1, sort_keys=True)
        print("summary of %d trials on %d ranks: %s" % (len(trials), RANKS, os.path.join(args.output, "summary.json")))
    return 0


if __name__ == "__main__":
    main()  # no sys.exit: pvbatch finalises MPI after the script returns
