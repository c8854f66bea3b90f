#!/usr/bin/env bash
# SPDX-License-Identifier: BSD-3-Clause
# Local half of the ParaView check on the GPU machine (scripts/gpu_pv_check.sh is the other half).
# The GPU machine has CUDA but no ParaView, no Python 3.11, no X server and nothing to install
# them with, so this machine packs them, and the plugin built here with CUDA (sm_90) against
# Debian's ParaView, into gpu-pv/ (git-ignored):
#   gpu-pv/pv.tar.zst.partNN  bundle 1, one tar stream (zstd --long=27) cut into parts of
#       AFAM_PV_PART_MB MiB (default 50), each carried by its own device call (64 MiB a call, the
#       repository included); gpu-pv/PARTS lists them with their sha256. It holds, under pv/:
#       usr/bin/ Debian's pvbatch, pvpython, pvserver, OpenMPI's orterun/orted; usr/lib/ the Python
#       3.11 standard library (no tests, Tk or caches), ParaView's Python packages (paraview,
#       vtkmodules) and numpy, OpenMPI's and PMIx's components (usr/share, usr/etc: their help and
#       configuration); x/ Xvfb, xkbcomp, the xkb data, Mesa's swrast DRI driver; lib/ the `ldd`
#       closure of all of it (Mesa's libGLX_mesa too) but glibc, libstdc++ and libgcc_s, flat under
#       the names the loader asks for. Packed again only when those Debian packages change (or
#       AFAM_PV_REPACK=1): about 20 minutes of zstd on 2 busy cores.
#   gpu-pv/afam.tar.zst  bundle 2: AdaptiveFAM.so, `afam` and BenchAFAMRenderLoop built here with
#       CUDA (build dir BUILD_DIR, default build-gpu-pv), and the libraries they need that bundle 1
#       lacks; carried with the call that runs the check.
#   gpu-pv/zstd/  Debian's zstd and its libraries, as they are (the GPU machine has none).
#   gpu-pv/src/   this checkout's scripts, Python tests, pvbatch scripts and baselines, which the
#       device calls run (the device tool sends the session's main checkout, not a worktree).
#   scripts/gpu_pv_pack.sh [BUILD_DIR]
#   gpu-pv/afam_nocuda.tar.zst  with AFAM_PV_NOCUDA_BUILD (a ParaView build with AFAM_ENABLE_CUDA=OFF):
#       its plugin, which the check loads on the GPU machine too.
# AFAM_PV_PACK: the output folder (default gpu-pv/ of this checkout); AFAM_PV_BUNDLES ("pv afam",
# the default, or one of them); AFAM_JOBS (2); AFAM_PACK_ZSTD_LEVEL (bundle 1, default 15); nvcc
# from /usr/local/cuda/bin unless CUDACXX names another.
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
build="${1:-$root/build-gpu-pv}"
pack="${AFAM_PV_PACK:-$root/gpu-pv}"
export CUDACXX="${CUDACXX:-/usr/local/cuda/bin/nvcc}"
level="${AFAM_PACK_ZSTD_LEVEL:-15}"
part_mb="${AFAM_PV_PART_MB:-50}"
multiarch=/usr/lib/x86_64-linux-gnu
dist=/usr/lib/python3/dist-packages
die() { echo "gpu_pv_pack.sh: $*" >&2; exit 1; }


for f in /usr/bin/pvbatch3.11 /usr/bin/pvpython3.11 /usr/bin/pvserver /usr/bin/orterun /usr/bin/orted \
  "$(command -v Xvfb)" "$(command -v xkbcomp)" "$(command -v zstd)" "$multiarch/dri/swrast_dri.so"; do
  [ -e "$f" ] || die "$f is missing here (scripts/install-deps.sh installs ParaView, Xvfb, Mesa, zstd)"
done

