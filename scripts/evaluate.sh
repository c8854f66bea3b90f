#!/usr/bin/env bash
# SPDX-License-Identifier: BSD-3-Clause
# The evaluation report, from scratch, with one command:
#   scripts/evaluate.sh [--smoke|--small|--full] OUTDIR
# Writes OUTDIR/{encoding,quality,compressors,latency,stability,codecs}/*.csv, a PNG plot beside each
# CSV (same stem), OUTDIR/commands.log (every command run, in order, with its wall time) and
# OUTDIR/summary.md (the key numbers, Pareto verdict included; its latency comes from
# interleaved rounds of replays, scripts/evaluation/pareto_replays.sh, AFAM_PARETO_REPS rounds).
# Needs the `afam` and `afam_eval` binaries (AFAM_BUILD, default build-eval; built here if missing)
# and /usr/bin/python3 with numpy and matplotlib (Debian python3-numpy python3-matplotlib).
#   --smoke  tiny sizes for CI (< 3 minutes on 2 cores)
#   --small  the CPU report (default; < 30 minutes on a 2-core machine)
#   --full   the paper-scale sizes (GPU machine / big hosts)
# Environment: AFAM_DEVICE=cpu|gpu (ray caster of the replays and the quality renders; gpu builds
# with CUDA), AFAM_JOBS (threads, default 2), AFAM_PYTHON (default /usr/bin/python3), AFAM_ML_N
# (Marschner-Lobb size, overrides the size's default), AFAM_VOLUMES (corpus volumes, default
# Testing/Data/volumes), AFAM_TRAJECTORIES (folder of the recorded user_1.dat, user_2.dat; without
# it generated exploration walks are replayed, and the summary says so: scripts/trajectories.sh),
# AFAM_STORAGE_MBPS (emulated storage, default 100), AFAM_PARETO_REPS. On the GPU machine,
# scripts/gpu_evaluate.sh runs the --full report this way.
set -euo pipefail

SIZE=small
while [[ $# -gt 1 ]]; do
  case "$1" in
    --smoke) SIZE=smoke ;;
    --small) SIZE=small ;;
    --full) SIZE=full ;;
    *) echo "evaluate.sh: unknown option $1" >&2; exit 2 ;;
  esac
  shift
done
[[ $# -eq 1 ]] || { echo "usage: scripts/evaluate.sh [--smoke|--small|--full] OUTDIR" >&2; exit 2; }
OUT=$(mkdir -p "$1" && cd "$1" && pwd)
ROOT=$(cd "$(dirname "$0")/.." && pwd)
VOLUMES_DIR=${AFAM_VOLUMES:-$ROOT/Testing/Data/volumes}
BUILD=${AFAM_BUILD:-$ROOT/build-eval}
PY=${AFAM_PYTHON:-/usr/bin/python3}
DEVICE=${AFAM_DEVICE:-cpu}
JOBS=${AFAM_JOBS:-2}

if [[ ! -x $BUILD/Apps/afam || ! -x $BUILD/Apps/evaluation/afam_eval ]]; then
  CUDA=OFF; [[ $DEVICE == gpu ]] && CUDA=ON
  mkdir -p "$BUILD"
  { cmake -S "$ROOT" -B "$BUILD" -DCMAKE_BUILD_TYPE=Release -DAFAM_ENABLE_PARAVIEW=OFF -DAFAM_ENABLE_CUDA=$CUDA &&
    cmake --build "$BUILD" -j"$JOBS" --target afam afam_eval; } > "$BUILD/evaluate_build.log" 2>&1 ||
    { tail -30 "$BUILD/evaluate_build.log" >&2; echo "evaluate.sh: build failed ($BUILD/evaluate_build.log)" >&2; exit 1; }
fi
AFAM=$BUILD/Apps/afam
EVAL=$BUILD/Apps/evaluation/afam_eval

# ---- sizes ------------------------------------------------------------------------------------
case $SIZE in
  smoke)
    ML_N=33; BLOCKS=8; IMG=48; FRAMES=12; PREFETCHERS="none linear"
    BOUNDS="1e-2 1e-3"; REL_BOUNDS="1e-2"; FIXED_NCPS="3 5"; VOLUMES="bucky_32x32x32_uint8.raw"
    SDS="0.02,0.01"; ZFP_RATES="1 4"; FPZIP_PRECS="8 14"; QUALITY_BOUNDS="1e-3"; REPLAY_IMG=24; REPLAY_SD=0.02; PARETO_REPS=1 ;;
  small)
    ML_N=257; BLOCKS=16; IMG=96; FRAMES=400; PREFETCHERS="none linear appa forecache lstm"
    BOUNDS="3e-2 1e-2 3e-3 1e-3 3e-4 1e-4"; REL_BOUNDS="3e-2 1e-2 3e-3 1e-3"; FIXED_NCPS="5 9 13"
    VOLUMES=$(cd "$VOLUMES_DIR" && ls *.raw | tr '\n' ' ')
    SDS="0.02,0.01,0.005,0.0025"; ZFP_RATES="0.25 0.5 1 2 4 8"; FPZIP_PRECS="4 6 8 12 16 20"
    QUALITY_BOUNDS="1e-3 1e-4"; REPLAY_IMG=32; REPLAY_SD=0.01; PARETO_REPS=3 ;;
  full)
    ML_N=513; BLOCKS=16; IMG=512; FRAMES=400; PREFETCHERS="none linear appa forecache lstm"
    BOUNDS="3e-2 1e-2 3e-3 1e-3 3e-4 1e-4"; REL_BOUNDS="3e-2 1e-2 3e-3 1e-3"; FIXED_NCPS="5 9 17 25"
    VOLUMES=$(cd "$VOLUMES_DIR" && ls *.raw | tr '\n' ' ')
    SDS="0.01,0.005,0.0025,0.00125"; ZFP_RATES="0.25 0.5 1 2 4 8"; FPZIP_PRECS="4 6 8 12 16 20"
    QUALITY_BOUNDS="1e-3 1e-4"; REPLAY_IMG=512; REPLAY_SD=0.005; PARETO_REPS=3 ;;
