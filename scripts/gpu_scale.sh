#!/usr/bin/env bash
# Interaction on a real scan at scale, on the GPU machine (issue 27's measurement): builds Core +
# CudaKernels + Apps, makes the repository's HeadMRVolume large with `afam enlarge` (default
# 1204x1480x1264 uint8, 2.25 G voxels, noise 2.5: about the compression of a real T1 scan at a
# relative RMSE of 1e-2), encodes it at 1e-2 relative with the defaults, and replays the first
# FRAMES views of user_1 with --device gpu --cold --lod screen and a 1 GB host cache, at each
# image size, waiting for every miss (exact) and with a miss budget (its still frame compared with
# the last view rendered fresh with an unlimited cache: psnr=99 is identical); one table last.
#   scripts/gpu_scale.sh [BUILD_DIR]
# AFAM_SCALE_DIMS (X,Y,Z), AFAM_SCALE_NOISE, AFAM_SCALE_FRAMES (30), AFAM_SCALE_SIZES ("512 1024"),
# AFAM_SCALE_BUDGETS ("exact 20": exact, or milliseconds), AFAM_SCALE_CACHE_BYTES (1e9).
# Trajectory: $AFAM_TRAJECTORIES/user_1.dat, else gpu-data/trajectories/user_1.dat (carried).
set -uo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
build="${1:-$root/build-gpu}"
work="${AFAM_SCALE_WORK:-/tmp/afam_scale}"
logs="${OUT:-$work}"
source "$root/scripts/gpu_deps.sh"
mkdir -p "$work" "$logs"
dims="${AFAM_SCALE_DIMS:-1204,1480,1264}"
noise="${AFAM_SCALE_NOISE:-2.5}"
frames="${AFAM_SCALE_FRAMES:-30}"
cache="${AFAM_SCALE_CACHE_BYTES:-1000000000}"
traj="${AFAM_TRAJECTORIES:-$root/gpu-data/trajectories}/user_1.dat"
[ -f "$traj" ] || { echo "gpu_scale.sh: no trajectory at $traj" >&2; exit 1; }
echo "GPU: $(nvidia-smi --query-gpu=name,memory.total --format=csv,noheader 2>/dev/null | head -1), $(nproc) cores"
t0=$(date +%s)
cmake -S "$root" -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=Release -DAFAM_ENABLE_PARAVIEW=OFF \
  -DAFAM_ENABLE_CUDA=ON >"$logs/configure.log" 2>&1 &&
  ninja -C "$build" afam >"$logs/build.log" 2>&1 || { tail -20 "$logs/build.log"; exit 1; }
echo "build: $(( $(date +%s) - t0 )) s"
afam="$build/Apps/afam"
raw="$work/headmr_$(tr ',' 'x' <<<"$dims")_uint8.raw"
t0=$(date +%s)
"$afam" enlarge "$root/Testing/Data/volumes/HeadMRVolume_48x62x42_uint8.raw" "$raw" --dims "$dims" \
  --noise "$noise" | tee "$logs/enlarge.log"
echo "enlarge: $(( $(date +%s) - t0 )) s"
t0=$(date +%s)
"$afam" encode "$raw" "$work/scan.afam" --error-bound 1e-2 --relative >"$logs/encode.log" 2>&1 ||
  { tail -5 "$logs/encode.log"; exit 1; }
echo "encode: $(( $(date +%s) - t0 )) s, $(grep -o 'bytes_out=[0-9]*\|ratio=[0-9.]*' "$logs/encode.log" | tr '\n' ' ')"
"$afam" info "$work/scan.afam" | grep -E "kinds|level" | tail -4
rm -f "$raw"  # the replays read the .afam file only
head -c $(( frames * 12 )) "$traj" >"$work/path.dat"  # 12 bytes a pose
printf '%-6s %-7s %12s %12s %12s %12s %10s %10s %12s %14s\n' size budget median_ms caching_ms p95_ms first_ms misses stand_ins still_ms still_vs_fresh >"$logs/table.txt"
for size in ${AFAM_SCALE_SIZES:-512 1024}; do
  for budget in ${AFAM_SCALE_BUDGETS:-exact 20}; do
    opt=(); [ "$budget" = exact ] || opt=(--miss-budget-ms "$budget" --still-out "$work/still.png")
    log="$logs/replay_${size}_${budget}.log"
    "$afam" replay "$work/scan.afam" --trajectory "$work/path.dat" --size "$size" --device gpu --cold \
      --lod screen --cache-bytes "$cache" --cache-blocks 0 "${opt[@]}" >"$log" 2>&1 || { tail -5 "$log"; continue; }
    first=$(grep -m1 '^pov=0 ' "$log" | grep -o 'latency_ms=[0-9.]*' | cut -d= -f2)
    same=-  # the still frame against the last view rendered fresh with an unlimited cache
    if [ "$budget" != exact ] && "$afam" render "$work/scan.afam" --trajectory "$work/path.dat" \
      --view $(( $(stat -c %s "$work/path.dat") / 12 - 1 )) --size "$size" --device gpu --lod screen \
      --cache-bytes 0 --cache-blocks 0 --out "$work/fresh.png" >/dev/null 2>&1; then
      same=$("$afam" compare "$work/still.png" "$work/fresh.png" | grep -o 'psnr=[0-9.]*')
    fi
    misses=$(grep -o '^hits=[0-9]* misses=[0-9]*' "$log" | grep -o 'misses=[0-9]*' | cut -d= -f2)
    line=$(grep '^median_latency_ms=' "$log")
    printf '%-6s %-7s %12s %12s %12s %12s %10s %10s %12s %14s\n' "$size" "$budget" \
      "$(grep -o 'median_latency_ms=[0-9.]*' <<<"$line" | cut -d= -f2)" \
      "$(grep -o 'median_caching_ms=[0-9.]*' <<<"$line" | cut -d= -f2)" \
      "$(grep -o 'p95_latency_ms=[0-9.]*' <<<"$line" | cut -d= -f2)" "$first" "$misses" \
      "$(grep -o 'stand_in_blocks=[0-9]*' <<<"$line" | cut -d= -f2)" \
      "$(grep -o '^still_frame caching_ms=[0-9.]* latency_ms=[0-9.]*' "$log" | grep -o 'latency_ms=[0-9.]*' | cut -d= -f2)" \
      "$same" >>"$logs/table.txt"
  done
done
echo "================ gpu_scale: $(cut -d, -f1-3 <<<"$dims") uint8, noise $noise, 1e-2 relative, first $frames views of user_1, cold, screen LOD, ${cache} B cache"
cat "$logs/table.txt"
