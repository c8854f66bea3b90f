#!/usr/bin/env bash
# SPDX-License-Identifier: BSD-3-Clause
# The encoding table: Marschner-Lobb 128/256/512 and every corpus volume, Adaptive-FAM with the
# fast search against the exhaustive in-level encoder (the paper's loop) measured in the same run,
# fast == exhaustive check (byte-identical files), sizes against the paper's layout, peak RSS.
#
# usage: Testing/Benchmarks/encode_table.sh [AFAM_EXE] [WORK_DIR] [THREADS]
#   AFAM_EXE  default build-enc/Apps/afam;  WORK_DIR default /tmp/afam_encode_table;  THREADS 2
# Env: SIZES="128 256 512" (ML sizes), EXHAUSTIVE_MAX=512 (largest ML size with the exhaustive
# baseline), CORPUS_BOUNDS="1e-3 1e-2" (relative bounds for the corpus).
set -euo pipefail
here="$(cd "$(dirname "$0")/../.." && pwd)"
AFAM="${1:-$here/build-enc/Apps/afam}"
WORK="${2:-/tmp/afam_encode_table}"
T="${3:-2}"
SIZES="${SIZES:-128 256 512}"
EXHAUSTIVE_MAX="${EXHAUSTIVE_MAX:-512}"
CORPUS_BOUNDS="${CORPUS_BOUNDS:-1e-3 1e-2}"
DATA="${DATA:-$here/Testing/Data/volumes}"
mkdir -p "$WORK"
TIME=/usr/bin/time

field() { grep -o "$1=[^ ]*" <<<"$2" | head -1 | cut -d= -f2; }

# encode IN OUT ARGS... -> sets OUT_TEXT and RSS_KB
encode() {
  local in="$1" out="$2"; shift 2
  OUT_TEXT="$("$TIME" -f "maxrss_kb=%M" "$AFAM" encode "$in" "$out" --threads "$T" "$@" 2>"$WORK/time.txt")"
  RSS_KB="$(grep -o 'maxrss_kb=[0-9]*' "$WORK/time.txt" | cut -d= -f2)"
}

hist() {  # NCP histogram per level, compact
  grep '^level ' <<<"$1" | sed -E 's/^level ([0-9]+):.* ncp: (.*)$/L\1{\2}/' | tr '\n' ' '
}

echo "machine: $(nproc) cores, $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ //'), load $(cut -d' ' -f1-3 /proc/loadavg)"
echo "afam: $AFAM  threads: $T"
echo
echo "### Marschner-Lobb (4 levels, 16 blocks, p = 2, absolute RMSE bound 1e-4)"
echo
echo "| size | encoder | wall s | CPU s | M voxels/s/thread (wall) | M voxels/CPU-s | fits | ratio (float32) | file bytes | paper-layout bytes | max block RMSE | peak RSS MB | NCP histogram per level |"
echo "|---|---|---|---|---|---|---|---|---|---|---|---|---|"
for n in $SIZES; do
  raw="$WORK/ml_${n}x${n}x${n}_float32.raw"
  rm -f "$WORK"/ml${n}_*.afam
  [ -f "$raw" ] || "$AFAM" ml --size "$n" "$raw" >/dev/null
  runs="adaptive:fast inlevel:fast"
  [ "$n" -le "$EXHAUSTIVE_MAX" ] && runs="$runs inlevel:exhaustive"
  for r in $runs; do
    mode="${r%%:*}"; search="${r##*:}"
    out="$WORK/ml${n}_${mode}_${search}.afam"
    encode "$raw" "$out" --mode "$mode" --search "$search" --error-bound 1e-4
    t="$OUT_TEXT"
    vps=$(field voxels_per_s_per_thread "$t"); vpc=$(field voxels_per_cpu_s "$t")
    printf "| %s^3 | %s %s | %s | %s | %.2f | %.2f | %s | %s | %s | %s | %s | %.0f | %s |\n" "$n" "$mode" "$search" \
      "$(field seconds "$t")" "$(field cpu_seconds "$t")" "$(awk "BEGIN{print $vps/1e6}")" "$(awk "BEGIN{print $vpc/1e6}")" \
      "$(field fits "$t")" "$(field ratio_float32 "$t")" "$(field bytes_out "$t")" "$(field paper_layout_bytes "$t")" \
      "$(field max_block_rmse "$t")" "$(awk "BEGIN{print $RSS_KB/1024}")" "$(hist "$t")"
  done
  if [ -f "$WORK/ml${n}_inlevel_exhaustive.afam" ]; then
    if cmp -s "$WORK/ml${n}_inlevel_fast.afam" "$WORK/ml${n}_inlevel_exhaustive.afam"; then
      echo "| ${n}^3 | fast == exhaustive | byte-identical files: same NCP* on all blocks | | | | | | | | | | |"
    else
      echo "| ${n}^3 | fast != exhaustive | FILES DIFFER | | | | | | | | | | |"
    fi
  fi
  v="$("$AFAM" verify "$WORK/ml${n}_adaptive_fast.afam" --against "$raw")"
  echo "| ${n}^3 | verify adaptive | $(grep -o 'rmse=[^ ]*' <<<"$v") $(grep -o 'max_error=[^ ]*' <<<"$v") (whole finest level vs raw) | | | | | | | | | | |"
done
echo
echo "### Corpus ($DATA; 4 levels, 16 blocks, p = 2, relative RMSE bound)"
echo
echo "| volume | bound | encoder | wall s | fits | fast==exhaustive | ratio (original type) | ratio (float32) | file bytes | paper-layout bytes | max block RMSE | NCP histogram per level |"
echo "|---|---|---|---|---|---|---|---|---|---|---|---|"
for f in "$DATA"/*.raw; do
  name="$(basename "$f" .raw)"
  for b in $CORPUS_BOUNDS; do
    encode "$f" "$WORK/${name}_fast.afam" --mode adaptive --search fast --error-bound "$b" --relative
    tf="$OUT_TEXT"
    encode "$f" "$WORK/${name}_ilf.afam" --mode inlevel --search fast --error-bound "$b" --relative
    encode "$f" "$WORK/${name}_ile.afam" --mode inlevel --search exhaustive --error-bound "$b" --relative
    te="$OUT_TEXT"
    same=no; cmp -s "$WORK/${name}_ilf.afam" "$WORK/${name}_ile.afam" && same=yes
    printf "| %s | %s | adaptive fast (exhaustive in-level: %s s, %s fits) | %s | %s | %s | %s | %s | %s | %s | %s | %s |\n" "$name" "$b" \
      "$(field seconds "$te")" "$(field fits "$te")" "$(field seconds "$tf")" "$(field fits "$tf")" "$same" \
      "$(field ratio "$tf")" "$(field ratio_float32 "$tf")" "$(field bytes_out "$tf")" "$(field paper_layout_bytes "$tf")" \
      "$(field max_block_rmse "$tf")" "$(hist "$tf")"
  done
done
