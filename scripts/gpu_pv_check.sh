#!/usr/bin/env bash
# SPDX-License-Identifier: BSD-3-Clause
# ParaView itself (pvbatch, pvpython, pvserver) with the plugin's CUDA path, on the GPU machine (no
# ParaView, no Python 3.11, no X server there): runs what scripts/gpu_pv_pack.sh built and packed
# into gpu-pv/ on a Debian machine. Device calls back to back (a machine is given back 30 s after a
# call), from the repository root, each carrying gpu-pv/zstd, gpu-pv/PARTS, gpu-pv/src and one
# more thing:
#   gpu-pv/src/scripts/gpu_pv_check.sh part           carrying one gpu-pv/pv.tar.zst.partNN
#        (as many calls as there are parts; after the last, bundle 1 is checked and unpacked)
#   gpu-pv/src/scripts/gpu_pv_check.sh part run [WAIT] carrying the last part and
#        gpu-pv/afam.tar.zst (the plugin and programs)
# (`run` again, with nothing more carried, goes on waiting when WAIT seconds, default 540, were too
# few.) gpu-pv/src is this checkout's scripts, tests and baselines as packed. Parts already there
# (or unpacked) are kept, so a call that failed is simply made again. Unpacks under
# $AFAM_PV_PREFIX (default /opt/afam-pv): pv/ (ParaView, Python 3.11, numpy, OpenMPI, Xvfb, Mesa,
# their libraries) and afam/ (AdaptiveFAM.so, afam, BenchAFAMRenderLoop). `run` starts Xvfb on :98
# (AFAM_PV_DISPLAY) and, in its own process session, the check:
#   - "tests": the plugin's pvbatch / pvpython tests (Testing/Python, as ctest runs them, plus the
#     pvserver client of 1 and 2 ranks), each twice: AFAM_TEST_DEVICE=cpu, then gpu (every
#     "Adaptive-FAM Volume" display set to that device, each frame checked to have been cast there
#     and, with NVIDIA's OpenGL, drawn through CUDA-OpenGL interop: afam_test_util's hook); then
#     every image the gpu run wrote against the cpu run's image of the same name: at most 2/255
#     in every channel of every pixel ("[pv gpu-vs-cpu]" lines);
#   - "faults": the GPU asked for where CUDA is hidden (CUDA_VISIBLE_DEVICES=""), and (when
#     gpu-pv/afam_nocuda.tar.zst was carried) by the plugin built without CUDA: one message each,
#     CPU frames equal to the CPU's;
#   - "bench": Marschner-Lobb N^3 (AFAM_PV_N, default 1024) encoded at the paper's settings, the
#     camera path user_1 (carried in gpu-data/trajectories, else generated) replayed through
#     paraview.simple in pvbatch (Apps/pvbatch/afam_pv_loop.py) at AFAM_PV_SIZES ("512 1024"),
#     cold and warm, beside BenchAFAMRenderLoop (the VTK window) and `afam replay --device gpu`
#     on the same file, views (AFAM_PV_FRAMES, default 200), cache (AFAM_PV_CACHE_MB, 220) and
#     GPU pool, and ParaView's own "Volume" representation on the raw samples (frame time, time to
#     the first image; AFAM_PV_RAW=0 leaves it out); then through pvserver of 1 and 2 ranks with a
#     pvpython client on the loopback address (AFAM_PV_SERVER_BENCH=0 leaves it out).
# AFAM_PV_PARTS picks among "tests faults bench" (default all); AFAM_PV_TESTS names the tests to
# run (default all: Pipeline ShowColoured Placement State Scenes DefaultLod EditKeepsCache Damage
# DecodeDamaged FileChanged DecodeLevel TimeSteps MatchesVolume ColourArray BadFiles Panel FrameBudget
# ClientServer1 ClientServer2). OpenGL is NVIDIA's
# own on the GPU (AFAM_PV_GLX=nvidia, default) or Mesa's llvmpipe (AFAM_PV_GLX=mesa: no interop;
# the GPU frames then go through the host; give it its own AFAM_PV_WORK). Logs, CSVs and images go
# to $OUT/<work folder's name>.tar.gz when OUT is set; a table is printed last.
set -uo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
mode="${1:-}"
prefix="${AFAM_PV_PREFIX:-/opt/afam-pv}"
display="${AFAM_PV_DISPLAY:-98}"
work="${AFAM_PV_WORK:-/tmp/afam_gpu_pv}"
glx="${AFAM_PV_GLX:-nvidia}"
if [ -n "${AFAM_PV_PACK:-}" ]; then pack="$AFAM_PV_PACK"
elif [ -f "$root/../PARTS" ]; then pack="$(cd "$root/.." && pwd)"  # run from gpu-pv/src
else pack="$root/gpu-pv"; fi
repo="$(cd "$pack/.." && pwd)"  # the checkout the device call runs in (gpu-data/ there)
unzstd() { LD_LIBRARY_PATH="$pack/zstd" "$pack/zstd/zstd" -q -d --long=27 -c "$@"; }
die() { echo "gpu_pv_check.sh: $*" >&2; exit 1; }

