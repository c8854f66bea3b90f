#!/usr/bin/env bash
# The latency bar on the GPU machine: Marschner-Lobb N^3 (default 1024) encoded with the paper's
# settings (4 levels, 16 finest blocks per axis, p = 2, RMSE bound 1e-4) as Adaptive-FAM, FAM
# (fixed NCP = n) and DS; every trajectory replayed at 512 x 512 with --device gpu from a cold page
# cache (--cold: the file is evicted from the OS page cache before each point of view), the same
# cache budget in bytes for every method, with each prefetcher. Prints one table last.
#   scripts/gpu_replay.sh [BUILD_DIR]     (builds the afam target there if it is missing)
# Environment: AFAM_REPLAY_N (volume size, 1024), AFAM_REPLAY_CACHE_BYTES (default 220e6: about the
# paper's 200 micro-models of FAM at 1024^3), AFAM_REPLAY_PREFETCH ("none appa forecache lstm"),
# AFAM_REPLAY_CACHE_BLOCKS (when set: a budget of that many micro-models instead of bytes, e.g. the
# paper's 200), AFAM_REPLAY_METHODS ("adaptive fixed ds"), AFAM_REPLAY_TRAJECTORIES ("user_1 user_2"),
# AFAM_REPLAY_WORK (scratch folder, default /tmp/afam_replay), AFAM_TRAJECTORIES (folder of the
# recorded user_1.dat, user_2.dat; default $AFAM_GPU_DATA/trajectories or gpu-data/trajectories when
# carried; generated exploration walks otherwise, and the script says so). Logs and CSVs go to $OUT
# when set.
set -uo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
build="${1:-$root/build-gpu}"
n="${AFAM_REPLAY_N:-1024}"
cache="${AFAM_REPLAY_CACHE_BYTES:-220000000}"
prefetchers="${AFAM_REPLAY_PREFETCH:-none appa forecache lstm}"
methods="${AFAM_REPLAY_METHODS:-adaptive fixed ds}"
trajectories="${AFAM_REPLAY_TRAJECTORIES:-user_1 user_2}"
budget=(--cache-bytes "$cache" --cache-blocks 0)
budget_text="cache ${cache} bytes for every method"
if [ -n "${AFAM_REPLAY_CACHE_BLOCKS:-}" ]; then
  budget=(--cache-blocks "$AFAM_REPLAY_CACHE_BLOCKS")
  budget_text="cache ${AFAM_REPLAY_CACHE_BLOCKS} micro-models"
fi
work="${AFAM_REPLAY_WORK:-/tmp/afam_replay}"
logs="${OUT:-$work/logs}"
mkdir -p "$work" "$logs"
afam="$build/Apps/afam"
source "$root/scripts/gpu_deps.sh"  # zstd headers where the machine lacks them
if [ ! -x "$afam" ]; then
  cmake -S "$root" -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=Release -DAFAM_ENABLE_PARAVIEW=OFF \
    -DAFAM_ENABLE_CUDA=ON >"$logs/replay_configure.log" 2>&1 &&
    ninja -C "$build" afam >"$logs/replay_build.log" 2>&1 || { tail -20 "$logs/replay_build.log"; exit 1; }
fi
carried="${AFAM_GPU_DATA:-$root/gpu-data}/trajectories"
[ -n "${AFAM_TRAJECTORIES:-}" ] || [ ! -d "$carried" ] || export AFAM_TRAJECTORIES="$carried"
source "$root/scripts/trajectories.sh"
afam_trajectories "$afam" "$work/trajectories" >"$logs/trajectories.txt" || exit 1
cat "$logs/trajectories.txt"
t0=$(date +%s)
[ -f "$work/ml.raw" ] || "$afam" ml --size "$n" "$work/ml.raw" >/dev/null || exit 1
echo "afam ml ${n}^3: $(( $(date +%s) - t0 )) s"
for mode in $methods; do
  f="$work/ml_$mode.afam"
  t0=$(date +%s)
  [ -f "$f" ] || "$afam" encode "$work/ml.raw" "$f" --dims "$n,$n,$n" --mode "$mode" \
    --error-bound 1e-4 --levels 4 --blocks 16 --degree 2 --quiet || exit 1
  echo "encode $mode: $(( $(date +%s) - t0 )) s, $(stat -c %s "$f") bytes"
done
rm -f "$work/ml.raw"  # only the encodings are read from here on
table="$logs/replay_table.md"
{
  echo "| trajectory | method | prefetch | median latency ms | median caching ms | median render ms | miss rate |"
  echo "|---|---|---|---|---|---|---|"
} >"$table"
for traj in $trajectories; do
  for mode in $methods; do
    for pf in $prefetchers; do
      name="${traj}_${mode}_${pf}"
      "$afam" replay "$work/ml_$mode.afam" --trajectory "$AFAM_TRAJ_DIR/$traj.dat" \
        --size 512,512 --device gpu --cold "${budget[@]}" --prefetch "$pf" \
        --quiet --csv "$logs/$name.csv" >"$logs/$name.log" 2>&1
      last=$(grep "median_latency_ms=" "$logs/$name.log" | tail -1)
      lat=$(sed -n 's/.*median_latency_ms=\([^ ]*\).*/\1/p' <<<"$last")
      cac=$(sed -n 's/.*median_caching_ms=\([^ ]*\).*/\1/p' <<<"$last")
      ren=$(sed -n 's/.*median_render_ms=\([^ ]*\).*/\1/p' <<<"$last")
      mis=$(sed -n 's/.*miss_rate=\([^ ]*\).*/\1/p' <<<"$last")
      echo "| $traj | $mode | $pf | ${lat:-?} | ${cac:-?} | ${ren:-?} | ${mis:-?} |" >>"$table"
    done
  done
done
grep -h -m1 -i "device" "$logs"/*.log | head -1 || true
echo "ML ${n}^3, 512x512, --device gpu --cold, $budget_text"
cat "$logs/trajectories.txt"
cat "$table"
