#!/usr/bin/env bash
# The main job: install what is missing, build, generate a Marschner-Lobb volume, encode it
# (Adaptive-FAM, FAM, DS), render points of view of an exploration path through the ParaView plugin
# with pvbatch (Apps/pvbatch/afam_demo.py), next to Core's `afam render` of the same views and
# ParaView's own Volume representation of the raw volume, and report error against the analytic
# ground truth and time per method. Then one real volume of the repository (Testing/Data/volumes),
# encoded and rendered through the plugin next to ParaView's Volume representation of the raw file
# (Apps/pvbatch/afam_demo_real.py): sizes, data error and image difference. Output under out/demo/.
# The exploration path is generated (`afam trajectory`, seed 1); a recorded one is used instead when
# AFAM_TRAJECTORIES names a folder holding user_1.dat.
# Knobs (environment): AFAM_BUILD (build folder), AFAM_DEMO_SIZE (256), AFAM_DEMO_VIEWS (0,100,200),
# AFAM_DEMO_REPEATS (timed renders per view after a warm-up, 3), AFAM_DEMO_SAMPLE_DISTANCE (0.01),
# AFAM_DEMO_VOLUME (neghip_66x66x66_uint8.raw), AFAM_DEMO_REAL_VIEWS (0,4,8 of a 12-view orbit).
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
build="${AFAM_BUILD:-$root/build}"
out="$root/out/demo"
"$root/scripts/install-deps.sh"
"$root/scripts/build.sh" "$build"
afam="$build/Apps/afam"
plugin="$build/lib/paraview-5.11/plugins/AdaptiveFAM/AdaptiveFAM.so"
if [ ! -f "$plugin" ]; then
  echo "demo.sh: the ParaView plugin was not built ($plugin missing; is ParaView 5.11 installed?)" >&2
  exit 1
fi
mkdir -p "$out"
if [ -n "${AFAM_TRAJECTORIES:-}" ] && [ -f "$AFAM_TRAJECTORIES/user_1.dat" ]; then
  traj="$AFAM_TRAJECTORIES/user_1.dat"
  echo "demo.sh: points of view from the recorded path $traj"
else
  traj="$out/walk.dat"
  "$afam" trajectory "$traj" --kind walk --views 400 --seed 1
  echo "demo.sh: points of view from a GENERATED exploration path (afam trajectory, seed 1);" \
       "set AFAM_TRAJECTORIES to a folder with user_1.dat to use a recorded one"
fi
"$afam" ml --size 129 "$out/ml.raw"
methods=()
for mode in adaptive fixed ds; do
  "$afam" encode "$out/ml.raw" "$out/ml_$mode.afam" --dims 129,129,129 --mode "$mode" --error-bound 1e-4
  methods+=(--method "$mode=$out/ml_$mode.afam")
done
# Headless ParaView: Xvfb with -noreset (without it Xvfb resets when its last client leaves and
# ParaView can lose its display), and a time limit.
xvfb=(timeout 1800 xvfb-run -a -s "-screen 0 1280x1024x24 -noreset")
"${xvfb[@]}" pvbatch "$root/Apps/pvbatch/afam_demo.py" --plugin "$plugin" --afam "$afam" --trajectory "$traj" \
    --out "$out" "${methods[@]}" --raw "$out/ml.raw" --views "${AFAM_DEMO_VIEWS:-0,100,200}" \
    --size "${AFAM_DEMO_SIZE:-256}" --repeats "${AFAM_DEMO_REPEATS:-3}" \
    --sample-distance "${AFAM_DEMO_SAMPLE_DISTANCE:-0.01}"
# A real volume from the repository, encoded with an RMSE bound of 1e-3 of its value range, seen
# from a 12-view orbit that keeps the whole volume in the authors' 14-degree view.
volume="$root/Testing/Data/volumes/${AFAM_DEMO_VOLUME:-neghip_66x66x66_uint8.raw}"
real="$out/$(basename "$volume" .raw).afam"
"$afam" encode "$volume" "$real" --error-bound 1e-3 --relative
"$afam" trajectory "$out/orbit.dat" --kind orbit --views 12 --distance 9 --theta 70 --phi 20
"${xvfb[@]}" pvbatch "$root/Apps/pvbatch/afam_demo_real.py" --plugin "$plugin" --afam "$afam" \
    --file "$real" --raw "$volume" --trajectory "$out/orbit.dat" --out "$out" \
    --views "${AFAM_DEMO_REAL_VIEWS:-0,4,8}" --size "${AFAM_DEMO_SIZE:-256}" \
    --repeats "${AFAM_DEMO_REPEATS:-3}" --sample-distance "${AFAM_DEMO_SAMPLE_DISTANCE:-0.01}"
echo "images and reports (report.csv, report_real.csv) in $out"
