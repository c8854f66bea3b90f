#!/usr/bin/env bash
# GPU check, for the GPU machine (CUDA, no VTK): configure Core + CudaKernels + Apps,
# build, run the GPU tests, compute-sanitizer memcheck + racecheck on one frame, the GPU
# benchmarks, and print a short table LAST.
#   scripts/gpu_check.sh [BUILD_DIR]
# Corpus volumes: $AFAM_GPU_DATA/volumes when set, else the repository's Testing/Data/volumes.
# Trajectory: user_1.dat from $AFAM_TRAJECTORIES, else $AFAM_GPU_DATA/trajectories or gpu-data/
# (git-ignored, carried), else a generated exploration walk (the summary says which). Logs go to
# $OUT when set (device tool), else to BUILD_DIR/gpu_check/.
set -uo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
build="${1:-$root/build-gpu}"
logs="${OUT:-$build/gpu_check}"
source "$root/scripts/gpu_deps.sh"  # zstd headers where the machine lacks them
mkdir -p "$logs"
jobs="${AFAM_JOBS:-16}"
status() { printf '%-28s %s\n' "$1" "$2" >>"$logs/summary.txt"; }
: >"$logs/summary.txt"

gpu="$(nvidia-smi --query-gpu=name,driver_version,memory.total --format=csv,noheader 2>/dev/null | head -1)"
echo "GPU: ${gpu:-none}  nvcc: $(nvcc --version 2>/dev/null | tail -1)"

# --- Configure and build (keep going past failures elsewhere; our targets are checked below).
t0=$(date +%s)
cmake -S "$root" -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=Release \
  -DAFAM_ENABLE_PARAVIEW=OFF -DAFAM_ENABLE_CUDA=ON >"$logs/configure.log" 2>&1
rc=$?
if [ $rc -ne 0 ]; then tail -30 "$logs/configure.log"; status configure "FAILED"; cat "$logs/summary.txt"; exit 1; fi
ninja -C "$build" -j "$jobs" -k 0 >"$logs/build.log" 2>&1
build_rc=$?
grep -E "error|FAILED" "$logs/build.log" | head -20
grep -E "registers|spill" "$logs/build.log" | head -5
status "build (ninja -j$jobs)" "$([ $build_rc -eq 0 ] && echo ok || echo "rc=$build_rc (see build.log)") in $(( $(date +%s) - t0 )) s"
tests="$build/Testing/Cuda/afam_cuda_tests"
bench="$build/Testing/Cuda/bench_gpu"
if [ ! -x "$tests" ] || [ ! -x "$bench" ]; then
  status "GPU targets" "NOT BUILT"; cat "$logs/summary.txt"; exit 1
fi

# --- GPU tests.
"$tests" --gtest_color=no >"$logs/tests.log" 2>&1
test_rc=$?
grep -E "^\[(gpu-vs-cpu|generic-vs-p2|pool|ds|gpu-edits|gpu-damage|gpu-missing|gpu-decode|gpu-promise)\]|reference LRU|Failure|FAILED|SKIPPED|PASSED" "$logs/tests.log"
status "GPU tests" "$(grep -E '^\[  PASSED  \]' "$logs/tests.log" | head -1) $(grep -E '^\[  FAILED  \] [0-9]' "$logs/tests.log" | head -1) $(grep -E '^\[  SKIPPED \] [0-9]' "$logs/tests.log" | head -1)"
worst=$(grep -E '^\[gpu-vs-cpu\]' "$logs/tests.log" | grep -oE "max \|diff\| [0-9]+/255" | grep -oE "[0-9]+/" | tr -d / | sort -n | tail -1)
status "GPU vs CPU worst diff" "${worst:-?}/255 over $(grep -c '^\[gpu-vs-cpu\]' "$logs/tests.log") images (bar <= 2/255, exact kernels)"
worst=$(grep -E '^\[gpu-missing\]' "$logs/tests.log" | grep -oE "max \|diff\| [0-9]+/255" | grep -oE "[0-9]+/" | tr -d / | sort -n | tail -1)
status "missing samples vs CPU" "${worst:-?}/255 over $(grep -c '^\[gpu-missing\]' "$logs/tests.log") images (bar <= 2/255, exact and fast kernels)"
status "bound promise on GPU" "$(grep -E '^\[gpu-promise\]' "$logs/tests.log" | grep -oE 'files [0-9]+|mismatches [0-9]+|failed [0-9]+' | paste -sd' ')"
for m in fma fast; do
  w=$(grep -E "^\[gpu-vs-cpu:$m\]" "$logs/tests.log" | grep -oE "max \|diff\| [0-9]+/255" | grep -oE "[0-9]+/" | tr -d / | sort -n | tail -1)
  status "  same, $m kernels" "${w:-?}/255 (reported, not a bar)"