# The shared libraries FILES load (ldd), but the C and C++ runtimes the GPU machine's newer
# Ubuntu provides, as "soname<TAB>path" lines.
closure() {
  ldd "$@" 2>/dev/null | awk '$2 == "=>" && $3 ~ /^\// { print $1 "\t" $3 }' |
    grep -vE '^(libc|libm|libpthread|libdl|librt|libresolv|libutil|libstdc\+\+|libgcc_s)\.so' |
    sort -u
}
copy_closure() {  # copy_closure DEST SKIP FILES...: the closure, flat, under its sonames, but those in SKIP
  local dest="$1" skip="$2"; shift 2
  mkdir -p "$dest"
  closure "$@" | while IFS=$'\t' read -r soname path; do
    [ -e "$dest/$soname" ] || [ -e "$skip/$soname" ] || cp -L "$path" "$dest/$soname"
  done
  if ldd "$@" 2>/dev/null | grep -q "not found"; then
    ldd "$@" 2>/dev/null | grep "not found" | sort -u >&2; die "unresolved libraries (above)"
  fi
}
elf_files() {  # the ELF files under the folders given
  find "$@" -type f \( -name '*.so*' -o -perm -u+x \) -exec sh -c 'head -c 4 "$1" | grep -q ELF && echo "$1"' _ {} \;
}
stage="$(mktemp -d)"
trap 'rm -rf "$stage"' EXIT
mkdir -p "$pack"

# ------------------------------------------------ Bundle 1 (parts): ParaView, Python, MPI, X.
# Packed again only when ParaView's package changed, or with AFAM_PV_REPACK=1.
stamp="$(dpkg-query -W -f '${Package} ${Version}\n' paraview python3-paraview libpython3.11 python3-numpy xvfb libgl1-mesa-dri 2>/dev/null | tr '\n' ' ') zstd -$level parts ${part_mb}M"
if [[ " ${AFAM_PV_BUNDLES:-pv afam} " != *" pv "* ]]; then
  [ -f "$pack/PARTS" ] || die "no bundle 1 in $pack yet: leave AFAM_PV_BUNDLES unset"
