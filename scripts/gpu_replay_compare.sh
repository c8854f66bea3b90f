#!/usr/bin/env bash
# Cold replay latency beside an earlier commit, in one run on the GPU machine: Marschner-Lobb N^3
# (default 1024) encoded at the paper's settings (4 levels, 16 finest blocks per axis, p = 2, RMSE
# bound 1e-4, every other option the commit's default) by the earlier commit's `afam` and by this
# tree's; both files replayed with --device gpu --cold at 512 x 512, no prefetching, the same cache
# budget in bytes, by their own binary, and the earlier file by this tree's binary too (the file's
# effect alone). Repetitions alternate between the three, and the table gives the median over
# repetitions of each replay's median latency, last.
#   here:  mkdir -p build-oldsrc && git archive COMMIT | gzip > build-oldsrc/src.tar.gz
#   there: scripts/gpu_replay_compare.sh build-oldsrc/src.tar.gz   (build-oldsrc carried)
# Environment: AFAM_REPLAY_N (1024), AFAM_REPLAY_SIZE (512, the image's side), AFAM_REPLAY_CACHE_BYTES (220e6), AFAM_COMPARE_REPS (3),
# AFAM_REPLAY_TRAJECTORIES ("user_1 user_2"), AFAM_REPLAY_WORK (/tmp/afam_compare), AFAM_JOBS (16).
set -uo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
old_tar="${1:?usage: gpu_replay_compare.sh OLD_SOURCE.tar.gz}"
n="${AFAM_REPLAY_N:-1024}"
size="${AFAM_REPLAY_SIZE:-512}"
cache="${AFAM_REPLAY_CACHE_BYTES:-220000000}"
reps="${AFAM_COMPARE_REPS:-3}"
trajectories="${AFAM_REPLAY_TRAJECTORIES:-user_1 user_2}"
work="${AFAM_REPLAY_WORK:-/tmp/afam_compare}"
logs="${OUT:-$work/logs}"
jobs="${AFAM_JOBS:-16}"
mkdir -p "$work/old-src" "$logs"
source "$root/scripts/gpu_deps.sh"
tar xzf "$old_tar" -C "$work/old-src" || { echo "cannot unpack $old_tar"; exit 1; }

build_afam() {  # source build log
  cmake -S "$1" -B "$2" -G Ninja -DCMAKE_BUILD_TYPE=Release -DAFAM_ENABLE_PARAVIEW=OFF -DAFAM_ENABLE_CUDA=ON \
    >"$3" 2>&1 && ninja -C "$2" -j "$(( jobs / 2 ))" afam >>"$3" 2>&1
}
t0=$(date +%s)
build_afam "$work/old-src" "$work/build-old" "$logs/build_old.log" & p_old=$!
build_afam "$root" "$root/build-gpu" "$logs/build_new.log" & p_new=$!
wait $p_old || { tail -20 "$logs/build_old.log"; exit 1; }
wait $p_new || { tail -20 "$logs/build_new.log"; exit 1; }
echo "builds: $(( $(date +%s) - t0 )) s"
old="$work/build-old/Apps/afam"
new="$root/build-gpu/Apps/afam"

carried="${AFAM_GPU_DATA:-$root/gpu-data}/trajectories"
[ -n "${AFAM_TRAJECTORIES:-}" ] || [ ! -d "$carried" ] || export AFAM_TRAJECTORIES="$carried"
source "$root/scripts/trajectories.sh"
afam_trajectories "$new" "$work/trajectories" >"$logs/trajectories.txt" || exit 1
[ -f "$work/ml.raw" ] || "$new" ml --size "$n" "$work/ml.raw" >/dev/null || exit 1
for side in old new; do
  bin="$old"; [ $side = new ] && bin="$new"
  t0=$(date +%s)
  [ -f "$work/ml_$side.afam" ] || "$bin" encode "$work/ml.raw" "$work/ml_$side.afam" --dims "$n,$n,$n" \
    --error-bound 1e-4 --levels 4 --blocks 16 --degree 2 --quiet || exit 1
  echo "encode ($side binary): $(( $(date +%s) - t0 )) s, $(stat -c %s "$work/ml_$side.afam") bytes"
done
rm -f "$work/ml.raw"

median() { sort -g | awk '{v[NR]=$1} END {if (NR == 0) print "?"; else if (NR % 2) print v[(NR+1)/2]; else print (v[NR/2]+v[NR/2+1])/2}'; }
combos="old:old new:new new:old"  # binary:file
for rep in $(seq 1 "$reps"); do
  for traj in $trajectories; do
    for combo in $combos; do
      bin="$old"; [ "${combo%%:*}" = new ] && bin="$new"
      log="$logs/${traj}_${combo/:/_}_$rep.log"
      "$bin" replay "$work/ml_${combo##*:}.afam" --trajectory "$AFAM_TRAJ_DIR/$traj.dat" --size "$size,$size" \
        --device gpu --cold --cache-bytes "$cache" --cache-blocks 0 --prefetch none --quiet >"$log" 2>&1
      sed -n 's/.*median_latency_ms=\([^ ]*\).*/\1/p' "$log" | tail -1 >"$log.median"
    done
  done
done
table="$logs/compare_table.md"
{
  echo "| trajectory | binary | file | median latency ms (median of $reps) | each run | vs earlier |"
  echo "|---|---|---|---|---|---|"
  for traj in $trajectories; do
    base=$(cat "$logs/${traj}_old_old_"*.log.median | median)
    for combo in $combos; do
      runs=$(cat "$logs/${traj}_${combo/:/_}_"*.log.median | tr '\n' ' ')
      m=$(cat "$logs/${traj}_${combo/:/_}_"*.log.median | median)
      echo "| $traj | ${combo%%:*} | ${combo##*:} | $m | $runs | $(awk -v a="$m" -v b="$base" 'BEGIN {if (b > 0) printf "%.3f", a / b; else print "?"}') |"
    done
  done
} >"$table"
grep -h -m1 -i "device" "$logs"/*_1.log | head -1 || true
echo "ML ${n}^3 at the paper's settings, ${size}x${size}, --device gpu --cold, prefetch none, cache $cache bytes"
cat "$logs/trajectories.txt"
cat "$table"