esac
ML_N=${AFAM_ML_N:-$ML_N}
LEVELS=4
PARETO_REPS=${AFAM_PARETO_REPS:-$PARETO_REPS}
# Replays run in the paper's regime: 200-model cache, OS page cache dropped before each point of
# view, storage emulated at STORAGE_MBPS (the paper read from a 5400 rpm HDD).
STORAGE_MBPS=${AFAM_STORAGE_MBPS:-100}

mkdir -p "$OUT"/{encoding,quality,compressors,latency,stability,codecs,work,images}
W=$OUT/work
LOG=$OUT/commands.log
: > "$LOG"
{
  echo "# scripts/evaluate.sh --$SIZE $OUT"
  echo "# date: $(date -u +%FT%TZ)  host: $(uname -n)  git: $(cd "$ROOT" && git rev-parse --short HEAD 2>/dev/null || echo ?)"
  echo "# cpu: $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ *//')  cores: $(nproc)  threads used: $JOBS"
  echo "# device: $DEVICE$( [[ $DEVICE == gpu ]] && echo " ($(nvidia-smi --query-gpu=name --format=csv,noheader 2>/dev/null | head -1))")  ml: ${ML_N}^3"
} >> "$LOG"

# run CMD...: logs the command, runs it, logs its wall time; stdout goes to the caller.
run() {
  local t0 t1 rc=0
  echo "$*" >> "$LOG"
  t0=$(date +%s.%N)
  "$@" || rc=$?
  t1=$(date +%s.%N)
  echo "#   wall_s=$(awk -v a="$t0" -v b="$t1" 'BEGIN{printf "%.3f", b - a}') rc=$rc" >> "$LOG"
  return $rc
}
stamp() { echo "[$(date +%T)] $*" >&2; }
kv() { grep -o "$1=[^ ]*" | tail -1 | cut -d= -f2; }  # kv KEY < text

# The two exploration paths replayed below: recorded (AFAM_TRAJECTORIES) or generated walks.
source "$ROOT/scripts/trajectories.sh"
afam_trajectories "$AFAM" "$W/trajectories" > "$W/trajectories.txt"
TRAJ_DIR=$AFAM_TRAJ_DIR
TRAJ_NOTE=$(cat "$W/trajectories.txt")
stamp "$TRAJ_NOTE"
echo "# $TRAJ_NOTE" >> "$LOG"

T_START=$(date +%s)

