# SPDX-License-Identifier: BSD-3-Clause
# Installs what is missing on Debian 12, then configures and builds MuscleDeformation (Release).
# Sourced by Examples/run_main_job.sh and Testing/run_test_suite.sh.
#   MUSCLEDEFORMATION_BUILD_DIR  build folder (default: build/ in the source tree)
#   MUSCLEDEFORMATION_DATA_DIR   real data folder (default: ../shared/data beside the source tree)

MD_SOURCE_DIR=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
MD_BUILD_DIR=${MUSCLEDEFORMATION_BUILD_DIR:-$MD_SOURCE_DIR/build}
MD_DATA_DIR=${MUSCLEDEFORMATION_DATA_DIR:-$MD_SOURCE_DIR/../shared/data}

# ParaView 5.11 carries its own VTK: never add libvtk9-dev or python3-vtk9 here (python3-vtk9
# conflicts with python3-paraview). The -dev packages after qtxmlpatterns5-dev-tools are ones
# ParaView's CMake package looks for when a plugin asks for ParaView::RemotingCore.
# libqt5svg5: the GUI's toolbar icons are SVG; without it they show blank.
# openmpi-bin: mpiexec, to run Examples/batch.py's trials over ranks (pvbatch --mpi).
MD_PACKAGES=(
  cmake g++ make
  paraview paraview-dev python3-paraview
  libeigen3-dev libgtest-dev
  xvfb xauth libgl1-mesa-dri
  qtbase5-dev qttools5-dev qtxmlpatterns5-dev-tools
  libopenmpi-dev libdouble-conversion-dev liblz4-dev libutfcpp-dev
  libpugixml-dev
  libqt5svg5 openmpi-bin
)

# What the test suite needs besides: its hygiene checks (Testing/lint.sh).
MD_TEST_PACKAGES=(clang-format clang-tidy git)

# Installs what is missing of MD_PACKAGES (and of any packages named as arguments).
md_install_dependencies() {
  local missing=() package
  for package in "${MD_PACKAGES[@]}" "$@"; do
    if ! dpkg-query -W -f='${Status}' "$package" 2>/dev/null | grep -q "install ok installed"; then
      missing+=("$package")
    fi
  done
  if [ ${#missing[@]} -eq 0 ]; then
    echo "== All required Debian packages are installed"
    return 0
  fi
  local sudo=""
  if [ "$(id -u)" -ne 0 ]; then
    command -v sudo >/dev/null || { echo "Installing ${missing[*]} needs root (or sudo)" >&2; return 1; }
    sudo="sudo"
  fi
  echo "== Installing: ${missing[*]}"
  $sudo apt-get update
  DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y --no-install-recommends "${missing[@]}"
}

md_build() {
  echo "== Building in $MD_BUILD_DIR"
  cmake -S "$MD_SOURCE_DIR" -B "$MD_BUILD_DIR" -DCMAKE_BUILD_TYPE=Release \
    -DMUSCLEDEFORMATION_DATA_DIR="$MD_DATA_DIR"
  cmake --build "$MD_BUILD_DIR" --parallel "$(nproc)"
  MD_PLUGIN=$(find "$MD_BUILD_DIR" -name MuscleDeformation.so -print -quit)
  [ -n "$MD_PLUGIN" ] || { echo "the build produced no MuscleDeformation.so" >&2; return 1; }
  export MUSCLEDEFORMATION_PLUGIN="$MD_PLUGIN"
}

# Runs a command with an X display: rendering needs one (a private Xvfb when there is none).
md_with_display() {
  "$MD_SOURCE_DIR/Testing/with_display.sh" "$@"
}
