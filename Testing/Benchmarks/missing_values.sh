#!/usr/bin/env bash
# Issue 30's bars for missing samples, one table: each volume with holes (a ball cut out of every
# corpus volume; a CT's field of view; generated land), encoded at relative RMSE 1e-2 and 1e-3 and
# at relative max-error 1e-2 and 1e-3, against the same volume with its holes filled by the nearest
# valid value (what users do by hand today), both with the same options; `afam verify --against`
# on the masked file checks the mask and the bound on the valid samples.
# Usage: Testing/Benchmarks/missing_values.sh BUILD_DIR OUT_DIR [VOLUMES_DIR]
#   ENLARGE=X,Y,Z also measures the CT (headsq) made large to X,Y,Z (afam enlarge) with its field
#   of view cut out.
set -euo pipefail
root="$(cd "$(dirname "$0")/../.." && pwd)"
afam="${1:?usage: missing_values.sh BUILD_DIR OUT_DIR [VOLUMES_DIR]}/Apps/afam"
out="${2:?usage: missing_values.sh BUILD_DIR OUT_DIR [VOLUMES_DIR]}"
vols="${3:-$root/Testing/Data/volumes}"
mkdir -p "$out"
cases=()
for raw in "$vols"/*.raw; do cases+=("$raw ball"); done
cases+=("$vols/headsq_quarter_64x64x93_int16.raw fov" "$vols/HeadMRVolume_48x62x42_uint8.raw fov"
        "$vols/chi_field_50x50x50_float32.raw land" "$vols/hydrogen_3d_orbital_64x64x64_float32.raw land")
if [ -n "${ENLARGE:-}" ]; then
  big="$out/headsq_big_$(echo "$ENLARGE" | tr , x)_int16.raw"
  [ -f "$big" ] || "$afam" enlarge "$vols/headsq_quarter_64x64x93_int16.raw" "$big" --dims "$ENLARGE" >/dev/null
  cases+=("$big fov")
fi
printf "%-44s %-5s %-16s %10s %10s %6s %s\n" volume shape bound masked nearest ratio verify
larger=0
total=0
for c in "${cases[@]}"; do
  set -- $c
  raw=$1 shape=$2
  name="$(basename "$raw" .raw)"
  dims="$(echo "$name" | sed 's/.*_\([0-9]*\)x\([0-9]*\)x\([0-9]*\)_.*/\1,\2,\3/')"
  holes="$out/${name}_${shape}.raw" filled="$out/${name}_${shape}_nearest.raw"
  [ -f "$holes" ] || "$afam" mask "$raw" "$holes" --shape "$shape" --nearest "$filled" >/dev/null
  for bound in "--error-bound 1e-2" "--error-bound 1e-3" "--max-error 1e-2" "--max-error 1e-3"; do
    "$afam" encode "$holes" "$out/m.afam" --dims "$dims" --type float32 $bound --relative --quiet
    "$afam" encode "$filled" "$out/n.afam" --dims "$dims" --type float32 $bound --relative --quiet
    m=$(stat -c %s "$out/m.afam") n=$(stat -c %s "$out/n.afam")
    v=$("$afam" verify "$out/m.afam" --against "$holes" --dims "$dims" --type float32 | tail -1 |
        grep -o 'max_error=.*')
    printf "%-44s %-5s %-16s %10d %10d %6.3f %s\n" "$name" "$shape" "${bound#--}" "$m" "$n" \
      "$(echo "$m / $n" | bc -l)" "$v"
    total=$((total + 1))
    [ "$m" -le "$n" ] || larger=$((larger + 1))
  done
done
echo "masked file no larger than the nearest-filled one: $((total - larger)) of $total"
