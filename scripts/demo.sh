#!/usr/bin/env bash
# The main job: install what is missing, build, generate a Marschner-Lobb volume, encode it
# (Adaptive-FAM, FAM, DS), render points of view of user_1.dat and report error against the
# analytic ground truth and run time per method. Output under out/demo/.
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
build="${AFAM_BUILD:-$root/build}"
out="$root/out/demo"
"$root/scripts/install-deps.sh"
"$root/scripts/build.sh" "$build"
afam="$build/Apps/afam"
traj="$root/../shared/data/trajectories/user_1.dat"
mkdir -p "$out"
"$afam" ml --size 129 "$out/ml.raw"
report="$out/report.csv"
echo "method,view,render_ms,psnr,ssim" > "$report"
for mode in adaptive fixed ds; do
  "$afam" encode "$out/ml.raw" "$out/ml_$mode.afam" --dims 129,129,129 --mode "$mode" --error-bound 1e-4
  for view in 0 200; do
    line=$("$afam" render "$out/ml_$mode.afam" --trajectory "$traj" --view "$view" --size 256,256 \
             --out "$out/${mode}_$view.png" --ground-truth-ml | tr '\n' ' ')
    ms=$(sed -n 's/.*render_ms=\([^ ]*\).*/\1/p' <<<"$line")
    psnr=$(sed -n 's/.*psnr=\([^ ]*\).*/\1/p' <<<"$line")
    ssim=$(sed -n 's/.*ssim=\([^ ]*\).*/\1/p' <<<"$line")
    echo "$mode,$view,$ms,$psnr,$ssim" >> "$report"
  done
done
column -s, -t "$report"
echo "images and report in $out"
