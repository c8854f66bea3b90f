#!/usr/bin/env bash
# Installs, from Debian's packages only, what building and testing Adaptive-FAM needs.
# Idempotent: when every package is already present it changes nothing and costs no network.
set -euo pipefail

packages=(
  build-essential cmake ninja-build pkg-config git clang-format
  libeigen3-dev libgtest-dev libbenchmark-dev libpng-dev zlib1g-dev libzstd-dev gzip
  paraview paraview-dev python3-paraview python3-numpy python3-matplotlib
  xvfb xauth mesa-utils openmpi-bin libopenmpi-dev
  libzfp-dev libfpzip-dev
  # clang with libFuzzer and its sanitizer runtimes (scripts/fuzz.sh); gcc's ASan/UBSan/TSan
  # runtimes (scripts/sanitize.sh) come with build-essential
  clang-14 libclang-rt-14-dev libclang-common-14-dev
  # -dev packages ParaView's CMake config needs but paraview-dev does not declare
  libqt5opengl5-dev qtbase5-dev qttools5-dev libqt5svg5-dev libutfcpp-dev libhdf5-mpi-dev libnetcdf-dev libgdal-dev
  libtiff-dev liblz4-dev libglew-dev libgl2ps-dev libtheora-dev libogg-dev libavformat-dev
  libavcodec-dev libavutil-dev libswscale-dev libdouble-conversion-dev
)

missing=()
for p in "${packages[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done

if [ ${#missing[@]} -eq 0 ]; then
  echo "install-deps: all ${#packages[@]} packages present"
  exit 0
fi

echo "install-deps: installing ${#missing[@]} missing packages: ${missing[*]}"
SUDO=""
if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
$SUDO apt-get update -q
DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -q --no-install-recommends "${missing[@]}"