# ---- (2) encoding ------------------------------------------------------------------------------
stamp "encoding sweep"
ML=$W/ml_${ML_N}x${ML_N}x${ML_N}_float32.raw
run "$AFAM" ml --size "$ML_N" "$ML" > /dev/null
ENC_CSV=$OUT/encoding/encoding.csv
echo "volume,mode,bound,relative,ncp,seconds,fits,bytes_in,bytes_out,ratio_float32,rmse,max_error,value_range" > "$ENC_CSV"
encode_one() {  # VOLUME_LABEL RAW MODE BOUND REL NCP OUTFILE [extra args]
  local label=$1 raw=$2 mode=$3 bound=$4 rel=$5 ncp=$6 out=$7; shift 7
  local args=(encode "$raw" "$out" --mode "$mode" --levels $LEVELS --blocks $BLOCKS --threads "$JOBS" "$@")
  [[ $mode != fixed && $mode != ds ]] && args+=(--error-bound "$bound")
  [[ $rel == 1 ]] && args+=(--relative)
  [[ $mode == fixed && $ncp != n ]] && args+=(--ncp "$ncp")
  local e v
  e=$(run "$AFAM" "${args[@]}" 2>/dev/null)
  v=$(run "$AFAM" verify "$out" --against "$raw" "$@" 2>/dev/null)
  local range
  range=$(echo "$e" | grep -o 'value_range=\[[^]]*\]' | sed 's/value_range=\[\(.*\), \(.*\)\]/\1 \2/' |
          awk 'NF == 2 {printf "%.9g", $2 - $1; next} {printf "nan"}')
  echo "$label,$mode,$bound,$rel,$ncp,$(echo "$e" | kv seconds),$(echo "$e" | kv fits),$(echo "$e" | kv bytes_in),$(echo "$e" | kv bytes_out),$(echo "$e" | kv ratio_float32),$(echo "$v" | kv rmse),$(echo "$v" | kv max_error),$range" >> "$ENC_CSV"
}
for b in $BOUNDS; do
  for m in adaptive inlevel; do encode_one ml "$ML" $m "$b" 0 - "$W/ml_${m}_$b.afam"; done
done
for k in $FIXED_NCPS n; do encode_one ml "$ML" fixed - 0 "$k" "$W/ml_fixed_$k.afam"; done
encode_one ml "$ML" ds - 0 - "$W/ml_ds.afam"
for vol in $VOLUMES; do
  name=${vol%%_[0-9]*x*}
  for b in $REL_BOUNDS; do
    for m in adaptive inlevel; do encode_one "$name" "$VOLUMES_DIR/$vol" $m "$b" 1 - "$W/${name}_${m}_$b.afam"; done
  done
  for k in $FIXED_NCPS; do encode_one "$name" "$VOLUMES_DIR/$vol" fixed - 1 "$k" "$W/${name}_fixed_$k.afam"; done
done
run $PY "$ROOT/scripts/evaluation/report.py" encoding "$OUT"

# ---- (3) rendering quality vs time at the cross-level view ------------------------------------
stamp "rendering quality"
TRAJ1=$TRAJ_DIR/user_1.dat
TRAJ2=$TRAJ_DIR/user_2.dat
QFILES=("DS=$W/ml_ds.afam" "FAM=$W/ml_fixed_n.afam")
for b in $QUALITY_BOUNDS; do QFILES+=("Adaptive-FAM_$b=$W/ml_adaptive_$b.afam"); done
QFILES+=("inlevel_${QUALITY_BOUNDS##* }=$W/ml_inlevel_${QUALITY_BOUNDS##* }.afam")
mkdir -p "$OUT/images/quality"
run "$EVAL" quality --trajectory "$TRAJ1" --view auto --size "$IMG" --sd "$SDS" --threads "$JOBS" --device "$DEVICE" \
  --csv "$OUT/quality/quality.csv" --images "$OUT/images/quality" "${QFILES[@]}" > "$W/quality.log"
VIEW=$(awk -F, 'NR==2{print $4}' "$OUT/quality/quality.csv")
run $PY "$ROOT/scripts/evaluation/report.py" quality "$OUT"

# ---- (4) compressors at matched ratio ---------------------------------------------------------
stamp "compressors"
CMP_CSV=$OUT/compressors/compressors_codec.csv
echo "codec,param,ratio,rmse,decompress_ms_total,decompress_us_per_block,file" > "$CMP_CSV"
CFILES=()
for codec in zfp fpzip; do
  if [[ $codec == zfp ]]; then params=$ZFP_RATES; else params=$FPZIP_PRECS; fi
  for p in $params; do
    f=$W/ml_${codec}_$p.afam
    if o=$(run "$EVAL" compress --codec $codec --param "$p" "$W/ml_ds.afam" "$f" 2>&1); then
      echo "$codec,$p,$(echo "$o" | kv ratio),$(echo "$o" | kv rmse),$(echo "$o" | kv decompress_ms_total),$(echo "$o" | kv decompress_us_per_block),$f" >> "$CMP_CSV"
      CFILES+=("${codec}_$p=$f")
    else
      echo "# $codec unavailable: $o" >> "$LOG"
    fi
  done
done
AFILES=()
for b in $BOUNDS; do AFILES+=("Adaptive-FAM_$b=$W/ml_adaptive_$b.afam"); done
SD_MID=$(echo "$SDS" | cut -d, -f2)
run "$EVAL" quality --trajectory "$TRAJ1" --view "$VIEW" --size "$IMG" --sd "$SD_MID" --threads "$JOBS" --device "$DEVICE" \
  --csv "$OUT/compressors/compressors_quality.csv" --images "$OUT/images/quality" \
  "DS=$W/ml_ds.afam" "${AFILES[@]}" "${CFILES[@]}" > "$W/compressors.log"