store_parts() {  # keep each carried part of bundle 1; unpack once all are there
  [ -f "$pack/PARTS" ] || die "gpu-pv/PARTS was not carried"
  [ -x "$pack/zstd/zstd" ] || die "gpu-pv/zstd was not carried"
  mkdir -p "$prefix/parts"
  local p
  for p in "$pack"/pv.tar.zst.part*; do
    [ ! -f "$prefix/pv/STAMP" ] || [ "$(cat "$prefix/pv/STAMP")" != "$(sed -n 's/^# stamp: //p' "$pack/PARTS")" ] || break
    [ -f "$p" ] || continue
    cp "$p" "$prefix/parts/" && echo "kept $(basename "$p") ($(stat -c %s "$p") bytes)"
  done
  local want have=0 total=0 stamp
  stamp="$(sed -n 's/^# stamp: //p' "$pack/PARTS")"
  if [ -f "$prefix/pv/STAMP" ] && [ "$(cat "$prefix/pv/STAMP")" = "$stamp" ]; then
    echo "bundle 1 already unpacked under $prefix/pv"
  else
    while read -r sum name; do
      [ "${sum:0:1}" = "#" ] && continue
      total=$((total + 1))
      if [ -f "$prefix/parts/$name" ] && [ "$(sha256sum "$prefix/parts/$name" | cut -d' ' -f1)" = "$sum" ]; then
        have=$((have + 1))
      else
        want="${want:-} $name"
      fi
    done <"$pack/PARTS"
    if [ "$have" -lt "$total" ]; then
      echo "bundle 1: $have of $total parts here; still to carry:${want}"
    else
      local t0=$(date +%s)
      rm -rf "$prefix/pv"
      mkdir -p "$prefix"
      cat $(grep -v '^#' "$pack/PARTS" | awk -v d="$prefix/parts/" '{ print d $2 }') | unzstd | tar -x -C "$prefix" ||
        die "unpacking bundle 1 failed"
      rm -rf "$prefix/parts"
      echo "unpacked bundle 1 into $prefix/pv: $(find "$prefix/pv" -type f | wc -l) files, $(du -sm "$prefix/pv" | cut -f1) MB in $(( $(date +%s) - t0 )) s"
    fi
  fi
  if [ -f "$pack/afam_nocuda.tar.zst" ]; then
    rm -rf "$prefix/afam_nocuda"
    unzstd "$pack/afam_nocuda.tar.zst" | tar -x -C "$prefix" || die "unpacking the plugin without CUDA failed"
    echo "unpacked the plugin built without CUDA into $prefix/afam_nocuda"
  fi
  if [ -f "$pack/afam.tar.zst" ]; then
    rm -rf "$prefix/afam"
    unzstd "$pack/afam.tar.zst" | tar -x -C "$prefix" || die "unpacking the plugin failed"
    echo "unpacked the plugin and programs (built at $(cat "$prefix/afam/COMMIT")) into $prefix/afam"
  fi
  # ParaView finds its Python packages from its libraries' folder up (lib/python3/dist-packages
  # beside lib/ of the nearest ancestor that has one): this one, not a system's.
  if [ -d "$prefix/pv" ]; then ln -sfn ../usr/lib/python3 "$prefix/pv/lib/python3"; fi
  if [ -d "$prefix/pv" ] && [ -d "$prefix/afam" ]; then
    local missing
    missing=$(LD_LIBRARY_PATH="$prefix/afam/afam:$prefix/afam/lib:$prefix/pv/lib" ldd "$prefix/pv/usr/bin/"pv* \
      "$prefix/afam/afam/"* 2>/dev/null | grep "not found" | sort -u)
    [ -z "$missing" ] || { echo "$missing"; die "libraries missing on this machine"; }
    echo "every library of pvbatch, pvpython, pvserver and the plugin resolves"
  fi
}

pv_env() {
  local pv="$prefix/pv"
  export LD_LIBRARY_PATH="$prefix/afam/afam:$prefix/afam/lib:$pv/lib"
  [ "$glx" = nvidia ] && export LD_LIBRARY_PATH="$LD_LIBRARY_PATH:/usr/local/nvidia/lib64"
  export __GLX_VENDOR_LIBRARY_NAME="$glx"
  export LIBGL_DRIVERS_PATH="$pv/x/dri"
  export DISPLAY=":$display"
  export PYTHONHOME="$pv/usr"
  export PYTHONPATH="$pv/usr/lib/python3/dist-packages"
  export PYTHONNOUSERSITE=1 PYTHONDONTWRITEBYTECODE=1 PYTHONUNBUFFERED=1
  # OpenMPI and PMIx where they were unpacked (their configured paths are under /usr)
  mpi_vars=(OPAL_PREFIX="$pv/usr" PMIX_PREFIX="$pv/usr/lib/x86_64-linux-gnu/pmix2"
    OMPI_MCA_mca_base_component_path="$pv/usr/lib/x86_64-linux-gnu/openmpi/lib/openmpi3"
    PMIX_MCA_mca_base_component_path="$pv/usr/lib/x86_64-linux-gnu/pmix2/lib/pmix"
    OMPI_MCA_plm_rsh_agent=false OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1)
  export "${mpi_vars[@]}"
  # the machine's own hwloc plugins (OpenCL, LLVM) and PMIx components are no business of ours
  export HWLOC_PLUGINS_PATH="$work/none" PMIX_MCA_mca_base_component_show_load_errors=0
  export PATH="$pv/usr/bin:$prefix/afam/afam:$PATH"
  export XDG_RUNTIME_DIR="$work/xdg"
  mkdir -p "$XDG_RUNTIME_DIR" && chmod 700 "$XDG_RUNTIME_DIR"
}

