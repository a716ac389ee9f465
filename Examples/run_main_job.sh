#!/usr/bin/env bash
# SPDX-License-Identifier: BSD-3-Clause
# Installs what is missing (Debian 12), builds, and runs the main job: the whole interpolation
# method against the one-pass method on the MusculoskeletalPhantom and, when present, on the real
# LHDL hip data (60 degrees of hip flexion, 4 steps); then whole motions with
# MotionMuscleDeformation: the phantom through a flexion sweep and, when present, the LHDL hip
# through every frame of hip_flexion.mot and hip_adduction.mot (time series .pvd, pictures of every
# frame, a movie, plots of the measures over time).
#   bash Examples/run_main_job.sh [output folder, default results/]
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/../Testing/bootstrap.sh"

OUTPUT=$(realpath -m "${1:-$MD_SOURCE_DIR/results}")
md_install_dependencies
md_build
mkdir -p "$OUTPUT"

echo "== Phantom, 30 degrees of hip flexion in 8 steps (the femur sweeps into the rectus femoris)"
md_with_display pvpython "$MD_SOURCE_DIR/Examples/phantom_interpolation.py" --output "$OUTPUT/phantom" \
  --flexion 30 --steps 8
if [ -d "$MD_DATA_DIR/lhdl_hip_r" ]; then
  echo "== LHDL right hip (real data), 60 degrees of hip flexion"
  md_with_display pvpython "$MD_SOURCE_DIR/Examples/lhdl_hip_interpolation.py" --data "$MD_DATA_DIR" \
    --motion hip_flexion --frame 35 --output "$OUTPUT/lhdl"
else
  echo "== Real data not found in $MD_DATA_DIR: ran the phantom only"
fi
echo "== Whole motions, every frame deformed from the one before (MotionMuscleDeformation)"
md_with_display pvpython "$MD_SOURCE_DIR/Examples/motion.py" --output "$OUTPUT/motion" --data "$MD_DATA_DIR"
echo
echo "Results (pictures .png, meshes .vtp, figures.json; the motions as .pvd time series, frames, movies and plots in motion/) are in: $OUTPUT"
