#!/usr/bin/env bash
# SPDX-License-Identifier: BSD-3-Clause
# Prefetching benchmark: next-pose error of every predictor on two exploration paths
# (`afam predict`), and replay of Marschner-Lobb 256^3 with the paper's 200-block cache with each
# prefetcher (`afam replay`), warm and in the paper's regime (cold storage capped at 100 MB/s).
# Usage: Testing/Benchmarks/bench_prefetch.sh BUILD_DIR [WORK_DIR]
# Env: SIZE (image, default 64,64), SD (sample distance, default 0.02), SHADING (off), THREADS (1),
#      TRAJ (trajectories replayed, default "user_2"), REGIMES (default "warm cold100"),
#      AFAM_TRAJECTORIES (folder of recorded user_1.dat, user_2.dat; generated walks otherwise).
set -euo pipefail
root="$(cd "$(dirname "$0")/../.." && pwd)"
build="$(cd "${1:?usage: bench_prefetch.sh BUILD_DIR [WORK_DIR]}" && pwd)"
work="${2:-/tmp/afam_bench_prefetch}"
afam="$build/Apps/afam"
SIZE="${SIZE:-64,64}"; SD="${SD:-0.02}"; SHADING="${SHADING:-off}"; THREADS="${THREADS:-1}"
TRAJ="${TRAJ:-user_2}"; REGIMES="${REGIMES:-warm cold100}"
mkdir -p "$work"
cd "$work"
source "$root/scripts/trajectories.sh"
afam_trajectories "$afam" "$work/trajectories"
data="$AFAM_TRAJ_DIR"
if [ ! -f ml_256.afam ]; then
  "$afam" ml --size 256 ml_256.raw
  "$afam" encode ml_256.raw ml_256.afam --error-bound 1e-3 --quiet
  rm -f ml_256.raw
fi
echo "machine: $(nproc) cores, $(uname -srm), load $(cut -d' ' -f1-3 /proc/loadavg)"
echo "## next-pose error (afam predict)"
for t in user_1 user_2; do
  for p in none linear appa forecache lstm; do
    out=$("$afam" predict "$data/$t.dat" --predictor "$p" --out "pred_${t}_$p.dat")
    echo "predict traj=$t predictor=$p $(echo "$out" | grep -o 'mean_inference_us=[0-9.]*') $(echo "$out" | grep -o 'mean_position_error=[0-9.]*')"
  done
  out=$("$afam" predict "$data/$t.dat" --predictor forecache --file ml_256.afam --out "pred_${t}_fcdata.dat")
  echo "predict traj=$t predictor=forecache+signature $(echo "$out" | grep -o 'mean_inference_us=[0-9.]*') $(echo "$out" | grep -o 'mean_position_error=[0-9.]*')"
done
rm -f ml_256.afam.appa
echo "## APPA table"
"$afam" predict "$data/user_2.dat" --predictor appa --file ml_256.afam --out pred_appa_tmp.dat | head -1
"$afam" predict "$data/user_2.dat" --predictor appa --file ml_256.afam --out pred_appa_tmp.dat | head -1
echo "## replay (ML 256^3, cache 200 blocks, image $SIZE, sample distance $SD, shading $SHADING, $THREADS ray thread(s))"
for t in $TRAJ; do
  for regime in $REGIMES; do
    extra=()
    if [ "$regime" = cold100 ]; then extra=(--cold --storage-mbps 100); fi
    for p in none linear appa forecache lstm; do
      line=$("$afam" replay ml_256.afam --trajectory "$data/$t.dat" --size "$SIZE" --sample-distance "$SD" \
               --shading "$SHADING" --threads "$THREADS" --cache-blocks 200 --prefetch "$p" "${extra[@]}" \
               --quiet --csv "replay_${t}_${regime}_$p.csv" | tail -1)
      echo "replay traj=$t regime=$regime prefetch=$p $line"
    done
  done
done
