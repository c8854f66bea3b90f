#!/usr/bin/env bash
# SPDX-License-Identifier: BSD-3-Clause
# Encoding under mpirun: Apps/pvbatch/afam_encode.py on a Marschner-Lobb raw volume, on one pvbatch
# process (1 and 2 threads) and on 2 ranks of 1 thread each; wall time and peak RSS of every rank
# (/usr/bin/time: the whole pvbatch process, ParaView's start included) and the encode's own wall
# time (afam_encode.py's seconds=), the bytes of the files, and whether the 2-rank file is byte-identical to the
# one-process file. A run on a 16^3 volume gives pvbatch's own footprint (ParaView + plugin); a
# reference run on the ranks (read_piece.py: each rank reads its piece of the volume, then a 16^3
# Wavelet is encoded so that the encoder's code is resident) gives what the encode of the volume
# adds on each rank beside its piece, printed last beside one z-row of finest blocks.
#
# usage: Testing/Benchmarks/encode_mpi.sh [BUILD_DIR] [WORK_DIR] [SIZE]
#   BUILD_DIR default build;  WORK_DIR default /tmp/afam_encode_mpi;  SIZE default 256
# Env: ENCODE_OPTIONS (default "--levels 4 --blocks 16 --error-bound 1e-4"), RANKS (default 2),
# MPIRUN_OPTIONS (e.g. "--mca mpi_yield_when_idle 1": waiting ranks give up their core),
# ONLY_RANKS=1 (skip the one-process runs; the comparison then uses the files left by a full run),
# HEAPTRACK=1 (run every process under heaptrack and print its peak heap: what was allocated and
# not yet freed at the worst moment, free of the code pages and freed memory that peak RSS counts;
# the runs are then 10-20x slower, and their times mean nothing).
set -euo pipefail
here="$(cd "$(dirname "$0")/../.." && pwd)"
BUILD="$(cd "${1:-$here/build}" && pwd)"
WORK="${2:-/tmp/afam_encode_mpi}"
SIZE="${3:-256}"
RANKS="${RANKS:-2}"
read -r -a OPTIONS <<<"${ENCODE_OPTIONS:---levels 4 --blocks 16 --error-bound 1e-4}"
PLUGIN="$BUILD/lib/paraview-5.11/plugins/AdaptiveFAM/AdaptiveFAM.so"
SCRIPT="$here/Apps/pvbatch/afam_encode.py"
read -r -a MPIRUN_EXTRA <<<"${MPIRUN_OPTIONS:-}"
MPIRUN=(mpirun --oversubscribe "${MPIRUN_EXTRA[@]}")
if [ "$(id -u)" = 0 ]; then MPIRUN+=(--allow-run-as-root); fi
mkdir -p "$WORK"
cd "$WORK"
volume="ml_${SIZE}x${SIZE}x${SIZE}_float32.raw"
[ -f "$volume" ] || "$BUILD/Apps/afam" ml --size "$SIZE" "$volume" >/dev/null
[ -f ml_16x16x16_float32.raw ] || "$BUILD/Apps/afam" ml --size 16 ml_16x16x16_float32.raw >/dev/null

