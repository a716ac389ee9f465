#!/usr/bin/env bash
# SPDX-License-Identifier: BSD-3-Clause
# Installs what is missing (Debian 12), builds, and runs the main job: the whole interpolation
# method against the one-pass method on the MusculoskeletalPhantom and, when present, on the real
# LHDL hip data (60 degrees of hip flexion, 4 steps).
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
echo
echo "Results (pictures .png, meshes .vtp, figures.json) are in: $OUTPUT"
