#!/usr/bin/env bash
# SPDX-License-Identifier: BSD-3-Clause
# Two builds of `afam encode` side by side in one run: BASE (a build of an earlier commit) and NEW,
# on the repository's corpus (Testing/Data/volumes) at relative RMSE 1e-2 and 1e-3 and pointwise
# 1e-3, and on the head MRI made large with noise at two levels (EXTRA_DIMS, noise 2.5 and 6) at
# 1e-2; THREADS threads (default 1: per-thread speed), REPS runs of each build interleaved, the
# median seconds of each. Prints, per set, the summed bytes of each build (NEW's must stay within
# 1% of BASE's) and the median seconds and their ratio.
#
# usage: Testing/Benchmarks/encode_ab.sh NEW_AFAM BASE_AFAM
# Env: REPS (default 3), THREADS (default 1), EXTRA_DIMS (default 150,194,132), WORK (default a
#      temporary folder).
set -euo pipefail
here="$(cd "$(dirname "$0")/../.." && pwd)"
NEW="$1"
BASE="$2"
REPS="${REPS:-3}"
THREADS="${THREADS:-1}"
EXTRA_DIMS="${EXTRA_DIMS:-150,194,132}"
work="${WORK:-$(mktemp -d)}"
mkdir -p "$work"
[[ -n ${WORK:-} ]] || trap 'rm -rf "$work"' EXIT
head="$here/Testing/Data/volumes/HeadMRVolume_48x62x42_uint8.raw"
for noise in 2.5 6; do
  raw="$work/head_n${noise}_${EXTRA_DIMS//,/x}_uint8.raw"
  [[ -f $raw ]] || "$NEW" enlarge "$head" "$raw" --dims "$EXTRA_DIMS" --noise "$noise" >/dev/null
done
corpus=("$here"/Testing/Data/volumes/*.raw)
# One pass of a build over a set: prints "bytes seconds".
pass() {  # exe, bound arguments..., -- files...
  local exe="$1" bytes=0 seconds=0 out
  shift
  local bound=()
  while [[ $1 != -- ]]; do bound+=("$1"); shift; done
  shift
  for f in "$@"; do
    out="$("$exe" encode "$f" "$work/out.afam" "${bound[@]}" --threads "$THREADS")"
    bytes=$((bytes + $(grep -o 'bytes_out=[0-9]*' <<<"$out" | cut -d= -f2)))
    seconds="$(awk -v a="$seconds" -v b="$(grep -o '^seconds=[0-9.]*' <<<"$out" | cut -d= -f2)" \
      'BEGIN { print a + b }')"
  done
  echo "$bytes $seconds"
}
median() { sort -g | awk '{ v[NR] = $1 } END { print (NR % 2) ? v[(NR + 1) / 2] : (v[NR / 2] + v[NR / 2 + 1]) / 2 }'; }
row() {  # label, bound arguments..., -- files...
  local label="$1" nb bb ts=() tb=()
  shift
  for _ in $(seq "$REPS"); do
    read -r bb s <<<"$(pass "$BASE" "$@")"
    tb+=("$s")
    read -r nb s <<<"$(pass "$NEW" "$@")"
    ts+=("$s")
  done
  local mb mn
  mb="$(printf '%s\n' "${tb[@]}" | median)"
  mn="$(printf '%s\n' "${ts[@]}" | median)"
  printf '| %s | %d | %d | %.4f | %.3f | %.3f | %.2fx |\n' "$label" "$bb" "$nb" \
    "$(awk -v a="$nb" -v b="$bb" 'BEGIN { print a / b }')" "$mb" "$mn" \
    "$(awk -v a="$mb" -v b="$mn" 'BEGIN { print a / b }')"
}
echo "machine: $(nproc) cores, load $(cut -d' ' -f1-3 /proc/loadavg); threads $THREADS, medians of $REPS"
echo
echo "| set | BASE bytes | NEW bytes | NEW/BASE bytes | BASE s | NEW s | speed-up |"
echo "|---|---|---|---|---|---|---|"
row "corpus, RMSE 1e-2" --error-bound 1e-2 --relative -- "${corpus[@]}"
row "corpus, RMSE 1e-3" --error-bound 1e-3 --relative -- "${corpus[@]}"
row "corpus, max error 1e-3" --max-error 1e-3 -- "${corpus[@]}"
row "head made large $EXTRA_DIMS, noise 2.5, 1e-2" --error-bound 1e-2 --relative -- \
  "$work/head_n2.5_${EXTRA_DIMS//,/x}_uint8.raw"
row "head made large $EXTRA_DIMS, noise 6, 1e-2" --error-bound 1e-2 --relative -- \
  "$work/head_n6_${EXTRA_DIMS//,/x}_uint8.raw"
