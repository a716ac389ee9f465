# SPDX-License-Identifier: BSD-3-Clause
"""The LHDL right hip (real scans): the whole interpolation method against the one-pass method.

Run with pvpython (under xvfb-run on a machine without a display):

    pvpython Examples/lhdl_hip_interpolation.py --output results/lhdl [--motion hip_flexion --frame 35]

Reads ../shared/data/lhdl_hip_r (or --data / $MUSCLEDEFORMATION_DATA_DIR) through its own OpenSim
files: OpenSimModelReader places the femur and the muscle paths at the frame of the motion
(kinematics/<motion>.mot; frame 35 of hip_flexion is 60 degrees), MoveWithBodies moves the
scanned femur with it, ActionLineGrouping makes the paths the muscles' action lines. The four muscles are deformed
together by InterpolatedMuscleDeformation (N steps, obstacles the iliac bone, the sacrum and the
femur) and by the one-pass method (one step, the same static resolution). Writes lhdl_rest.png,
lhdl_current.png, lhdl_hulls.png, lhdl_step_<j>.png (bones and action lines),
lhdl_method_step_<j>.png (the muscles at every step of the method), lhdl_one_pass_resolved.png,
lhdl_deformed_one_pass.png (MuscleDeformation alone), the meshes as .vtp and figures.json (every
measure of docs/DESIGN.md per muscle and step), and prints the comparison. Exits with code 77 (skipped)
when the data is absent.
"""
import argparse
import json
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import lhdl  # noqa: E402
import mdexamples  # noqa: E402

HIP_CENTRE = (143.48, 243.44, -432.67)


def lateral_camera(view):
    """The right hip from the lateral side (-x), a little from the front (-y) and above."""
    mdexamples.set_camera(view, direction=lhdl.VIEW_DIRECTION, up=lhdl.VIEW_UP,
                          focal=[HIP_CENTRE[0], HIP_CENTRE[1] - 120.0, HIP_CENTRE[2] - 120.0], distance=1500.0)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--output", default=os.path.join(mdexamples.SOURCE_DIR, "results", "lhdl"))
    parser.add_argument("--plugin", help="path of MuscleDeformation.so (found in build*/ by default)")
    parser.add_argument("--data", help="folder holding lhdl_hip_r (default ../shared/data)")
    parser.add_argument("--motion", default="hip_flexion", choices=["hip_flexion", "hip_adduction"])
    parser.add_argument("--frame", type=int, default=35)
    parser.add_argument("--steps", type=int, default=4, help="interpolation steps N (0 = automatic)")
    parser.add_argument("--mode", choices=["Rigid", "Linear"], default="Rigid")
    args = parser.parse_args(argv)
    data = mdexamples.lhdl_data_dir(args.data)
    if data is None:
        return mdexamples.SKIPPED
    mdexamples.load_plugin(explicit=args.plugin)

    inputs = lhdl.load(os.path.join(data, "lhdl_hip_r"), args.motion, args.frame)
    frame = inputs.pop("frame")
    inputs.pop("model")
    pipeline = mdexamples.interpolation_pipeline(inputs, args.steps, args.mode)
    # The muscles' origins and insertions held on their bones by the data set's own landmarks.
    pipeline["interpolated"].AttachmentFileName = os.path.join(data, "lhdl_hip_r", "attachment_areas_rp_mm.csv")
    view = mdexamples.make_view()
    images, figures = mdexamples.run(pipeline, view, lateral_camera, args.output, "lhdl")
    mdexamples.close_view(view)
    figures.update({"data": "LHDL lhdl_hip_r", "motion": frame.motion, "frame": frame.index,
                    "hip_flexion_degrees": frame.hip_flexion, "hip_adduction_degrees": frame.hip_adduction,
                    "mode": args.mode})
    with open(os.path.join(args.output, "figures.json"), "w") as out:
        json.dump(figures, out, indent=2)
    print("LHDL hip, %s frame %d (flexion %.1f, adduction %.1f degrees): %d steps (%s), %d pictures and "
          "the meshes written to %s" % (frame.motion, frame.index, frame.hip_flexion, frame.hip_adduction,
                                        figures["number_of_steps"], args.mode, len(images),
                                        os.path.abspath(args.output)))
    print(mdexamples.method_summary(figures))
    return 0


if __name__ == "__main__":
    sys.exit(main())
