#!/usr/bin/env bash
# SPDX-License-Identifier: BSD-3-Clause
# afam encode --device cpu against --device gpu (the NCP searches asked ahead of the GPU's
# least-squares residuals) side by side in one run, on the repository's head MRI made large with
# `afam enlarge`, at relative RMSE 1e-2: REPS runs of each interleaved, the median seconds of each
# and their ratio, fits and residuals asked ahead, and whether the two files are the same bytes.
#
# usage: Testing/Benchmarks/encode_gpu.sh AFAM
# Env: DIMS (default 602,740,632), NOISE (2.5), TISSUE_NOISE (NOISE's; NOISE=2 TISSUE_NOISE=3
#      DETAIL=12 makes a real T1 MRI's bytes and blocks, README), DETAIL (0), THREADS (0: every
#      core), REPS (3), WORK (default a temporary folder).
set -euo pipefail
here="$(cd "$(dirname "$0")/../.." && pwd)"
AFAM="$1"
DIMS="${DIMS:-602,740,632}"
NOISE="${NOISE:-2.5}"
DETAIL="${DETAIL:-0}"
TISSUE_NOISE="${TISSUE_NOISE:-$NOISE}"
THREADS="${THREADS:-0}"
REPS="${REPS:-3}"
work="${WORK:-$(mktemp -d)}"
mkdir -p "$work"
[[ -n ${WORK:-} ]] || trap 'rm -rf "$work"' EXIT
raw="$work/head_n${NOISE}_t${TISSUE_NOISE}_d${DETAIL}_${DIMS//,/x}_uint8.raw"
[[ -f $raw ]] || "$AFAM" enlarge "$here/Testing/Data/volumes/HeadMRVolume_48x62x42_uint8.raw" \
  "$raw" --dims "$DIMS" --noise "$NOISE" --tissue-noise "$TISSUE_NOISE" --detail "$DETAIL" >/dev/null
cat "$raw" >/dev/null  # in the page cache, as the issue's bar says
declare -A seconds
for rep in $(seq "$REPS"); do
  for dev in cpu gpu; do
    out="$("$AFAM" encode "$raw" "$work/$dev.afam" --error-bound 1e-2 --relative \
      --threads "$THREADS" --device "$dev")"
    seconds[$dev]+="$(grep -o '^seconds=[0-9.]*' <<<"$out" | cut -d= -f2) "
    [[ $rep == 1 ]] && echo "$dev: $(sed -n 3p <<<"$out")" &&
      grep -o 'level [0-9]*:.*residual_seconds=[0-9.]*' <<<"$out" |
      sed -E 's/ (searched|complex|refits|exact|max_rmse|max_error|bound)=[^ ]*//g; s/^/  /'
  done
  cmp -s "$work/cpu.afam" "$work/gpu.afam" && same=yes || same=NO
done
median() { tr ' ' '\n' | grep . | sort -g | awk '{a[NR]=$1} END {print a[int((NR+1)/2)]}'; }
c=$(median <<<"${seconds[cpu]}")
g=$(median <<<"${seconds[gpu]}")
echo "encode ${DIMS} noise ${NOISE} tissue ${TISSUE_NOISE} detail ${DETAIL}, threads ${THREADS}: cpu median ${c} s (${seconds[cpu]}), gpu median ${g} s (${seconds[gpu]}), cpu/gpu $(awk "BEGIN {printf \"%.2f\", $c / $g}"); same bytes: ${same}; $(stat -c %s "$work/gpu.afam") bytes"