elif [ "${AFAM_PV_REPACK:-0}" = 1 ] || [ ! -f "$pack/PARTS" ] || [ "$(sed -n 's/^# stamp: //p' "$pack/PARTS")" != "$stamp" ]; then
  rm -f "$pack"/pv.tar.zst.part* "$pack/PARTS"
  s="$stage/pv"
  mkdir -p "$s/usr/bin" "$s/usr/lib/python3/dist-packages" "$s/usr/lib/x86_64-linux-gnu" "$s/usr/share" \
    "$s/usr/etc" "$s/x/bin" "$s/x/dri" "$s/x/xkb"
  cp -L /usr/bin/pvbatch3.11 /usr/bin/pvpython3.11 /usr/bin/pvserver /usr/bin/orterun /usr/bin/orted "$s/usr/bin/"
  ln -s pvbatch3.11 "$s/usr/bin/pvbatch"
  ln -s pvpython3.11 "$s/usr/bin/pvpython"
  ln -s orterun "$s/usr/bin/mpirun"
  tar -C /usr/lib -cf - --exclude=__pycache__ --exclude=python3.11/test --exclude=python3.11/idlelib \
    --exclude=python3.11/tkinter --exclude=python3.11/turtledemo --exclude=python3.11/lib2to3 \
    --exclude=python3.11/ensurepip --exclude=python3.11/config-3.11-x86_64-linux-gnu python3.11 |
    tar -C "$s/usr/lib" -xf -
  tar -C "$dist" -cf - --exclude=__pycache__ --exclude=tests --exclude=paraview/web --exclude=paraview/demos \
    paraview vtkmodules vtk.py numpy | tar -C "$s/usr/lib/python3/dist-packages" -xf -
  # OpenMPI and PMIx: components, help texts, configuration (relocated with OPAL_PREFIX there).
  cp -r "$multiarch/openmpi" "$multiarch/pmix2" "$s/usr/lib/x86_64-linux-gnu/"
  rm -rf "$s/usr/lib/x86_64-linux-gnu/openmpi/include" "$s/usr/lib/x86_64-linux-gnu/pmix2/include"
  find "$s/usr/lib/x86_64-linux-gnu" -name '*.a' -delete
  cp -r /usr/share/openmpi "$s/usr/share/"
  if [ -d /usr/share/pmix ]; then cp -r /usr/share/pmix "$s/usr/share/"; fi
  cp -r /etc/openmpi "$s/usr/etc/"
  # Xvfb with GLX (Mesa's software driver serves Xvfb; the programs' own context is NVIDIA's,
  # chosen with __GLX_VENDOR_LIBRARY_NAME on the GPU machine, or Mesa's llvmpipe).
  cp -L "$(command -v Xvfb)" "$(command -v xkbcomp)" "$s/x/bin/"
  cp -L "$multiarch/dri/swrast_dri.so" "$s/x/dri/"
  cp -L "$multiarch/libGLX_mesa.so.0" "$s/x/"
  cp -r /usr/share/X11/xkb/. "$s/x/xkb/"
  mapfile -t elfs < <(elf_files "$s/usr/bin" "$s/usr/lib" "$s/x/bin" "$s/x/dri" "$s/x/libGLX_mesa.so.0")
  echo "gpu_pv_pack.sh: the closure of ${#elfs[@]} programs and modules"
  copy_closure "$s/lib" /nonexistent "${elfs[@]}"
  mv "$s/x/libGLX_mesa.so.0" "$s/lib/"
  echo "$stamp" >"$s/STAMP"
  t0=$(date +%s)
  tar -C "$stage" -cf - pv | zstd -q -T0 "-$level" --long=27 -c |
    split -b "${part_mb}M" -d -a 2 - "$pack/pv.tar.zst.part"
  parts=("$pack"/pv.tar.zst.part*)
  {
    echo "# parts of pv.tar.zst (zstd -$level --long=27): cat them in this order; sha256 of each"
    echo "# stamp: $stamp"
    for p in "${parts[@]}"; do echo "$(sha256sum "$p" | cut -d' ' -f1) $(basename "$p")"; done
  } >"$pack/PARTS.new"
  mv "$pack/PARTS.new" "$pack/PARTS"
  printf 'pv: %d files, %d MB unpacked, %.1f MB packed in %d parts of at most %d MiB (%d s)\n' \
    "$(find "$s" -type f | wc -l)" "$(( $(du -sb "$s" | cut -f1) / 1000000 ))" \
    "$(cat "${parts[@]}" | wc -c | awk '{ print $1 / 1e6 }')" "${#parts[@]}" "$part_mb" \
    "$(( $(date +%s) - t0 ))" | tee "$pack/SIZES"
  # the library names bundle 1 holds, so that bundle 2 carries only the others
  ls "$s/lib" >"$pack/PV_LIBS"
  rm -rf "$s"
else
  echo "gpu_pv_pack.sh: bundle 1 is current ($(grep -c ' pv.tar.zst.part' "$pack/PARTS") parts); AFAM_PV_REPACK=1 packs it again"
fi

# ------------------------------------------------ Bundle 2: the plugin and programs built here.
if [[ " ${AFAM_PV_BUNDLES:-pv afam} " != *" afam "* ]]; then exit 0; fi
if [ ! -f "$build/CMakeCache.txt" ]; then
  cmake -S "$root" -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=Release -DAFAM_ENABLE_PARAVIEW=ON \
    -DAFAM_ENABLE_CUDA=ON -DCMAKE_CUDA_ARCHITECTURES=90 -DCMAKE_CUDA_COMPILER="$CUDACXX"
fi
cmake --build "$build" -j "${AFAM_JOBS:-2}" --target AdaptiveFAM afam BenchAFAMRenderLoop
plugin="$(find "$build" -name AdaptiveFAM.so -path '*plugins*' | head -1)"
[ -n "$plugin" ] || die "no AdaptiveFAM.so under $build"
for p in Apps/afam Testing/VTK/BenchAFAMRenderLoop; do
  [ -x "$build/$p" ] || die "$build/$p was not built"