case "$mode" in
part)
  echo "GPU: $(nvidia-smi --query-gpu=name,driver_version,memory.total --format=csv,noheader 2>/dev/null | head -1)"
  store_parts
  [ "${2:-}" = run ] || exit 0
  shift 2
  exec "$0" run "$@"
  ;;
run)
  wait_s="${2:-540}"
  [ -x "$prefix/pv/usr/bin/pvbatch3.11" ] ||
    die "no ParaView under $prefix/pv: carry every part first (a machine given back between the calls loses them)"
  [ -f "$prefix/afam/afam/AdaptiveFAM.so" ] || die "no plugin under $prefix/afam: carry gpu-pv/afam.tar.zst"
  mkdir -p "$work"
  carried="$repo/gpu-data/trajectories"  # recorded paths, when carried with this call
  if [ -d "$carried" ] && [ ! -d "$prefix/trajectories" ]; then cp -r "$carried" "$prefix/trajectories"; fi
  if [ ! -S "/tmp/.X11-unix/X$display" ]; then
    [ -x /usr/bin/xkbcomp ] || cp "$prefix/pv/x/bin/xkbcomp" /usr/bin/xkbcomp  # where Xvfb looks
    LD_LIBRARY_PATH="$prefix/pv/lib" LIBGL_DRIVERS_PATH="$prefix/pv/x/dri" setsid "$prefix/pv/x/bin/Xvfb" ":$display" \
      -screen 0 1280x1280x24 -noreset -xkbdir "$prefix/pv/x/xkb" </dev/null >"$work/xvfb.log" 2>&1 &
    for _ in $(seq 50); do [ -S "/tmp/.X11-unix/X$display" ] && break; sleep 0.2; done
    [ -S "/tmp/.X11-unix/X$display" ] || { tail "$work/xvfb.log"; die "Xvfb did not start"; }
  fi
  if [ ! -f "$work/started" ]; then
    date +%s >"$work/started"
    setsid bash -c "'$0' work >'$work/run.log' 2>&1; echo \$? >'$work/rc'" </dev/null >/dev/null 2>&1 &
  fi
  t0=$(date +%s); shown=0
  while [ ! -f "$work/rc" ] && [ $(( $(date +%s) - t0 )) -lt "$wait_s" ]; do
    sleep 5
    n=$(wc -l <"$work/run.log" 2>/dev/null || echo 0)
    if [ "$n" -gt "$shown" ]; then sed -n "$((shown + 1)),${n}p" "$work/run.log"; shown=$n; fi
  done
  n=$(wc -l <"$work/run.log" 2>/dev/null || echo 0)
  [ "$n" -le "$shown" ] || sed -n "$((shown + 1)),${n}p" "$work/run.log"
  if [ -n "${OUT:-}" ]; then
    tar -C "$work" -czf "$OUT/$(basename "$work").tar.gz" --exclude='*.afam' --exclude='*.raw' --exclude=xdg . 2>/dev/null
  fi
  if [ ! -f "$work/rc" ]; then
    echo "still running after $(( $(date +%s) - $(cat "$work/started") )) s: call 'gpu-pv/src/scripts/gpu_pv_check.sh run' again"
    exit 0
  fi
  exit "$(cat "$work/rc")"
  ;;
work)
  ;;  # below
*)
  sed -n '2,40p' "$0" | sed 's/^# \{0,1\}//'
  exit 2
  ;;
esac

