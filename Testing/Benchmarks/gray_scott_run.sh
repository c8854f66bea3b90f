#!/usr/bin/env bash
# SPDX-License-Identifier: BSD-3-Clause
# Issue 42's run bar: a 40-step Gray-Scott run made 512^3 float32 (21.5 GB), encoded as one run.
# Simulates at 128^3 (`afam simulate`, settled patterns saved every 20 iterations), makes each step
# 512^3 with fixed noise (`afam enlarge --noise 0.008 --seed 9`: the same noise field every step),
# then times `afam encode STEPS... run.afam --error-bound 1e-2 --relative --device D` once per
# entry of DEVS (wall clock), printing each run's summary line, the seconds of every step, and
# whether every file has the same bytes as the first.
#
# usage: Testing/Benchmarks/gray_scott_run.sh [AFAM_EXE]
# Env: WORK (default /dev/shm/afam_gray_scott: 21.5 GB of steps; kept, so that a second call skips
#      the simulation and the enlargement), DEVS (default "gpu cpu"), DIMS (default 512,512,512),
#      STEPS (default 40), TIMEOUT (seconds per encode, default 600).
set -uo pipefail
afam=${1:-build/Apps/afam}
work=${WORK:-/dev/shm/afam_gray_scott}
dims=${DIMS:-512,512,512}
steps=${STEPS:-40}
mkdir -p "$work"
if ! ls "$work"/big_*_float32.raw > /dev/null 2>&1; then
  t0=$(date +%s.%N)
  "$afam" simulate "$work/gs" --dims 128,128,128 --steps "$steps" --every 20 --warmup 6000 \
    --seeds 48 > "$work/simulate.log" 2>&1 || { tail -3 "$work/simulate.log"; exit 1; }
  k=0
  for f in "$work"/gs_*_128x128x128_float32.raw; do
    out="$work/big_$(printf %02d $k)_${dims//,/x}_float32.raw"
    "$afam" enlarge "$f" "$out" --dims "$dims" --noise 0.008 --seed 9 > /dev/null ||
      { echo "enlarge $f failed"; exit 1; }
    rm "$f"
    k=$((k + 1))
  done
  echo "made $k steps of $dims in $(awk "BEGIN{print $(date +%s.%N) - $t0}") s ($(du -sh "$work" | cut -f1))"
fi
first=""
n=0
for dev in ${DEVS:-gpu cpu}; do
  n=$((n + 1))
  out="$work/run_${dev}_$n.afam"
  t0=$(date +%s.%N)
  timeout "${TIMEOUT:-600}" "$afam" encode "$work"/big_*_float32.raw "$out" --error-bound 1e-2 \
    --relative --device "$dev" > "$work/encode_$n.log" 2> "$work/encode_$n.err"
  rc=$?
  echo "encode --device $dev: rc=$rc wall $(awk "BEGIN{print $(date +%s.%N) - $t0}") s $(tail -1 "$work/encode_$n.err")"
  grep -E "^steps=" "$work/encode_$n.log"
  echo "  step seconds: $(awk -F'seconds=' '/^step=/{printf "%s ", $2}' "$work/encode_$n.log")"
  [ "$rc" = 0 ] || continue
  if [ -z "$first" ]; then
    first=$out
  elif cmp -s "$first" "$out"; then
    echo "  the same bytes as $(basename "$first") ($(stat -c %s "$out") B)"
  else
    echo "  DIFFERENT bytes from $(basename "$first")"
  fi
done