done
grep -q "AFAM_HAVE_CUDA" "$build/build.ninja" || die "$build is not a CUDA build (AFAM_HAVE_CUDA missing)"
a="$stage/afam"
mkdir -p "$a/afam" "$a/lib"
cp -L "$plugin" "$build/Apps/afam" "$build/Testing/VTK/BenchAFAMRenderLoop" "$a/afam/"
# the plugin's own modules, when built as shared libraries (lib/ of the build)
find "$build/lib" -name '*.so*' ! -name AdaptiveFAM.so 2>/dev/null | while read -r f; do cp -L "$f" "$a/afam/"; done
skip="$stage/pvlibs"
mkdir -p "$skip"
while read -r f; do : >"$skip/$f"; done <"$pack/PV_LIBS"
for f in "$a/afam/"*; do : >"$skip/$(basename "$f")"; done
LD_LIBRARY_PATH="$a/afam${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}" copy_closure "$a/lib" "$skip" "$a/afam/"*
{ git -C "$root" rev-parse --short HEAD
  if git -C "$root" status --porcelain --untracked-files=no | grep -q .; then echo "(with uncommitted changes)"; fi
} | paste -sd' ' >"$a/COMMIT"
tar -C "$stage" -cf - afam | zstd -q -T0 -19 --long=27 -o "$pack/afam.tar.zst" -f
printf 'afam: %d files, %d MB unpacked, %.1f MB packed (programs at %s)\n' "$(find "$a" -type f | wc -l)" \
  "$(( $(du -sb "$a" | cut -f1) / 1000000 ))" "$(stat -c %s "$pack/afam.tar.zst" | awk '{ print $1 / 1e6 }')" \
  "$(cat "$a/COMMIT")" | tee -a "$pack/SIZES"

# ------------------------------------------------ Bundle 3 (optional): the plugin built without CUDA.
# AFAM_PV_NOCUDA_BUILD names a ParaView build of this checkout with AFAM_ENABLE_CUDA=OFF: its plugin
# goes to gpu-pv/afam_nocuda.tar.zst, which the check loads on the GPU machine (CPU frames, one
# message).
rm -f "$pack/afam_nocuda.tar.zst"
if [ -n "${AFAM_PV_NOCUDA_BUILD:-}" ]; then
  nb="$AFAM_PV_NOCUDA_BUILD"
  [ -f "$nb/CMakeCache.txt" ] || die "AFAM_PV_NOCUDA_BUILD=$nb is not a build folder"
  grep -q "^AFAM_ENABLE_CUDA:BOOL=OFF" "$nb/CMakeCache.txt" || die "$nb is built with CUDA"
  cmake --build "$nb" -j "${AFAM_JOBS:-2}" --target AdaptiveFAM
  n="$stage/afam_nocuda"
  mkdir -p "$n"
  cp -L "$(find "$nb" -name AdaptiveFAM.so -path '*plugins*' | head -1)" "$n/"
  tar -C "$stage" -cf - afam_nocuda | zstd -q -T0 -19 --long=27 -o "$pack/afam_nocuda.tar.zst" -f
  echo "afam_nocuda: the plugin without CUDA, $(stat -c %s "$pack/afam_nocuda.tar.zst" | awk '{ print $1 / 1e6 }') MB packed" | tee -a "$pack/SIZES"
fi

# ------------------------------------------------ zstd, and what the device calls run.
rm -rf "$pack/zstd" "$pack/src"
mkdir -p "$pack/zstd" "$pack/src"
cp -L "$(command -v zstd)" "$pack/zstd/zstd"
copy_closure "$pack/zstd" /nonexistent "$pack/zstd/zstd"
git -C "$root" ls-files scripts Testing/Python Testing/Data/Baseline Testing/Data/format Testing/Data/volumes \
  Apps/pvbatch |
  tar -C "$root" -cf - -T - | tar -C "$pack/src" -xf -
echo "src: $(du -sb "$pack/src" | cut -f1) bytes of scripts, tests and baselines" | tee -a "$pack/SIZES"
echo "packed into $pack; repository (tracked files) $(git -C "$root" ls-files -z | du -cb --files0-from=- | tail -1 | cut -f1) bytes"
echo "device calls: gpu-pv/src/scripts/gpu_pv_check.sh part (one part each), then ... run (see its header)"