# ---------------------------------------------------------------- the check itself (mode work)
pv_env
pv="$prefix/pv/usr/bin"
plugin="$prefix/afam/afam/AdaptiveFAM.so"
afam="$prefix/afam/afam/afam"
tests="$root/Testing/Python"
summary="$work/summary.txt"
: >"$summary"
status() { printf '%-52s %s\n' "$1" "$2" | tee -a "$summary"; }
failed=0
part() { [[ " ${AFAM_PV_PARTS:-tests faults bench} " == *" $1 "* ]]; }
echo "GPU: $(nvidia-smi --query-gpu=name,driver_version --format=csv,noheader 2>/dev/null | head -1); GLX vendor $glx; plugin built at $(cat "$prefix/afam/COMMIT")"
# pvpython from the bundle alone: its Python, packages and libraries (what else it maps is listed)
"$pv/pvpython3.11" --force-offscreen-rendering -c "
import sys, numpy, paraview, paraview.simple
print('pvpython: Python', sys.version.split()[0], 'at', sys.prefix, '; numpy', numpy.__version__, '; paraview', paraview.__file__)
paraview.simple.LoadPlugin('$plugin', remote=False, ns=globals())
maps = set(l.split()[-1] for l in open('/proc/self/maps') if '.so' in l.split()[-1])
print('libraries mapped from outside $prefix:', ' '.join(sorted(m for m in maps if not m.startswith('$prefix'))))
if not paraview.__file__.startswith('$prefix') or not numpy.__file__.startswith('$prefix'):
    sys.exit('ParaView or numpy come from outside $prefix')
" || { echo "pvpython does not start from the bundle"; exit 1; }
# pvserver of one rank without mpirun: no MPI (ParaView's --no-mpi); two ranks: the carried mpirun.
cat >"$work/pvserver1" <<EOF
#!/bin/sh
exec "$pv/pvserver" --no-mpi "\$@"
EOF
# mpirun with OpenMPI's relocation (afam_server.py starts it without OMPI_/PMIX_/OPAL_ variables)
{ echo "#!/bin/sh"; printf 'export'; printf " '%s'" "${mpi_vars[@]}"; echo
  echo "exec \"$pv/mpirun\" \"\$@\""; } >"$work/mpirun"
chmod +x "$work/pvserver1" "$work/mpirun"

