#!/usr/bin/env bash
# The VTK module, the README's example and the C++ VTK image tests built against a VTK without
# ParaView, and those tests run (label `vtk`; one of them checks with ldd that no ParaView library
# is linked). Only what they need is built. scripts/test.sh calls this after the main suite.
#   scripts/plain_vtk.sh [BUILD_DIR]        (default build-vtk)
# AFAM_VTK_DIR: the folder holding vtk-config.cmake; default Debian ParaView's own VTK (Debian's
# libvtk9-dev cannot be installed beside python3-paraview), used here as a plain VTK.
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
build="${1:-$root/build-vtk}"
vtk_dir="${AFAM_VTK_DIR:-/usr/lib/x86_64-linux-gnu/cmake/paraview-5.11/vtk}"
if [ ! -f "$vtk_dir/vtk-config.cmake" ] && [ ! -f "$vtk_dir/VTKConfig.cmake" ]; then
  echo "plain_vtk.sh: no vtk-config.cmake in $vtk_dir (set AFAM_VTK_DIR)" >&2
  exit 1
fi
generator=()
if command -v ninja >/dev/null 2>&1; then generator=(-G Ninja); fi
if [ ! -f "$build/CMakeCache.txt" ]; then
  cmake -S "$root" -B "$build" "${generator[@]}" -DCMAKE_BUILD_TYPE=Release \
    -DAFAM_ENABLE_PARAVIEW=OFF -DAFAM_ENABLE_VTK=ON -DAFAM_ENABLE_CUDA=OFF -DVTK_DIR="$vtk_dir" \
    -DAFAM_WARNINGS_AS_ERRORS="${AFAM_WERROR:-OFF}"
fi
cmake --build "$build" --target afam_vtk_tests -j "${AFAM_JOBS:-$(nproc)}"
ctest --test-dir "$build" --output-on-failure --timeout 900 -L vtk -j "${AFAM_TEST_JOBS:-2}"
