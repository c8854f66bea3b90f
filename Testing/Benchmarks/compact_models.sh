#!/usr/bin/env bash
# SPDX-License-Identifier: BSD-3-Clause
# What the compact form of cached models (a table and a 1- or 2-byte code a point: integer-coded
# splines and samples, interpolants with rounded points) gives a renderer, side by side with the
# same renderer keeping float32 models, in one run: the repository's head MRI made large with
# noise above the bound (so that most finest blocks are interpolants), encoded at 1e-2 relative
# with the defaults, replayed on a camera path with a cold page cache, screen-space LOD and a
# host cache smaller than the decoded finest level, `--models float` then `--models compact`, twice
# each, printed as a markdown table (medians of the per-run medians). On the GPU, VARIANTS also
# compares how the GPU pool holds compact models (GpuPoolModels, AFAM_GPU_POOL_MODELS) with a pool
# of GPU_MB MiB, e.g. VARIANTS="compact:floats compact:auto" GPU_MB=96.
#
# usage: Testing/Benchmarks/compact_models.sh [AFAM_EXE] [TRAJECTORY.dat]
#   AFAM_EXE default build/Apps/afam; TRAJECTORY default a generated exploration walk
# Env: DEVICE (cpu|gpu, default cpu), DIMS (default 384,496,336), NOISE (default 6), SIZE (image
#      side, default 512), FRAMES (default 60), CACHE_MB (default 256), WORK (default a temporary
#      folder, removed afterwards), GPU_MB (GPU pool, default 2048), VARIANTS (default
#      "float compact": MODELS[:POOL] with POOL auto|floats|compact, default auto).
set -euo pipefail
here="$(cd "$(dirname "$0")/../.." && pwd)"
AFAM="${1:-$here/build/Apps/afam}"
TRAJ="${2:-}"
DEVICE="${DEVICE:-cpu}"
DIMS="${DIMS:-384,496,336}"
NOISE="${NOISE:-6}"
SIZE="${SIZE:-512}"
FRAMES="${FRAMES:-60}"
CACHE_MB="${CACHE_MB:-256}"
GPU_MB="${GPU_MB:-2048}"
VARIANTS="${VARIANTS:-float compact}"
[[ -x $AFAM ]] || { echo "compact_models.sh: no afam executable at $AFAM" >&2; exit 1; }
work="${WORK:-$(mktemp -d)}"
mkdir -p "$work"
[[ -n ${WORK:-} ]] || trap 'rm -rf "$work"' EXIT
raw="$work/head_${DIMS//,/x}_uint8.raw"
file="$work/head_${DIMS//,/x}.afam"
[[ -f $raw ]] || "$AFAM" enlarge "$here/Testing/Data/volumes/HeadMRVolume_48x62x42_uint8.raw" "$raw" \
  --dims "$DIMS" --noise "$NOISE" >/dev/null
t0=$(date +%s.%N)
[[ -f $file ]] || "$AFAM" encode "$raw" "$file" --error-bound 1e-2 --relative --quiet >/dev/null
t1=$(date +%s.%N)
if [[ -z $TRAJ ]]; then
  TRAJ="$work/walk.dat"
  "$AFAM" trajectory "$TRAJ" --kind walk --views "$FRAMES" --seed 3 >/dev/null
fi
value() { grep -o "$1=[0-9.e+-]*" <<<"$2" | tail -1 | cut -d= -f2; }
echo "machine: $(nproc) cores, $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ //')"
echo "scan: head MRI made large to $DIMS, noise $NOISE, $(stat -c %s "$file") bytes at 1e-2 relative (encoded in $(awk -v a="$t0" -v b="$t1" 'BEGIN { printf "%.1f", b - a }') s)"
"$AFAM" info "$file" | grep -E "^level|kinds" | tail -2
echo "command: AFAM_GPU_POOL_MODELS=POOL afam replay FILE --trajectory $(basename "$TRAJ") --size $SIZE,$SIZE --device $DEVICE --gpu-budget-mb $GPU_MB --lod screen --cold --cache-bytes $((CACHE_MB * 1000000)) --cache-blocks 0 --frames $FRAMES --models MODELS"
echo
echo "| models | GPU pool | run | median frame ms | p95 ms | median caching ms | misses / frame | cache peak MB | GPU uploads / frame | frames on the CPU |"
echo "|---|---|---|---|---|---|---|---|---|---|"
column() {  # mean of a CSV column
  awk -F, -v name="$1" 'NR == 1 { for (i = 1; i <= NF; ++i) if ($i == name) c = i; next }
    c { m += $c; n++ } END { printf "%.1f", n ? m / n : 0 }' "$2"
}
for run in 1 2; do
  for variant in $VARIANTS; do
    models="${variant%%:*}"
    pool=auto
    [[ $variant == *:* ]] && pool="${variant#*:}"
    csv="$work/replay_${models}_${pool}_$run.csv"
    out=$(AFAM_GPU_POOL_MODELS="$pool" "$AFAM" replay "$file" --trajectory "$TRAJ" \
      --size "$SIZE,$SIZE" --device "$DEVICE" --gpu-budget-mb "$GPU_MB" --lod screen --cold \
      --cache-bytes "$((CACHE_MB * 1000000))" --cache-blocks 0 --frames "$FRAMES" \
      --models "$models" --quiet --csv "$csv" 2>&1)
    on_cpu=$(awk -F, 'NR == 1 { for (i = 1; i <= NF; ++i) if ($i == "on_gpu") c = i; next }
      c && $c == 0 { n++ } END { print n + 0 }' "$csv")
    echo "| $models | $pool | $run | $(value median_latency_ms "$out") | $(value p95_latency_ms "$out") | $(value median_caching_ms "$out") | $(column misses "$csv") | $(awk -v b="$(value cache_peak_bytes "$out")" 'BEGIN { printf "%.1f", b / 1e6 }') | $(column gpu_uploads "$csv") | $on_cpu |"
  done
done