run $PY "$ROOT/scripts/evaluation/report.py" compressors "$OUT"

# ---- (5) input latency over the two exploration paths -----------------------------------------
stamp "latency replays"
LAT_CSV=$OUT/latency/latency_summary.csv
echo "trajectory,method,file,prefetch,median_latency_ms,median_caching_ms,median_render_ms,miss_rate,csv" > "$LAT_CSV"
REPLAY_BOUND=${QUALITY_BOUNDS##* }
for traj in user_1 user_2; do
  for meth in DS FAM Adaptive-FAM; do
    case $meth in
      DS) f=$W/ml_ds.afam ;;
      FAM) f=$W/ml_fixed_n.afam ;;
      Adaptive-FAM) f=$W/ml_adaptive_$REPLAY_BOUND.afam ;;
    esac
    for pf in $PREFETCHERS; do
      csv=$OUT/latency/replay_${traj}_${meth}_${pf}.csv
      o=$(set -o pipefail; run "$AFAM" replay "$f" --trajectory "$TRAJ_DIR/$traj.dat" --frames "$FRAMES" \
            --size "$REPLAY_IMG,$REPLAY_IMG" --sample-distance "$REPLAY_SD" --cache-blocks 200 \
            --cold --storage-mbps "$STORAGE_MBPS" --prefetch "$pf" --threads "$JOBS" --device "$DEVICE" --quiet --csv "$csv" 2>&1 | tail -1) || {
        echo "# replay $traj $meth $pf failed: $o" >> "$LOG"; continue; }
      echo "$traj,$meth,$f,$pf,$(echo "$o" | kv median_latency_ms),$(echo "$o" | kv median_caching_ms),$(echo "$o" | kv median_render_ms),$(echo "$o" | kv miss_rate),$csv" >> "$LAT_CSV"
    done
  done
done
# The Pareto bar's latency: DS, FAM and Adaptive-FAM replayed side by side (no prefetching),
# PARETO_REPS rounds with the order rotated, pooled per point of view by report.py, so that the
# verdict does not hang on which replay a burst of load hit.
stamp "Pareto replays ($PARETO_REPS rounds, methods interleaved)"
run "$ROOT/scripts/evaluation/pareto_replays.sh" "$AFAM" "$OUT/latency" "$TRAJ_DIR" "$FRAMES" \
  "$REPLAY_IMG" "$REPLAY_SD" "$STORAGE_MBPS" "$JOBS" "$PARETO_REPS" \
  "DS=$W/ml_ds.afam" "FAM=$W/ml_fixed_n.afam" "Adaptive-FAM=$W/ml_adaptive_$REPLAY_BOUND.afam"
run $PY "$ROOT/scripts/evaluation/report.py" latency "$OUT"

# ---- (6) numerical stability and seams --------------------------------------------------------
stamp "stability and seams"
run "$EVAL" stability --csv "$OUT/stability/stability.csv" --chi "$VOLUMES_DIR/chi_field_50x50x50_float32.raw" > "$W/stability.log"
SFILES=("ml_adaptive=$W/ml_adaptive_${REPLAY_BOUND}.afam" "ml_fam=$W/ml_fixed_n.afam" "ml_ds=$W/ml_ds.afam")
for vol in $VOLUMES; do
  name=${vol%%_[0-9]*x*}
  SFILES+=("${name}_adaptive=$W/${name}_adaptive_${REL_BOUNDS##* }.afam")
done
run "$EVAL" seams --csv "$OUT/stability/seams.csv" "${SFILES[@]}" > "$W/seams.log"

# ---- (7) Adaptive-FAM against ZFP at the same RMSE on the corpus -------------------------------
# afam compare-codecs with the encoder's default partition; ZFP fixed-accuracy tuned to the RMSE
# Adaptive-FAM reached.
stamp "compression against ZFP (compare-codecs)"
CC_VOLS=()
for vol in $VOLUMES; do CC_VOLS+=("$VOLUMES_DIR/$vol"); done
run "$AFAM" compare-codecs "${CC_VOLS[@]}" --bounds 1e-2,1e-3 --threads "$JOBS" --work "$W" \
  --csv "$OUT/codecs/compare_codecs.csv" > "$W/compare_codecs.log"
run $PY "$ROOT/scripts/evaluation/report.py" codecs "$OUT"

# ---- summary -------------------------------------------------------------------------------------
T_END=$(date +%s)
echo "# total_wall_s=$((T_END - T_START)) size=$SIZE" >> "$LOG"
run $PY "$ROOT/scripts/evaluation/report.py" summary "$OUT" --size "$SIZE" --wall "$((T_END - T_START))"
[[ ${AFAM_EVAL_KEEP_WORK:-0} == 1 ]] || rm -rf "$W"
stamp "done in $((T_END - T_START)) s: $OUT/summary.md"
