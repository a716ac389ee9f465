# SPDX-License-Identifier: BSD-3-Clause
"""The whole interpolation method on the MusculoskeletalPhantom, with screenshots of every step.

Run with pvpython (under xvfb-run on a machine without a display):

    pvpython Examples/phantom_interpolation.py --output results/phantom [--flexion 60] [--steps 4]

Writes, into the output folder: phantom_rest.png and phantom_current.png (bones, muscles and
action lines in the rest and the current pose), phantom_step_<j>.png for every interpolation
step j = 0..N, phantom_hulls.png (the muscles' coarse hulls), phantom_method_step_<j>.png (the
muscles at every step of InterpolatedMuscleDeformation), phantom_one_pass_resolved.png (the
one-pass method), phantom_deformed_one_pass.png (MuscleDeformation alone), the meshes of every
block as .vtp, and figures.json; prints the comparison of the two methods. At 30 degrees
(--flexion 30 --steps 8) the femur swallows part of the rectus femoris in one pass: the paper's
"fixed on the bone" case.
"""
import argparse
import json
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import mdexamples  # noqa: E402
from paraview import simple  # noqa: E402


def phantom_inputs(flexion=60.0):
    """The phantom's five outputs as the inputs of mdexamples.interpolation_pipeline."""
    phantom = simple.MusculoskeletalPhantom(Flexion=flexion)
    names = ("muscles", "bones_rest", "bones_current", "lines_rest", "lines_current")
    inputs = {name: simple.OutputPort(phantom, port) for port, name in enumerate(names)}
    inputs["phantom"] = phantom
    return inputs


def lateral_camera(view, scale=1.0):
    """From the lateral side, a little from the front and above; the same for every picture."""
    mdexamples.set_camera(view, direction=(1.0, 0.55, 0.25), up=(0.0, 0.0, 1.0),
                          focal=[40.0 * scale, 60.0 * scale, -120.0 * scale], distance=1300.0 * scale)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--output", default=os.path.join(mdexamples.SOURCE_DIR, "results", "phantom"))
    parser.add_argument("--plugin", help="path of MuscleDeformation.so (found in build*/ by default)")
    parser.add_argument("--flexion", type=float, default=60.0, help="hip flexion of the current pose, degrees")
    parser.add_argument("--steps", type=int, default=4, help="interpolation steps N (0 = automatic)")
    parser.add_argument("--mode", choices=["Rigid", "Linear"], default="Rigid")
    args = parser.parse_args(argv)
    mdexamples.load_plugin(explicit=args.plugin)

    pipeline = mdexamples.interpolation_pipeline(phantom_inputs(args.flexion), args.steps, args.mode)
    view = mdexamples.make_view()
    images, figures = mdexamples.run(pipeline, view, lateral_camera, args.output, "phantom")
    mdexamples.close_view(view)
    figures.update({"data": "MusculoskeletalPhantom", "flexion_degrees": args.flexion, "mode": args.mode})
    with open(os.path.join(args.output, "figures.json"), "w") as out:
        json.dump(figures, out, indent=2)
    print("Phantom: %d steps (%s), %d pictures and the meshes written to %s"
          % (figures["number_of_steps"], args.mode, len(images), os.path.abspath(args.output)))
    print(mdexamples.method_summary(figures))
    return 0


if __name__ == "__main__":
    sys.exit(main())