done

# --- Sanitizers on one frame.
for tool in memcheck racecheck; do
  compute-sanitizer --tool $tool --error-exitcode 9 "$bench" --sanitize >"$logs/sanitizer_$tool.log" 2>&1
  src=$?
  tail -3 "$logs/sanitizer_$tool.log"
  status "compute-sanitizer $tool" "$([ $src -eq 0 ] && echo clean || echo "rc=$src: $(grep -m1 -E 'ERROR SUMMARY|Error' "$logs/sanitizer_$tool.log")")"
done

# --- Benchmarks.
"$bench" --table "$logs/bench_table.md" 2>&1 | tee "$logs/bench.log"
bench_rc=$?
status "bench_gpu" "$([ $bench_rc -eq 0 ] && echo ok || echo "rc=$bench_rc")"

# --- End to end through the command line: afam ml -> encode (Adaptive-FAM, paper settings) ->
# render the anchor views and replay user_1.dat with --device gpu and --device cpu.
afam="$build/Apps/afam"
e2e="$build/gpu_check_e2e"; mkdir -p "$e2e"
carried="${AFAM_GPU_DATA:-$root/gpu-data}/trajectories"
[ -n "${AFAM_TRAJECTORIES:-}" ] || [ ! -d "$carried" ] || export AFAM_TRAJECTORIES="$carried"
source "$root/scripts/trajectories.sh"
if [ -x "$afam" ] && afam_trajectories "$afam" "$e2e/trajectories" >"$e2e/trajectories.txt"; then
  traj="$AFAM_TRAJ_DIR/user_1.dat"
  status "trajectory" "$(cat "$e2e/trajectories.txt")"
  n="${AFAM_GPU_ML:-512}"
  t0=$(date +%s)
  "$afam" ml --size "$n" "$e2e/ml.raw" >/dev/null &&
    "$afam" encode "$e2e/ml.raw" "$e2e/ml.afam" --dims "$n,$n,$n" --type float32 --levels 4 --blocks 16 \
      --error-bound 1e-4 >"$e2e/encode.log" 2>&1
  status "afam ml+encode ${n}^3" "rc=$? in $(( $(date +%s) - t0 )) s (levels 4, blocks 16, p=2, bound 1e-4), $(grep -o 'bytes_out=[0-9]*' "$e2e/encode.log"), $(grep -o 'voxels_per_s_per_thread=[0-9.e+]*' "$e2e/encode.log")"
  for view in 0 100 200 300; do
    for dev in gpu cpu; do
      "$afam" render "$e2e/ml.afam" --trajectory "$traj" --view $view --size 512,512 \
        --device $dev --out "$e2e/view${view}_$dev.png" >"$e2e/render_${view}_$dev.log" 2>&1
    done
    g=$(grep -o 'render_ms=[0-9.]*' "$e2e/render_${view}_gpu.log" | cut -d= -f2)
    c=$(grep -o 'render_ms=[0-9.]*' "$e2e/render_${view}_cpu.log" | cut -d= -f2)
    b=$(grep -o 'blocks=[0-9]*' "$e2e/render_${view}_gpu.log" | head -1 | cut -d= -f2)
    d=$(python3 -c "
from PIL import Image; import numpy as np
a=np.asarray(Image.open('$e2e/view${view}_gpu.png'),dtype=int); b=np.asarray(Image.open('$e2e/view${view}_cpu.png'),dtype=int)
print('max diff %d/255, %d px differ' % (abs(a-b).max(), (abs(a-b).max(axis=2)>0).sum()))" 2>&1 | tail -1)
    status "afam render view $view" "blocks=$b gpu ${g} ms (upload+kernel+readback), cpu ${c} ms; $d"
  done
  grep -h "device=" "$e2e/render_0_gpu.log"
  "$afam" replay "$e2e/ml.afam" --trajectory "$traj" --size 512,512 --device gpu --quiet >"$e2e/replay_gpu.log" 2>&1
  status "afam replay user_1 gpu" "$(grep "median_latency_ms=" "$e2e/replay_gpu.log" | tail -1)"
  "$afam" replay "$e2e/ml.afam" --trajectory "$traj" --size 512,512 --device cpu --frames 12 --quiet >"$e2e/replay_cpu.log" 2>&1
  status "afam replay user_1 cpu (12)" "$(grep "median_latency_ms=" "$e2e/replay_cpu.log" | tail -1)"
  "$afam" replay "$e2e/ml.afam" --trajectory "$traj" --size 512,512 --device gpu --frames 12 --quiet >"$e2e/replay_gpu12.log" 2>&1
  status "afam replay user_1 gpu (12)" "$(grep "median_latency_ms=" "$e2e/replay_gpu12.log" | tail -1)"
else
  status "afam end to end" "not run: no afam binary"
fi

# --- GPU decoding (issue 27): a scan made large (half the bar's size per axis, 281 M voxels), encoded with the defaults, every payload decoded on the GPU and on one CPU thread in one
# run (bench_gpu_decode checks the floats are equal).
dec="$build/Testing/Cuda/bench_gpu_decode"
if [ -x "$dec" ] && [ -x "$afam" ]; then
  scan="$e2e/scan_602x740x632_uint8.raw"
  "$afam" enlarge "$root/Testing/Data/volumes/HeadMRVolume_48x62x42_uint8.raw" "$scan" \
    --dims 602,740,632 --noise 2.5 >/dev/null &&
    "$afam" encode "$scan" "$e2e/scan.afam" --error-bound 1e-2 --relative --quiet &&
    "$dec" "$e2e/scan.afam" --rounds 5 >"$logs/gpu_decode.log" 2>&1
  rm -f "$scan"
  pick() { grep "^$1 " "$logs/gpu_decode.log" | grep -oE "$2" | tr '\n' ' '; }
  status "GPU decode (scan, defaults)" "$(pick gpu_decode 'decodable=[0-9]+|decoded_bytes=[0-9]+|gbps=[0-9.]+|mismatches=[0-9]+')"
  status "  one CPU thread, same run" "$(pick cpu_decode 'gbps=[0-9.]+')"
  grep -E "^\[gpu-decode\]" "$logs/tests.log" | tail -1 | sed 's/^/  frames: /' >>"$logs/summary.txt"
fi

# --- GPU encoding (issue 42): afam encode --device cpu against --device gpu on the head made
# 602x740x632, every core, one run of each (Testing/Benchmarks/encode_gpu.sh; the same bytes), with
# noise 2.5 and as a real scan.
if [ -x "$afam" ]; then
  REPS=1 WORK="$e2e/encode" "$root/Testing/Benchmarks/encode_gpu.sh" "$afam" >"$logs/encode_gpu.log" 2>&1
  status "encode --device gpu vs cpu" "$(tail -1 "$logs/encode_gpu.log")"
  rm -rf "$e2e/encode"
  # The same size with a real T1 MRI's bytes and blocks (quiet air, noisy tissue, detail).
  NOISE=2 TISSUE_NOISE=3 DETAIL=12 REPS=1 WORK="$e2e/encode" \
    "$root/Testing/Benchmarks/encode_gpu.sh" "$afam" >"$logs/encode_gpu_real.log" 2>&1
  status "  a real scan's bytes" "$(tail -1 "$logs/encode_gpu_real.log")"
  rm -rf "$e2e/encode"
fi

echo
echo "================ gpu_check summary ================"
echo "GPU: ${gpu:-none}"
cat "$logs/summary.txt"
[ -f "$logs/bench_table.md" ] && cat "$logs/bench_table.md"
[ $test_rc -eq 0 ] && [ $bench_rc -eq 0 ]