declare -A PEAK  # label:rank -> peak RSS (KiB), or peak heap under HEAPTRACK
# run LABEL RANKS THREADS IN OUT: one line per rank with wall seconds and peak RSS; OUT "reference":
# the reference run (read_piece.py) instead of an encode of IN
run() {
  local label="$1" ranks="$2" threads="$3" in="$4" out="$5"
  local encode=(pvbatch "$SCRIPT" --plugin "$PLUGIN" "$in" "$out" --threads "$threads" "${OPTIONS[@]}")
  if [ "$out" = reference ]; then
    encode=(pvbatch "$here/Testing/Benchmarks/read_piece.py" "$in" --plugin "$PLUGIN")
  else
    rm -f "$out"
  fi
  if [ -n "${HEAPTRACK:-}" ]; then
    encode=(sh -c 'r=${OMPI_COMM_WORLD_RANK:-0}; heaptrack -o "$0.r$r" "$@" >/dev/null 2>&1
                   heaptrack_print -f "$0.r$r.zst" --print-peaks 0 --print-allocators 0 |
                     sed -n "s/^peak heap memory consumption: /heap rank=$r peak_heap=/p"; rm -f "$0.r$r.zst"' \
            "$WORK/heaptrack.$label" "${encode[@]}")
  fi
  local timed=(sh -c '/usr/bin/time -f "rank=${OMPI_COMM_WORLD_RANK:-0} wall_s=%e cpu_s=%U+%S peak_rss_kb=%M" "$@" 2>&1 |
                      grep -E "^rank=|seconds=|^heap "' timed "${encode[@]}")
  if [ "$ranks" -gt 1 ]; then timed=("${MPIRUN[@]}" -np "$ranks" "${timed[@]}"); fi
  local text
  text="$(xvfb-run -a -s "-screen 0 640x480x24 -noreset" "${timed[@]}")"
  local line rank
  if [ -n "${HEAPTRACK:-}" ]; then
    while read -r line; do
      rank="$(sed 's/.*rank=\([0-9]*\).*/\1/' <<<"$line")"
      PEAK["$label:$rank"]="$(numfmt --from=si "$(sed 's/.*peak_heap=\([0-9.]*[KMG]\?\).*/\1/' <<<"$line")")"
      echo "$label $line"
    done < <(grep "^heap " <<<"$text" | sort)
  else
    grep "^rank=" <<<"$text" | sort | sed "s/^/$label process /"
    while read -r line; do
      rank="$(sed 's/^rank=\([0-9]*\).*/\1/' <<<"$line")"
      PEAK["$label:$rank"]="$(( $(sed 's/.*peak_rss_kb=\([0-9]*\).*/\1/' <<<"$line") * 1024 ))"
    done < <(grep "^rank=" <<<"$text")
  fi
  # the encoder's own time (filter + writer, after the reader): afam_encode.py's summary
  [ "$out" = reference ] || echo "$label encode_s=$(grep -o "seconds=[0-9.]*" <<<"$text" | cut -d= -f2) bytes=$(stat -c %s "$out")"
}

echo "volume $volume ($(stat -c %s "$volume") bytes), options ${OPTIONS[*]}, $(nproc) cores, load $(cut -d' ' -f1 /proc/loadavg)"
if [ -z "${ONLY_RANKS:-}" ]; then
  run "footprint(16^3,1proc)" 1 1 ml_16x16x16_float32.raw tiny.afam
  run "1proc,1thread" 1 1 "$volume" one_t1.afam
  run "1proc,2threads" 1 2 "$volume" one_t2.afam
fi
run "reference,${RANKS}ranks" "$RANKS" 1 "$volume" reference
run "${RANKS}ranks,1thread" "$RANKS" 1 "$volume" ranks_t1.afam
# What the encode adds on each rank beside its piece, against one z-row of finest blocks
# (their samples: blocks per axis^2 x (edge + 1)^3 floats; ~65-sample blocks when --blocks is 0).
blocks="$(sed -n 's/.*--blocks \([0-9]*\).*/\1/p' <<<" ${OPTIONS[*]} ")"
[ -n "$blocks" ] && [ "$blocks" != 0 ] || blocks=$(( (SIZE + 63) / 64 ))
row=$(( blocks * blocks * (SIZE / blocks + 1) ** 3 * 4 ))
for ((r = 0; r < RANKS; ++r)); do
  added=$(( ${PEAK["${RANKS}ranks,1thread:$r"]} - ${PEAK["reference,${RANKS}ranks:$r"]} ))
  echo "rank $r: the encode adds $(( added / 1000 )) kB to the reference run's peak (${HEAPTRACK:+heap, }one z-row of finest blocks: $(( row / 1000 )) kB; $(( added >= row ? 1 : 0 )) = over)"
done
if cmp -s one_t1.afam ranks_t1.afam && cmp -s one_t1.afam one_t2.afam; then
  echo "files: the ${RANKS}-rank file is byte-identical to the one-process files"
else
  echo "files: DIFFER"
  exit 1
fi
