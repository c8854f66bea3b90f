#!/usr/bin/env bash
# SPDX-License-Identifier: BSD-3-Clause
# Renderer benchmarks (docs/BENCHMARKS.md, "Renderer").
#
# usage: [PHASE=all|replay|quality] renderer_bench.sh AFAM_BIN BENCH_RENDER_BIN WORKDIR TRAJECTORY [PARALLEL]
#   Makes ML 256^3, encodes it three ways (Adaptive-FAM, FAM = fixed NCP = n, DS), then
#   1. replays the whole trajectory for each method at the same cache budget in bytes, cold storage
#      (OS page cache dropped before each point of view) with the emulated 100 MB/s cap, and cold
#      without the cap;
#   2. renders one fixed view per method against the analytic ground truth (PSNR, SSIM);
#   3. runs bench_render (O(1) lookup, 8 vs 64 vs 512 visible blocks, and the linear-scan design).
#   Every replay runs with --threads 2 pinned to its own 2 cores (taskset), so runs executed side by
#   side (PARALLEL=1, for machines with >= 16 cores) each see a 2-core machine.
set -euo pipefail
AFAM=$1; BENCH=$2; W=$3; TRAJ=$4; PAR=${5:-0}
SIZE=${SIZE:-256}; IMG=${IMG:-256,256}; SD=${SD:-0.01}; CACHE_BYTES=${CACHE_BYTES:-4000000}
BOUNDS=${BOUNDS:-"1e-4 1e-5"}; VIEW=${VIEW:-200}; PHASE=${PHASE:-all}
mkdir -p "$W"; cd "$W"
[ -f ml.raw ] || "$AFAM" ml --size "$SIZE" ml.raw
D=$SIZE,$SIZE,$SIZE
METHODS=""
for b in $BOUNDS; do
  [ -f "afam_$b.afam" ] || "$AFAM" encode ml.raw "afam_$b.afam" --dims $D --mode adaptive --error-bound "$b" --quiet
  METHODS="$METHODS afam_$b"
done
METHODS="$METHODS fam ds"
[ -f fam.afam ] || "$AFAM" encode ml.raw fam.afam --dims $D --mode fixed --quiet
[ -f ds.afam ] || "$AFAM" encode ml.raw ds.afam --dims $D --mode ds --quiet
ls -l *.afam | tee sizes.txt
core=0
run() {  # name, then replay options
  local name=$1; shift
  local cores="$core,$((core + 1))"
  core=$((core + 2))
  local cmd=(taskset -c "$cores" "$AFAM" replay "$@" --trajectory "$TRAJ" --size "$IMG" --sample-distance "$SD"
             --cache-bytes "$CACHE_BYTES" --cache-blocks 0 --threads 2 --quiet --csv "$name.csv")
  echo "${cmd[*]}" > "$name.cmd"
  if [ "$PAR" = 1 ]; then "${cmd[@]}" > "$name.log" 2>&1 & else "${cmd[@]}" > "$name.log" 2>&1; fi
}
if [ "$PHASE" != quality ]; then
  for m in $METHODS; do run "capped_$m" "$m.afam" --cold --storage-mbps 100; done
  for m in $METHODS; do run "uncapped_$m" "$m.afam" --cold; done
  wait
  for f in capped_*.log uncapped_*.log; do echo "$f: $(tail -1 "$f")"; done | tee summary_replay.txt
fi
[ "$PHASE" = replay ] && exit 0
core=0
# Quality at a fixed view (same LOD cut for all methods), default sample distance 0.005.
for m in $METHODS; do
  taskset -c "$core,$((core + 1))" "$AFAM" render "$m.afam" --trajectory "$TRAJ" --view "$VIEW" --size "$IMG" \
    --out "quality_$m.png" --ground-truth-ml --gt-out quality_gt.png --threads 2 --cache-blocks 0 > "quality_$m.log" 2>&1
done
core=$((core + 2))
taskset -c "$core" "$BENCH" --benchmark_repetitions=5 --benchmark_report_aggregates_only=true \
  --benchmark_min_time=0.2 > bench_render.txt 2>&1 || true
for f in quality_*.log; do echo "$f: $(grep -E 'psnr|bytes' "$f" | tr '\n' ' ')"; done | tee summary_quality.txt
grep -E "median" bench_render.txt | tee -a summary_quality.txt
