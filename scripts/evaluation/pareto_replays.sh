#!/usr/bin/env bash
# SPDX-License-Identifier: BSD-3-Clause
# Latency for the evaluation's Pareto bar, measured so that CPU noise cannot decide it: DS, FAM and
# Adaptive-FAM replayed side by side (no prefetching, cold page cache, emulated storage), REPS
# rounds, the order of the methods rotated every round so that no method always runs first or
# last. Called by scripts/evaluate.sh; can be re-run on its own:
#   scripts/evaluation/pareto_replays.sh AFAM OUTCSV_DIR TRAJ_DIR FRAMES IMG SD MBPS THREADS REPS \
#       DS=ds.afam FAM=fam.afam Adaptive-FAM=adaptive.afam
# Writes OUTCSV_DIR/pareto_replays.csv (one row per replay) and OUTCSV_DIR/pareto/*.csv (one row
# per point of view); AFAM_DEVICE=gpu replays on the CUDA ray caster. report.py pools the points of view of every round (medians, paired
# per-view differences).
set -euo pipefail
AFAM=$1 DIR=$2 TRAJ=$3 FRAMES=$4 IMG=$5 SD=$6 MBPS=$7 THREADS=$8 REPS=$9
shift 9
METHODS=() FILES=()
for kv in "$@"; do METHODS+=("${kv%%=*}"); FILES+=("${kv#*=}"); done
mkdir -p "$DIR/pareto"
SUM=$DIR/pareto_replays.csv
echo "round,slot,trajectory,method,file,median_latency_ms,median_caching_ms,median_render_ms,miss_rate,csv" > "$SUM"
kv() { grep -o "$1=[^ ]*" | tail -1 | cut -d= -f2; }
n=${#METHODS[@]}
for ((r = 1; r <= REPS; r++)); do
  for traj in user_1 user_2; do
    for ((s = 0; s < n; s++)); do
      i=$(( (s + r - 1) % n ))
      meth=${METHODS[$i]} f=${FILES[$i]}
      csv=$DIR/pareto/replay_${traj}_${meth}_r$r.csv
      o=$("$AFAM" replay "$f" --trajectory "$TRAJ/$traj.dat" --frames "$FRAMES" --size "$IMG,$IMG" \
            --sample-distance "$SD" --cache-blocks 200 --cold --storage-mbps "$MBPS" --prefetch none \
            --threads "$THREADS" --device "${AFAM_DEVICE:-cpu}" --quiet --csv "$csv" 2>&1 | tail -1)
      echo "$r,$s,$traj,$meth,$f,$(echo "$o" | kv median_latency_ms),$(echo "$o" | kv median_caching_ms),$(echo "$o" | kv median_render_ms),$(echo "$o" | kv miss_rate),$csv" >> "$SUM"
    done
  done
done
