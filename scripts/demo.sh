#!/usr/bin/env bash
# The main job: install what is missing, build, generate a Marschner-Lobb volume, encode it
# (Adaptive-FAM, FAM, DS), render points of view of user_1.dat through the ParaView plugin with
# pvbatch (Apps/pvbatch/afam_demo.py), next to Core's `afam render` of the same views and ParaView's
# own Volume representation of the raw volume, and report error against the analytic ground truth
# and time per method. Output under out/demo/ (images, report.csv).
# Knobs (environment): AFAM_BUILD (build folder), AFAM_DEMO_SIZE (256), AFAM_DEMO_VIEWS (0,100,200),
# AFAM_DEMO_REPEATS (timed renders per view after a warm-up, 3), AFAM_DEMO_SAMPLE_DISTANCE (0.01).
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
build="${AFAM_BUILD:-$root/build}"
out="$root/out/demo"
"$root/scripts/install-deps.sh"
"$root/scripts/build.sh" "$build"
afam="$build/Apps/afam"
plugin="$build/lib/paraview-5.11/plugins/AdaptiveFAM/AdaptiveFAM.so"
traj="$root/../shared/data/trajectories/user_1.dat"
if [ ! -f "$plugin" ]; then
  echo "demo.sh: the ParaView plugin was not built ($plugin missing; is ParaView 5.11 installed?)" >&2
  exit 1
fi
mkdir -p "$out"
"$afam" ml --size 129 "$out/ml.raw"
methods=()
for mode in adaptive fixed ds; do
  "$afam" encode "$out/ml.raw" "$out/ml_$mode.afam" --dims 129,129,129 --mode "$mode" --error-bound 1e-4
  methods+=(--method "$mode=$out/ml_$mode.afam")
done
# Headless ParaView: Xvfb with -noreset, and a time limit (Xvfb resets when its last client leaves).
timeout 1800 xvfb-run -a -s "-screen 0 1280x1024x24 -noreset" \
  pvbatch "$root/Apps/pvbatch/afam_demo.py" --plugin "$plugin" --afam "$afam" --trajectory "$traj" \
    --out "$out" "${methods[@]}" --raw "$out/ml.raw" --views "${AFAM_DEMO_VIEWS:-0,100,200}" \
    --size "${AFAM_DEMO_SIZE:-256}" --repeats "${AFAM_DEMO_REPEATS:-3}" \
    --sample-distance "${AFAM_DEMO_SAMPLE_DISTANCE:-0.01}"
echo "images and report in $out"
