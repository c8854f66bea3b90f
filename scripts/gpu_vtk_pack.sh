#!/usr/bin/env bash
# SPDX-License-Identifier: BSD-3-Clause
# Local half of the VTK check on the GPU machine (scripts/gpu_vtk_check.sh is the other half): the
# GPU machine has CUDA but no VTK, no X server and nothing to install them with, so this machine
# builds the programs there with CUDA against ParaView's VTK used as a plain VTK (no ParaView
# library linked), and packs them with everything they load into gpu-vtk/ (git-ignored):
#   gpu-vtk/zstd/          Debian's zstd and its libraries, uncompressed (the GPU machine has none)
#   gpu-vtk/bin.tar.zst    the C++ VTK image tests, BenchAFAMRenderLoop, BenchVTKRawVolume, AFAMRenderFile and the
#                          `afam` command line, with their `ldd` closure but glibc and libstdc++,
#                          flat under the names the loader asks for (unpacks to bin/ and lib/)
#   gpu-vtk/x.tar.zst      Xvfb, xkbcomp, the xkb data and Mesa's GLX library and swrast DRI
#                          driver (Xvfb's GLX needs them), with their closure (bin/, lib/, dri/, xkb/)
# Each bundle travels in its own device call (64 MiB carried per call, the repository included);
# zstd -19 with a 128 MiB window (--long=27) finds the nine programs' common CUDA and Core code.
#   scripts/gpu_vtk_pack.sh [BUILD_DIR]          (default build-gpu-vtk)
# AFAM_VTK_DIR: the folder of vtk-config.cmake (default Debian ParaView's own VTK); AFAM_JOBS
# (default 2); CMAKE_CUDA_ARCHITECTURES 90 (H100/H200); nvcc from /usr/local/cuda/bin unless
# CUDACXX names another.
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
build="${1:-$root/build-gpu-vtk}"
pack="$root/gpu-vtk"
vtk_dir="${AFAM_VTK_DIR:-/usr/lib/x86_64-linux-gnu/cmake/paraview-5.11/vtk}"
export CUDACXX="${CUDACXX:-/usr/local/cuda/bin/nvcc}"
level="${AFAM_PACK_ZSTD_LEVEL:-19}"
programs=(Testing/VTK/TestAFAMVolumeMapper Testing/VTK/TestAFAMDepthCompositing
  Testing/VTK/TestAFAMBlendModes Testing/VTK/TestAFAMFrameSettings Testing/VTK/TestAFAMMapperFileName
  Testing/VTK/BenchAFAMRenderLoop Testing/VTK/BenchVTKRawVolume Examples/AFAMRenderFile Apps/afam)

# --- Build (only what the GPU machine runs).
launcher=()
if command -v ccache >/dev/null 2>&1; then
  launcher=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache -DCMAKE_C_COMPILER_LAUNCHER=ccache
    -DCMAKE_CUDA_COMPILER_LAUNCHER=ccache)
fi
if [ ! -f "$build/CMakeCache.txt" ]; then
  cmake -S "$root" -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=Release "${launcher[@]}" \
    -DAFAM_ENABLE_PARAVIEW=OFF -DAFAM_ENABLE_VTK=ON -DAFAM_ENABLE_CUDA=ON \
    -DCMAKE_CUDA_ARCHITECTURES=90 -DVTK_DIR="$vtk_dir"
fi
cmake --build "$build" -j "${AFAM_JOBS:-2}" --target afam_vtk_tests AFAMRenderFile afam
for p in "${programs[@]}"; do
  [ -x "$build/$p" ] || { echo "gpu_vtk_pack.sh: $build/$p was not built" >&2; exit 1; }
done
if ! grep -q "AFAM_HAVE_CUDA" "$build/build.ninja"; then
  echo "gpu_vtk_pack.sh: $build is not a CUDA build (AFAM_HAVE_CUDA missing)" >&2
  exit 1
fi

# The shared libraries FILES load (ldd), but the C and C++ runtimes the GPU machine's newer
# Ubuntu provides, as "soname<TAB>path" lines.
closure() {
  ldd "$@" 2>/dev/null | awk '$2 == "=>" && $3 ~ /^\// { print $1 "\t" $3 }' |
    grep -vE '^(libc|libm|libpthread|libdl|librt|libresolv|libutil|libstdc\+\+|libgcc_s)\.so' |
    sort -u
}
copy_closure() {  # copy_closure DEST FILES...: the closure, flat, under its sonames
  local dest="$1"; shift
  mkdir -p "$dest"
  closure "$@" | while IFS=$'\t' read -r soname path; do cp -L "$path" "$dest/$soname"; done
  if ldd "$@" 2>/dev/null | grep -q "not found"; then
    echo "gpu_vtk_pack.sh: unresolved libraries:" >&2; ldd "$@" | grep "not found" >&2; exit 1
  fi
}
bundle() {  # bundle NAME STAGE: tar | zstd into gpu-vtk/NAME.tar.zst
  tar -C "$2" -cf - . | zstd -q -T0 "-$level" --long=27 -o "$pack/$1.tar.zst" -f
  printf '%-12s %5d files, %5d MB unpacked, %5.1f MB packed\n' "$1" \
    "$(find "$2" -type f | wc -l)" "$(( $(du -sb "$2" | cut -f1) / 1000000 ))" \
    "$(echo "$(stat -c %s "$pack/$1.tar.zst") / 1000000" | bc -l)" | tee -a "$pack/SIZES"
}

stage="$(mktemp -d)"
trap 'rm -rf "$stage"' EXIT
rm -rf "$pack"
mkdir -p "$pack/zstd" "$stage/bin/bin" "$stage/x/bin" "$stage/x/dri" "$stage/x/xkb"
: >"$pack/SIZES"

# --- zstd, uncompressed: what unpacks the rest.
cp -L "$(command -v zstd)" "$pack/zstd/zstd"
copy_closure "$pack/zstd" "$pack/zstd/zstd"

# --- Bundle 1: the programs.
for p in "${programs[@]}"; do cp -L "$build/$p" "$stage/bin/bin/"; done
copy_closure "$stage/bin/lib" "$stage/bin/bin/"*
git -C "$root" rev-parse --short HEAD >"$stage/bin/COMMIT"
bundle bin "$stage/bin"

# --- Bundle 2: an X server with GLX (Mesa's software driver serves Xvfb; the programs' own
# context can be NVIDIA's, chosen with __GLX_VENDOR_LIBRARY_NAME on the GPU machine).
multiarch=/usr/lib/x86_64-linux-gnu
cp -L "$(command -v Xvfb)" "$(command -v xkbcomp)" "$stage/x/bin/"
cp -L "$multiarch/dri/swrast_dri.so" "$stage/x/dri/"
cp -L "$multiarch/libGLX_mesa.so.0" "$stage/x/"
copy_closure "$stage/x/lib" "$stage/x/bin/"* "$stage/x/dri/swrast_dri.so" "$stage/x/libGLX_mesa.so.0"
mv "$stage/x/libGLX_mesa.so.0" "$stage/x/lib/"
cp -r /usr/share/X11/xkb/. "$stage/x/xkb/"
bundle x "$stage/x"

echo "zstd         $(du -sb "$pack/zstd" | cut -f1) bytes (carried as is)" | tee -a "$pack/SIZES"
echo "packed into $pack; repository (tracked files) $(git -C "$root" ls-files -z | du -cb --files0-from=- | tail -1 | cut -f1) bytes"
