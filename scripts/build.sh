#!/usr/bin/env bash
# Configures and builds everything this machine can build (ParaView plugin and CUDA kernels are
# switched on automatically when ParaView / nvcc are present). Usage: scripts/build.sh [BUILD_DIR]
# Warnings are always on; AFAM_WERROR=ON turns them into errors (developers and scripts/gpu_check.sh).
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
build="${1:-$root/build}"
jobs="${AFAM_JOBS:-$(nproc)}"
generator=()
if command -v ninja >/dev/null 2>&1; then generator=(-G Ninja); fi
if [ ! -f "$build/CMakeCache.txt" ]; then
  cmake -S "$root" -B "$build" "${generator[@]}" -DCMAKE_BUILD_TYPE=Release -DAFAM_WARNINGS_AS_ERRORS="${AFAM_WERROR:-OFF}"
fi
cmake --build "$build" -j "$jobs"
