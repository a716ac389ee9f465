#!/usr/bin/env bash
# SPDX-License-Identifier: BSD-3-Clause
# Installs what is missing (Debian 12), builds, and runs the whole test suite headless.
#   bash Testing/run_test_suite.sh [extra ctest arguments]
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/bootstrap.sh"

md_install_dependencies "${MD_TEST_PACKAGES[@]}"
md_build
if [ ! -d "$MD_DATA_DIR/lhdl_hip_r" ]; then
  echo "== Real data not found in $MD_DATA_DIR: the real-data tests will be reported as skipped"
fi
echo "== Running the tests"
ctest --test-dir "$MD_BUILD_DIR" --output-on-failure --parallel "$(nproc)" "$@"
