#!/usr/bin/env bash
# SPDX-License-Identifier: BSD-3-Clause
# A run of time steps in one file against one file per step and ZFP per step (issue 28's size
# bars), on three generated Gray-Scott series (`afam simulate`), printed as a markdown table:
#   slow      settled patterns saved every 20 iterations (warm-up 6000): a slowly evolving run
#   fast      young patterns saved every 20 iterations (warm-up 1000): they move everywhere
#   unrelated every step from another seed: steps that share nothing
#   dir:PATH  a series of your own: the files PATH/*.raw, in sorted order, as its steps (names as
#             `afam encode` reads them, e.g. name_0000_XxYxZ_float32.raw; Testing/Benchmarks/
#             vti_to_raw.py makes them from .vti steps); its row is named after PATH's last part
# For each series and relative RMSE bound E: `afam encode STEPS... run.afam --error-bound E
# --relative` (E relative to the whole run's range; the bound in data units is printed), every
# step checked with `afam verify run.afam --against STEPS...`; one `afam encode` per step at the
# same bound in data units; ZFP fixed-accuracy per step tuned by `afam compare-codecs` to the RMSE
# a one-step file reaches at E relative to that step's range. Bytes are whole files.
#
# usage: Testing/Benchmarks/run_size.sh [AFAM_EXE]
# Env: DIMS (default 64,64,64), STEPS (40), BOUNDS ("1e-2 1e-3"), SERIES ("slow fast unrelated";
#      dir:PATH entries mix with them), KEY_INTERVAL (passed as --key-interval when set),
#      WORK (default a temporary folder, removed afterwards; when set, each row's `afam encode`
#      and `afam verify` output stays there as SERIES/encode_E.txt and SERIES/verify_E.txt).
set -euo pipefail
here="$(cd "$(dirname "$0")/../.." && pwd)"
AFAM="${1:-$here/build/Apps/afam}"
DIMS="${DIMS:-64,64,64}"
STEPS="${STEPS:-40}"
BOUNDS="${BOUNDS:-1e-2 1e-3}"
SERIES="${SERIES:-slow fast unrelated}"
[[ -x $AFAM ]] || { echo "run_size.sh: no afam executable at $AFAM" >&2; exit 1; }
work="${WORK:-$(mktemp -d)}"
[[ -n ${WORK:-} ]] || trap 'rm -rf "$work"' EXIT
mkdir -p "$work"

generate() {  # series folder
  local s=$1 dir=$2
  mkdir -p "$dir"
  case $s in
    slow) "$AFAM" simulate "$dir/gs" --dims "$DIMS" --steps "$STEPS" --every 20 --warmup 6000 >/dev/null ;;
    fast) "$AFAM" simulate "$dir/gs" --dims "$DIMS" --steps "$STEPS" --every 20 --warmup 1000 >/dev/null ;;
    unrelated)
      for ((k = 0; k < STEPS; ++k)); do
        "$AFAM" simulate "$dir/seed$k" --dims "$DIMS" --steps 1 --warmup 500 --seed $((k + 1)) >/dev/null
        mv "$dir"/seed${k}_0000_*.raw "$dir/$(printf 'gs_%04d' "$k")_${DIMS//,/x}_float32.raw"
      done ;;
    *) echo "run_size.sh: unknown series $s" >&2; exit 1 ;;
  esac
}

key=()
[[ -z ${KEY_INTERVAL:-} ]] || key=(--key-interval "$KEY_INTERVAL")
label() { case $1 in dir:*) basename "${1#dir:}" ;; *) echo "$1" ;; esac; }

echo "machine: $(nproc) cores, $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ //')"
generated=0
for s in $SERIES; do
  case $s in
    dir:*)
      d=${s#dir:}
      files=("$d"/*.raw)
      [[ -e ${files[0]} ]] || { echo "run_size.sh: no .raw files in $d" >&2; exit 1; }
      echo "series: $(label "$s"): ${#files[@]} steps from $d ($(basename "${files[0]}") ...); afam $AFAM" ;;
    *)
      ((generated == 1)) || echo "series: Gray-Scott $DIMS, $STEPS steps; afam $AFAM"
      generated=1 ;;
  esac
done
[[ -z ${KEY_INTERVAL:-} ]] || echo "key interval: $KEY_INTERVAL"
echo
echo "| series | bound | run file | one file per step | run / per-step | ZFP per step | residual blocks | reference blocks | worst step rmse / bound | encode s |"
echo "|---|---|---|---|---|---|---|---|---|---|"
for s in $SERIES; do
  case $s in
    dir:*)
      dir="$work/$(label "$s")"
      mkdir -p "$dir"
      steps=("${s#dir:}"/*.raw) ;;
    *)
      dir="$work/$s"
      generate "$s" "$dir"
      steps=("$dir"/gs_*.raw) ;;
  esac
  for E in $BOUNDS; do
    t0=$(date +%s.%N)
    "$AFAM" encode "${steps[@]}" "$work/run.afam" --error-bound "$E" --relative "${key[@]}" >"$work/enc.txt"
    t1=$(date +%s.%N)
    bound=$(sed -n 's/.* bound=\([^ ]*\) .*/\1/p' "$work/enc.txt" | tail -1)
    residuals=$(grep -o 'residuals=[0-9]*' "$work/enc.txt" | cut -d= -f2 | paste -sd+ | bc)
    references=$(grep '^step=' "$work/enc.txt" | grep -o 'references=[0-9]*' | cut -d= -f2 | paste -sd+ | bc)
    "$AFAM" verify "$work/run.afam" --against "${steps[@]}" >"$work/verify.txt" ||
      { echo "run_size.sh: a step breaks the bound ($s, $E)" >&2; cat "$work/verify.txt" >&2; exit 1; }
    [[ -z ${WORK:-} ]] || cp "$work/enc.txt" "$dir/encode_$E.txt"
    [[ -z ${WORK:-} ]] || cp "$work/verify.txt" "$dir/verify_$E.txt"
    worst=$(sed -n 's/.* rmse=\([^ ]*\) .*/\1/p' "$work/verify.txt" | sort -g | tail -1)
    run=$(stat -c %s "$work/run.afam")
    per=0
    for f in "${steps[@]}"; do
      "$AFAM" encode "$f" "$work/one.afam" --error-bound "$bound" --quiet
      per=$((per + $(stat -c %s "$work/one.afam")))
    done
    "$AFAM" compare-codecs "${steps[@]}" --bounds "$E" --csv "$work/cc.csv" --work "$work" >/dev/null
    zfp=$(awk -F, '$5 == "zfp" { s += $7 } END { print s }' "$work/cc.csv")
    printf '| %s | %s | %d B | %d B | %.2fx smaller | %d B | %d | %d | %.4f | %.1f |\n' "$(label "$s")" "$E" \
      "$run" "$per" "$(echo "$per / $run" | bc -l)" "$zfp" "$residuals" "$references" \
      "$(echo "$worst / $bound" | bc -l)" "$(echo "$t1 - $t0" | bc -l)"
  done
done
