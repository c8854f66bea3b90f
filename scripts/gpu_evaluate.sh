#!/usr/bin/env bash
# SPDX-License-Identifier: BSD-3-Clause
# The evaluation report at full size on the GPU machine: scripts/evaluate.sh --full with
# AFAM_DEVICE=gpu (replays and quality renders on the CUDA ray caster) and every core.
#   scripts/gpu_evaluate.sh [WAIT_SECONDS]      (default 540)
# The device tool stops a command after 10 minutes, so the report runs in its own process session
# (setsid) and this script waits for it at most WAIT_SECONDS; call it again to go on waiting. The
# first call starts it; a call after it ended packs the report (CSVs, plots, summary.md,
# commands.log; not the images) into $OUT/evaluation_full.tar.gz and prints summary.md.
# zstd headers, ZFP and fpzip: the GPU machine lacks them; see scripts/gpu_deps.sh.
# Corpus volumes: the repository's Testing/Data/volumes. Trajectories: $AFAM_TRAJECTORIES, else
# $AFAM_GPU_DATA/trajectories or gpu-data/trajectories (carried), else generated exploration walks
# (evaluate.sh says which, in its log and summary.md).
# Scratch: $AFAM_EVAL_WORK (default /tmp/afam_eval_full). AFAM_EVAL_SIZE=smoke|small|full (default
# full) picks evaluate.sh's sizes (smoke: a check of this script's plumbing).
set -uo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
wait_s="${1:-540}"
size="${AFAM_EVAL_SIZE:-full}"
work="${AFAM_EVAL_WORK:-/tmp/afam_eval_full}"
mkdir -p "$work"
carried="${AFAM_GPU_DATA:-$root/gpu-data}/trajectories"
[ -n "${AFAM_TRAJECTORIES:-}" ] || [ ! -d "$carried" ] || export AFAM_TRAJECTORIES="$carried"

if [ ! -f "$work/started" ]; then
  source "$root/scripts/gpu_deps.sh"
  date +%s >"$work/started"
  echo "GPU: $(nvidia-smi --query-gpu=name,driver_version --format=csv,noheader 2>/dev/null | head -1)"
  echo "starting: scripts/evaluate.sh --$size $work/report (AFAM_DEVICE=gpu, AFAM_JOBS=$(nproc))"
  AFAM_DEVICE=gpu AFAM_JOBS="$(nproc)" AFAM_PYTHON="${AFAM_PYTHON:-$(command -v python3)}" AFAM_BUILD="$work/build" \
    setsid bash -c "'$root/scripts/evaluate.sh' --$size '$work/report' >'$work/run.log' 2>&1; echo \$? >'$work/rc'" \
    </dev/null >/dev/null 2>&1 &
fi

t0=$(date +%s)
shown=0
while [ ! -f "$work/rc" ] && [ $(( $(date +%s) - t0 )) -lt "$wait_s" ]; do
  sleep 5
  n=$(wc -l <"$work/run.log" 2>/dev/null || echo 0)
  if [ "$n" -gt "$shown" ]; then sed -n "$((shown + 1)),${n}p" "$work/run.log"; shown=$n; fi
done
elapsed=$(( $(date +%s) - $(cat "$work/started") ))
if [ ! -f "$work/rc" ]; then
  echo "still running after ${elapsed} s; last log lines:"
  tail -3 "$work/run.log" 2>/dev/null
  tail -2 "$work/report/commands.log" 2>/dev/null
  exit 0
fi
rc=$(cat "$work/rc")
echo "evaluate.sh --$size ended with rc=$rc after ${elapsed} s"
[ "$rc" -eq 0 ] || tail -30 "$work/run.log"
if [ -d "$work/report" ] && [ -n "${OUT:-}" ]; then
  tar -C "$work" -czf "$OUT/evaluation_full.tar.gz" --exclude=report/images --exclude=report/work report run.log
  echo "packed: $OUT/evaluation_full.tar.gz ($(du -h "$OUT/evaluation_full.tar.gz" | cut -f1))"
fi
cat "$work/report/summary.md" 2>/dev/null
exit "$rc"