# --- The plugin's ParaView tests, on the CPU and on the GPU, then GPU image = CPU image.
if part tests; then
  # name runner script [VAR=value ...]; runner: pvbatch (one process, no MPI) or pvpython
  # (--force-offscreen-rendering), as Testing/Python/CMakeLists.txt runs them
  list=(
    "Pipeline pvbatch TestAFAMPipeline.py"
    "ShowColoured pvpython TestAFAMShowColoured.py"
    "Placement pvbatch TestAFAMPlacement.py"
    "State pvbatch TestAFAMState.py"
    "Scenes pvbatch TestAFAMScenes.py"
    "DefaultLod pvbatch TestAFAMDefaultLod.py"
    "EditKeepsCache pvbatch TestAFAMEditKeepsCache.py"
    "Damage pvbatch TestAFAMDamage.py"
    "DecodeDamaged pvbatch TestAFAMDecodeDamaged.py"
    "FileChanged pvbatch TestAFAMFileChanged.py"
    "DecodeLevel pvbatch TestAFAMDecodeLevel.py"
    "TimeSteps pvbatch TestAFAMTimeSteps.py"
    "MatchesVolume pvpython TestAFAMMatchesVolume.py"
    "ColourArray pvpython TestAFAMColourArray.py"
    "BadFiles pvpython TestAFAMBadFiles.py"
    "Panel pvpython TestAFAMPanel.py"
    "FrameBudget pvpython TestAFAMFrameBudget.py"
    "ClientServer1 pvpython TestAFAMClientServer.py AFAM_SERVER_RANKS=1 AFAM_PVSERVER=$work/pvserver1"
    "ClientServer2 pvpython TestAFAMClientServer.py AFAM_SERVER_RANKS=2 AFAM_PVSERVER=$pv/pvserver AFAM_MPIRUN=$work/mpirun"
  )
  interop=0; [ "$glx" = nvidia ] && interop=1
  for device in cpu gpu; do
    for entry in "${list[@]}"; do
      read -r name runner script vars <<<"$entry"
      [ -z "${AFAM_PV_TESTS:-}" ] || [[ " $AFAM_PV_TESTS " == *" $name "* ]] || continue
      [ -f "$tests/$script" ] || { status "$name ($device)" "SKIPPED: $script not packed"; continue; }
      out="$work/tests/$device/$name"
      rm -rf "$out"; mkdir -p "$out"
      cmd=("$pv/pvbatch3.11" --no-mpi "$tests/$script")
      [ "$runner" = pvpython ] && cmd=("$pv/pvpython3.11" --force-offscreen-rendering "$tests/$script")
      t0=$(date +%s%N)
      # shellcheck disable=SC2086
      env AFAM_TEST_DEVICE=$device AFAM_TEST_INTEROP=$interop AFAM_PLUGIN="$plugin" AFAM_EXE="$afam" \
        AFAM_BASELINE="$root/Testing/Data/Baseline" AFAM_TEST_OUT="$out" AFAM_TEST_SCRIPTS="$tests" \
        $vars timeout 300 "${cmd[@]}" >"$out.log" 2>&1
      rc=$?
      secs=$(awk -v a="$t0" -v b="$(date +%s%N)" 'BEGIN { printf "%.1f", (b - a) / 1e9 }')
      # ctest's rule: a traceback or the failure marker fails a test whose exit code is 0
      if [ $rc -eq 0 ] && grep -qE "Traceback \(most recent call last\)|AFAM-TEST-FAIL" "$out.log"; then rc=99; fi
      local_frames="$(grep "^\[pv frame\] .*: device" "$out.log" | grep -v "(pvserver")"
      frames=$(grep -c . <<<"$local_frames")
      gpu=$(grep -c "cast on the GPU 1" <<<"$local_frames")
      interop_n=$(grep -c "through interop 1" <<<"$local_frames")
      built=$(grep -c "renderer built in this frame" <<<"$local_frames")
      server="$(grep "^\[pv frame\] .*(pvserver" "$out.log")"
      server_note=""
      if [ -n "$server" ]; then
        server_note="; pvserver frames checked $(grep -c . <<<"$server"): all drawing ranks on the GPU $(grep -cE "drawing blocks\): device GPU, ranks cast on the GPU [1-9]" <<<"$server"), through interop $(grep -cE "through interop [1-9]" <<<"$server")"
      fi
      hostmsg=$(grep -c "reach the window through the host" "$out.log")
      status "$name ($device)" "$([ $rc -eq 0 ] && echo passed || echo "FAILED rc=$rc") in $secs s; frames checked $frames: GPU $gpu, interop $interop_n, renderer built $built$server_note$([ "$hostmsg" = 0 ] || echo "; 'through the host' said $hostmsg time(s)")"
      [ $rc -eq 0 ] || { failed=1; grep -E "AFAM-TEST-FAIL|Error|error|Traceback" "$out.log" | head -5; }
    done
  done
  # Every image the GPU run wrote against the CPU run's of the same name.
  "$pv/pvpython3.11" "$root/scripts/gpu_pv_compare.py" "$work/tests/cpu" "$work/tests/gpu" 2 >"$work/compare.log" 2>&1
  crc=$?
  cat "$work/compare.log"
  status "GPU images against CPU images (bar 2/255)" "$([ $crc -eq 0 ] && echo passed || echo FAILED): $(tail -1 "$work/compare.log")"
  [ $crc -eq 0 ] || failed=1
fi

# --- Faults: CUDA hidden while the GPU is asked for; the plugin then draws on the CPU.
if part faults; then
  out="$work/faults"; mkdir -p "$out"
  CUDA_VISIBLE_DEVICES="" AFAM_TEST_NO_GPU=1 AFAM_PLUGIN="$plugin" AFAM_TEST_OUT="$out" \
    AFAM_TEST_SCRIPTS="$tests" AFAM_BASELINE="$root/Testing/Data/Baseline" timeout 300 \
    "$pv/pvbatch3.11" --no-mpi "$tests/TestAFAMScenes.py" >"$out/no_gpu.log" 2>&1
  rc=$?
  [ $rc -eq 0 ] && grep -qE "Traceback|AFAM-TEST-FAIL" "$out/no_gpu.log" && rc=99
  status "GPU asked for, CUDA hidden" "$([ $rc -eq 0 ] && echo passed || echo "FAILED rc=$rc"): $(grep -m1 "no-gpu:" "$out/no_gpu.log")"
  [ $rc -eq 0 ] || failed=1
  # The plugin built without CUDA, loaded here with the GPU there and asked for.
  if [ -f "$prefix/afam_nocuda/AdaptiveFAM.so" ]; then
    AFAM_TEST_NO_GPU=1 AFAM_PLUGIN="$prefix/afam_nocuda/AdaptiveFAM.so" AFAM_TEST_OUT="$out/nocuda" \
      AFAM_TEST_SCRIPTS="$tests" AFAM_BASELINE="$root/Testing/Data/Baseline" timeout 300 \
      "$pv/pvbatch3.11" --no-mpi "$tests/TestAFAMScenes.py" >"$out/no_cuda.log" 2>&1
    rc=$?
    [ $rc -eq 0 ] && grep -qE "Traceback|AFAM-TEST-FAIL" "$out/no_cuda.log" && rc=99
    status "plugin built without CUDA, GPU asked for" "$([ $rc -eq 0 ] && echo passed || echo "FAILED rc=$rc"): $(grep -m1 "no-gpu:" "$out/no_cuda.log")"
    [ $rc -eq 0 ] || failed=1
  fi
fi

# --- Timing in ParaView's own loop, beside the VTK window and afam replay, and ParaView's Volume.
table="$work/table.md"
: >"$table"
if part bench; then
  n="${AFAM_PV_N:-1024}"
  cache_mb="${AFAM_PV_CACHE_MB:-220}"
  nframes="${AFAM_PV_FRAMES:-200}"
  [ -n "${AFAM_TRAJECTORIES:-}" ] || [ ! -d "$prefix/trajectories" ] || export AFAM_TRAJECTORIES="$prefix/trajectories"
  source "$root/scripts/trajectories.sh"
  afam_trajectories "$afam" "$work/trajectories" >"$work/trajectories.txt" || { echo "no trajectory"; exit 1; }
  traj="$AFAM_TRAJ_DIR/user_1.dat"
  status "camera path" "$(cat "$work/trajectories.txt")"
  file="$work/ml${n}.afam"
  raw="$work/ml${n}.raw"
  what="ML ${n}^3"
  if [ -n "${AFAM_PV_ENLARGE:-}" ]; then  # the repository's head MRI made large, at 1e-2
    d="${AFAM_PV_ENLARGE//,/x}"
    raw="$work/head_${d}_uint8.raw"
    file="$work/head_${d}.afam"
    what="head MRI made ${d} (noise ${AFAM_PV_NOISE:-2.5}, detail ${AFAM_PV_DETAIL:-0}), 1e-2"
    t0=$(date +%s)
    [ -f "$file" ] || { "$afam" enlarge "$repo/Testing/Data/volumes/HeadMRVolume_48x62x42_uint8.raw" "$raw" \
        --dims "$AFAM_PV_ENLARGE" --noise "${AFAM_PV_NOISE:-2.5}" --detail "${AFAM_PV_DETAIL:-0}" >/dev/null &&
      "$afam" encode "$raw" "$file" --error-bound 1e-2 --relative --quiet >"$work/encode.log" 2>&1 &&
      rm -f "$raw"; } || { tail "$work/encode.log"; exit 1; }
    status "$what" "made and encoded in $(( $(date +%s) - t0 )) s, $(stat -c %s "$file") bytes"
  fi
  if [ ! -f "$file" ]; then
    t0=$(date +%s)
    "$afam" ml --size "$n" "$raw" >/dev/null &&
      "$afam" encode "$raw" "$file" --dims "$n,$n,$n" --mode adaptive --levels 4 --blocks 16 \
        --degree 2 --error-bound 1e-4 --quiet >"$work/encode.log" 2>&1 || { tail "$work/encode.log"; exit 1; }
    status "ML ${n}^3 generated + encoded" "$(( $(date +%s) - t0 )) s, $(stat -c %s "$file") bytes (4 levels, 16 blocks, p=2, 1e-4)"
  fi
  value() { sed -n "s/.*$1=\([^ ]*\).*/\1/p" <<<"$2" | tail -1; }
  {
    echo "| size | regime | ParaView Render() ms (median / p95) | fps | GPU / interop frames | VTK window Render() ms | afam replay ms | ParaView / VTK | bar |"
    echo "|---|---|---|---|---|---|---|---|---|"
  } >"$table"
  for size in ${AFAM_PV_SIZES:-512 1024}; do
    [ "${AFAM_PV_LOOPS:-1}" = 1 ] || break  # 0: only the rank benchmarks below
    for regime in warm cold; do
      cold=(); [ $regime = cold ] && cold=(--cold)
      tag="${size}_$regime"
      "$pv/pvbatch3.11" --no-mpi "$root/Apps/pvbatch/afam_pv_loop.py" --plugin "$plugin" --file "$file" \
        --trajectory "$traj" --size "$size" --frames "$nframes" --cache-mb "$cache_mb" "${cold[@]}" \
        --csv "$work/pv_$tag.csv" >"$work/pv_$tag.log" 2>&1 || { failed=1; tail -n 5 "$work/pv_$tag.log"; }
      vint=(); [ "$glx" = nvidia ] && vint=(--require-interop)
      "$prefix/afam/afam/BenchAFAMRenderLoop" "$file" --trajectory "$traj" --size "$size" --device gpu \
        --require-gpu "${vint[@]}" --cache-mb "$cache_mb" "${cold[@]}" --frames "$nframes" \
        --csv "$work/vtk_$tag.csv" >"$work/vtk_$tag.log" 2>&1 || { failed=1; tail -n 3 "$work/vtk_$tag.log"; }
      "$afam" replay "$file" --trajectory "$traj" --size "$size,$size" --device gpu --cache-bytes \
        "$((cache_mb * 1000000))" --cache-blocks 0 --gpu-budget-mb "$cache_mb" "${cold[@]}" --frames "$nframes" \
        --quiet --csv "$work/replay_$tag.csv" >"$work/replay_$tag.log" 2>&1 || { failed=1; tail -n 3 "$work/replay_$tag.log"; }
      p=$(grep "^pv_render_loop" "$work/pv_$tag.log" | tail -1)
      v=$(grep "median_render_call_ms=" "$work/vtk_$tag.log" | tail -1)
      r=$(value median_latency_ms "$(grep "median_latency_ms=" "$work/replay_$tag.log" | tail -1)")
      pm=$(value median_render_ms "$p"); vm=$(value median_render_call_ms "$v")
      ratio=$(awk -v a="$pm" -v b="$vm" 'BEGIN { if (b > 0) printf "%.2f", a / b; else print "?" }')
      bar="-"
      if [ "$size" = 1024 ] && [ $regime = warm ]; then
        bar="<= 1.2x VTK, >= 30 fps, first image <= 1 s: $(awk -v x="$ratio" -v f="$(value fps "$p")" -v t="$(value first_image_ms "$p")" 'BEGIN { print (x != "?" && x <= 1.2 && f >= 30 && t != "" && t <= 1000) ? "met" : "NOT met" }') (first image $(value first_image_ms "$p") ms)"
      fi
      echo "| ${size}^2 | $regime | ${pm:-?} / $(value p95_render_ms "$p") | $(value fps "$p") | $(value gpu_frames "$p") / $(value interop_frames "$p") of $(value frames "$p") | ${vm:-?} | ${r:-?} | $ratio | $bar |" >>"$table"
    done
  done
  echo "$what, user_1's first $nframes views, cache ${cache_mb} MB and GPU pool ${cache_mb} MB everywhere; medians of frames 2..N" >>"$table"
  # The same views through pvserver (1 rank, and 2 under mpirun sharing the GPU), a pvpython client
  # on the loopback address timing each Render() with the image delivered to it.
  if [ "${AFAM_PV_SERVER_BENCH:-1}" = 1 ]; then
    {
      echo
      echo "| pvserver ranks | client Render() ms (median / p95) | fps | frames cast on the GPU / through interop by every drawing rank | builtin pvbatch ms | client / builtin | first image ms |"
      echo "|---|---|---|---|---|---|---|"
    } >>"$table"
    size="${AFAM_PV_SIZES:-512 1024}"; size="${size##* }"  # the largest
    for ranks in 1 2; do
      port=$((22220 + ranks))
      if [ "$ranks" = 1 ]; then server=("$work/pvserver1" "--server-port=$port")
      else server=("$work/mpirun" -np 2 --oversubscribe "$pv/pvserver" "--server-port=$port"); fi
      setsid "${server[@]}" >"$work/pvserver${ranks}_bench.log" 2>&1 </dev/null &
      spid=$!
      timeout 300 "$pv/pvpython3.11" --force-offscreen-rendering "$root/Apps/pvbatch/afam_pv_loop.py" \
        --plugin "$plugin" --file "$file" --trajectory "$traj" --size "$size" --frames "$nframes" \
        --cache-mb "$cache_mb" --connect "$port" --csv "$work/pvserver${ranks}_$size.csv" \
        >"$work/pvserver${ranks}_$size.log" 2>&1 || { failed=1; tail -n 5 "$work/pvserver${ranks}_$size.log"; }
      kill -TERM -- "-$spid" 2>/dev/null; sleep 1; kill -KILL -- "-$spid" 2>/dev/null
      c=$(grep "^pv_render_loop" "$work/pvserver${ranks}_$size.log" | tail -1)
      b=$(grep "^pv_render_loop" "$work/pv_${size}_warm.log" | tail -1)
      echo "| $ranks | $(value median_render_ms "$c") / $(value p95_render_ms "$c") | $(value fps "$c") | $(value gpu_frames "$c") / $(value interop_frames "$c") of $(value frames "$c") | $(value median_render_ms "$b") | $(awk -v a="$(value median_render_ms "$c")" -v b="$(value median_render_ms "$b")" 'BEGIN { if (a > 0 && b > 0) printf "%.2f", a / b; else print "?" }') | $(value first_image_ms "$c") |" >>"$table"
    done
    echo "$what at ${size}^2, warm, the same $nframes views; the server's ranks, one GPU each where there are several" >>"$table"
  fi
  # pvbatch with 1, 2, ... ranks (AFAM_PV_BATCH_RANKS), each on its own GPU (the local rank's),
  # every rank drawing its box and IceT compositing: the largest size, warm, the same views.
  if [ -n "${AFAM_PV_BATCH_RANKS:-}" ]; then
    size="${AFAM_PV_SIZES:-512 1024}"; size="${size##* }"
    {
      echo
      echo "| pvbatch ranks | Render() ms (median / p95) | fps | first image ms | median / 1 rank's | rank 0 mapper / cast ms | slowest rank's mapper ms | GPU / interop frames |"
      echo "|---|---|---|---|---|---|---|---|"
    } >>"$table"
    one=""
    : >"$work/rank_logs.md"
    # An entry N runs N ranks; N:gpu0 the same with every rank's CUDA on GPU 0 (AFAM_CUDA_DEVICE=0).
    # Each rank logs ParaView's rendering scopes (IceT's times among them) to its own file, and
    # nvidia-smi is asked midway which processes each GPU holds (OpenGL "G", CUDA "C").
    for entry in $AFAM_PV_BATCH_RANKS; do
      ranks="${entry%%:*}"; tag="${entry//:/_}"
      envs=(PARAVIEW_LOG_RENDERING_VERBOSITY=INFO)
      [ "$entry" = "${ranks}:gpu0" ] && envs+=(AFAM_CUDA_DEVICE=0)
      launch=("$pv/pvbatch3.11" --no-mpi)
      [ "$ranks" = 1 ] || launch=("$work/mpirun" -np "$ranks" --oversubscribe "$pv/pvbatch3.11")
      rm -f "$work/pvlog${tag}_$size".*
      (for t in $(seq 15); do sleep 2; nvidia-smi; done >"$work/smi_${tag}.txt" 2>&1) &
      env "${envs[@]}" timeout 300 "${launch[@]}" "--log=$work/pvlog${tag}_$size,INFO" \
        "$root/Apps/pvbatch/afam_pv_loop.py" --plugin "$plugin" --file "$file" \
        --trajectory "$traj" --size "$size" --frames "$nframes" --cache-mb "$cache_mb" \
        --csv "$work/pvbatch${tag}_$size.csv" >"$work/pvbatch${tag}_$size.log" 2>&1 ||
        { failed=1; tail -n 5 "$work/pvbatch${tag}_$size.log"; }
      wait
      c=$(grep "^pv_render_loop" "$work/pvbatch${tag}_$size.log" | tail -1)
      m=$(value median_render_ms "$c"); [ "$entry" = 1 ] && one="$m"
      echo "| $entry | $m / $(value p95_render_ms "$c") | $(value fps "$c") | $(value first_image_ms "$c") | $(awk -v a="$m" -v b="$one" 'BEGIN { if (a > 0 && b > 0) printf "%.2f", a / b; else print "?" }') | $(value median_mapper_ms "$c") / $(value median_cast_ms "$c") | $(value median_slowest_mapper_ms "$c") | $(value gpu_frames "$c") / $(value interop_frames "$c") |" >>"$table"
      env -u PYTHONHOME -u PYTHONPATH python3 "$root/scripts/pv_rank_logs.py" "$work/pvlog${tag}_$size" "$entry" \
        >>"$work/rank_logs.md" 2>&1
      grep -E "pvbatch" "$work/smi_${tag}.txt" | sort | uniq -c | sed "s/^/[smi $entry] /" >>"$work/rank_logs.md"
      grep -h "GPU\|device" "$work/pvbatch${tag}_$size.log" | grep -iv "^gl:" | sort -u | head -n 6 | sed "s/^/[log $entry] /" >>"$work/rank_logs.md"
    done
    echo "$what at ${size}^2, warm, $nframes views, cache and GPU pool ${cache_mb} MB a rank; $(nvidia-smi -L | wc -l) GPU(s)" >>"$table"
    cat "$work/rank_logs.md" >>"$table"
  fi
  # ParaView's own Volume representation (its GPU ray caster on this OpenGL) on the raw samples.
  if [ -f "$raw" ] && [ "${AFAM_PV_RAW:-1}" = 1 ]; then
    size="${AFAM_PV_SIZES:-512 1024}"; size="${size##* }"
    "$pv/pvbatch3.11" --no-mpi "$root/Apps/pvbatch/afam_pv_loop.py" --plugin "$plugin" --raw "$raw" \
      --value-range-of "$file" --trajectory "$traj" --size "$size" --frames "$nframes" \
      --csv "$work/pvraw_$size.csv" >"$work/pvraw_$size.log" 2>&1 || { failed=1; tail -n 5 "$work/pvraw_$size.log"; }
    w=$(grep "^pv_render_loop" "$work/pvraw_$size.log" | tail -1)
    p=$(grep "^pv_render_loop" "$work/pv_${size}_warm.log" | tail -1)
    ours=$(value median_render_ms "$p"); theirs=$(value median_render_ms "$w")
    first=$(value first_image_ms "$p"); theirfirst=$(value first_image_ms "$w")
    {
      echo
      echo "ParaView's Volume representation on the raw ${n}^3 float32 samples against Adaptive-FAM Volume, ${size}^2, same views:"
      echo "| representation | median ms | p95 ms | first image ms (Show to image) |"
      echo "|---|---|---|---|"
      echo "| Adaptive-FAM Volume (warm) | $ours | $(value p95_render_ms "$p") | $first |"
      echo "| Volume (ParaView's GPU ray caster) | $theirs | $(value p95_render_ms "$w") | $theirfirst |"
      echo "Bars: faster per frame: $(awk -v a="$ours" -v b="$theirs" 'BEGIN { if (a > 0 && b > 0) printf "%.2fx %s", b / a, (a < b ? "met" : "NOT met"); else print "?" }'); >= 20x sooner to the first image: $(awk -v a="$first" -v b="$theirfirst" 'BEGIN { if (a > 0 && b > 0) printf "%.1fx %s", b / a, (b >= 20 * a ? "met" : "NOT met"); else print "?" }')"
    } >>"$table"
  fi
  rm -f "$raw"
fi
grep -hE "^gl: " "$work"/pv_*.log "$work"/vtk_*.log 2>/dev/null | sort -u

echo
echo "================ gpu_pv_check summary ================"
echo "GPU: $(nvidia-smi --query-gpu=name,driver_version --format=csv,noheader 2>/dev/null | head -1); plugin at $(cat "$prefix/afam/COMMIT"); GLX $glx"
cat "$summary"
cat "$table"
[ $failed -eq 0 ]
