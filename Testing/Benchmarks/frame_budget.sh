#!/usr/bin/env bash
# SPDX-License-Identifier: BSD-3-Clause
# Issue 44's bars on this machine: a frame never waits longer than its miss budget. The
# repository's head MRI made large with noise above the bound (every finest block an
# interpolant, as in a real scan's detail), encoded at 1e-2 relative with the defaults, replayed
# on recorded camera paths, cold page cache, screen-space LOD, a 20 ms miss budget, with a cache
# of the path's whole working set (the cache's peak bytes over the path with an unlimited cache)
# and with a quarter of it; BASE's afam (a build of the commit before) and NEW's in the same run.
# Prints one markdown row per path, cache and build: first image, median and p95 frame, the worst
# caching time after the first frame, stand-ins and blocks behind, and (NEW only) the motion
# frames' mean SSIM against the exact frame of each view (`afam replay --ssim`).
#
# usage: Testing/Benchmarks/frame_budget.sh NEW_AFAM BASE_AFAM|- TRAJECTORY.dat...  (-: NEW only)
#   e.g. build/Apps/afam /tmp/base-build/Apps/afam $AFAM_TRAJECTORIES/user_{1,2}.dat
# Env: DIMS (default 402,494,422), NOISE (default 6), DETAIL (afam enlarge --detail: structure at
#      every scale, so that the scan's bytes are a real scan's; default 0: none), TISSUE_NOISE
#      (afam enlarge --tissue-noise: the noise in tissue, air keeping NOISE; default NOISE; NOISE=2
#      TISSUE_NOISE=3 DETAIL=12 at 1204,1480,1264 has a real T1 MRI's bytes, complex blocks and
#      working set, docs/BENCHMARKS.md), SIZE (image side, default 128), BUDGET
#      (ms, default 20), DEVICE (cpu|gpu, default cpu), FRAMES (views of each path, default 400),
#      SAMPLE_DISTANCE (default 0.005; larger casts faster on a small CPU), WORK (default a
#      temporary folder), SSIM (1 default; 0 leaves out --ssim, whose exact reference frames are
#      drawn on the same device: on the CPU too slow at 1024^2), PREFETCH (afam replay --prefetch,
#      default none).
set -euo pipefail
here="$(cd "$(dirname "$0")/../.." && pwd)"
NEW="$1"
BASE="$2"
shift 2
DIMS="${DIMS:-402,494,422}"
NOISE="${NOISE:-6}"
DETAIL="${DETAIL:-0}"
TISSUE_NOISE="${TISSUE_NOISE:-$NOISE}"
SIZE="${SIZE:-128}"
BUDGET="${BUDGET:-20}"
DEVICE="${DEVICE:-cpu}"
FRAMES="${FRAMES:-400}"
SAMPLE_DISTANCE="${SAMPLE_DISTANCE:-0.005}"
SSIM="${SSIM:-1}"
PREFETCH="${PREFETCH:-none}"
work="${WORK:-$(mktemp -d)}"
mkdir -p "$work"
[[ -n ${WORK:-} ]] || trap 'rm -rf "$work"' EXIT
tag="n${NOISE}_t${TISSUE_NOISE}_d${DETAIL}"
raw="$work/head_${tag}_${DIMS//,/x}_uint8.raw"
file="$work/head_${DIMS//,/x}_${tag}.afam"
detail=()
[[ $DETAIL == 0 ]] || detail=(--detail "$DETAIL")
[[ -f $raw ]] || "$NEW" enlarge "$here/Testing/Data/volumes/HeadMRVolume_48x62x42_uint8.raw" \
  "$raw" --dims "$DIMS" --noise "$NOISE" --tissue-noise "$TISSUE_NOISE" "${detail[@]}" >/dev/null
[[ -f $file ]] || "$NEW" encode "$raw" "$file" --error-bound 1e-2 --relative --quiet >/dev/null
value() { { grep -o "$1=[0-9.e+-]*" <<<"$2" || true; } | tail -1 | cut -d= -f2; }
# Figures of a replay's CSV: first latency, median, p95, p95/median, worst caching after the first.
figures() {
  local lat first worst
  lat="$(awk -F, 'NR > 1 { print $4 }' "$1" | sort -g)"
  first="$(awk -F, 'NR == 2 { print $4 }' "$1")"
  worst="$(awk -F, 'NR > 2 && $2 > w { w = $2 } END { print w + 0 }' "$1")"
  awk -v first="$first" -v worst="$worst" '{ v[NR] = $1 }
    END { n = NR; med = n % 2 ? v[(n + 1) / 2] : (v[n / 2] + v[n / 2 + 1]) / 2
          r = int(0.95 * n + 0.999999); if (r < 1) r = 1
          printf "%.1f | %.1f | %.1f | %.2f | %.1f", first, med, v[r], v[r] / med, worst }' <<<"$lat"
}
common=(--size "$SIZE,$SIZE" --device "$DEVICE" --cold --lod screen --miss-budget-ms "$BUDGET"
  --cache-blocks 0 --quiet --frames "$FRAMES" --sample-distance "$SAMPLE_DISTANCE"
  --prefetch "$PREFETCH")
echo "machine: $(nproc) cores, $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ //'), load $(cut -d' ' -f1-3 /proc/loadavg)"
echo "scan: head MRI made large to $DIMS, noise $NOISE (tissue $TISSUE_NOISE), detail $DETAIL, $(stat -c %s "$file") bytes at 1e-2 relative"
echo "command: afam replay FILE --trajectory PATH ${common[*]} --cache-bytes C [--ssim] --csv OUT"
echo
echo "| path | cache | build | first image ms | median ms | p95 ms | p95/median | worst caching after the first ms | stand-ins | blocks behind | mean SSIM |"
echo "|---|---|---|---|---|---|---|---|---|---|---|"
for traj in "$@"; do
  name="$(basename "$traj" .dat)"
  out="$("$NEW" replay "$file" --trajectory "$traj" "${common[@]}" --cache-bytes 0)"
  ws="$(value cache_peak_bytes "$out")"
  for cache in "$ws" "$((ws / 4))"; do
    label="$((cache / 1000000)) MB"
    [[ $cache == "$ws" ]] && label="$label (working set)" || label="$label (a quarter)"
    builds=(base new)
    [[ $BASE == - ]] && builds=(new)
    for build in "${builds[@]}"; do
      exe="$BASE"
      extra=()
      [[ $build == new ]] && exe="$NEW"
      [[ $build == new && $SSIM == 1 ]] && extra=(--ssim)
      csv="$work/${name}_${cache}_${build}.csv"
      out="$("$exe" replay "$file" --trajectory "$traj" "${common[@]}" --cache-bytes "$cache" \
        "${extra[@]}" --csv "$csv")"
      standins="$(value stand_in_blocks "$out")"
      behind="$(value blocks_behind "$out")"
      ssim="$(value mean_ssim "$out")"
      echo "| $name | $label | $build | $(figures "$csv") | $standins | ${behind:--} | ${ssim:--} |"
    done
  done
done
