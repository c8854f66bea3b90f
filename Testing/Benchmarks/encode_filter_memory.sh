#!/usr/bin/env bash
# Peak memory of one pvbatch process encoding an 8-bit volume through the encoding filter
# (Apps/pvbatch/afam_encode.py: ParaView's raw reader -> vtkAFAMEncoder), for each build given:
# the builds before and after a change, measured in one sitting, with the files they write
# compared byte for byte. The volume: the repository's HeadMRVolume made large to SIZE^3 uint8
# (`afam enlarge` of the last build given; default 512).
# Usage: Testing/Benchmarks/encode_filter_memory.sh WORK_DIR BUILD_DIR [BUILD_DIR ...]
#        SIZE=512 ENCODE_OPTIONS="--error-bound 1e-2 --relative" ROUNDS=1
set -euo pipefail
here="$(cd "$(dirname "$0")/../.." && pwd)"
WORK="${1:?usage: encode_filter_memory.sh WORK_DIR BUILD_DIR [BUILD_DIR ...]}"
shift
[ $# -ge 1 ] || { echo "give at least one build directory" >&2; exit 2; }
SIZE="${SIZE:-512}"
ROUNDS="${ROUNDS:-1}"
read -r -a OPTIONS <<<"${ENCODE_OPTIONS:---error-bound 1e-2 --relative}"
mkdir -p "$WORK"
volume="$WORK/headmr_${SIZE}x${SIZE}x${SIZE}_uint8.raw"
if [ ! -f "$volume" ]; then
  last="$(cd "${!#}" && pwd)"  # the newest build has `afam enlarge`
  "$last/Apps/afam" enlarge "$here/Testing/Data/volumes/HeadMRVolume_48x62x42_uint8.raw" "$volume" \
    --dims "$SIZE,$SIZE,$SIZE" >/dev/null
fi
echo "volume $(basename "$volume") ($(stat -c %s "$volume") bytes), options ${OPTIONS[*]}, $(nproc) cores"
outputs=()
for build in "$@"; do
  build="$(cd "$build" && pwd)"
  plugin="$build/lib/paraview-5.11/plugins/AdaptiveFAM/AdaptiveFAM.so"
  out="$WORK/$(echo "$build" | tr '/' '_').afam"
  for ((r = 1; r <= ROUNDS; ++r)); do
    rm -f "$out"
    line="$(xvfb-run -a -s "-screen 0 640x480x24 -noreset" /usr/bin/time -f "wall_s=%e peak_rss_kb=%M" \
      pvbatch "$here/Apps/pvbatch/afam_encode.py" --plugin "$plugin" "$volume" "$out" --quiet \
      "${OPTIONS[@]}" 2>&1 | grep -E "^wall_s=")"
    echo "build=$build round=$r $line bytes=$(stat -c %s "$out")"
  done
  outputs+=("$out")
done
for ((i = 1; i < ${#outputs[@]}; ++i)); do
  if cmp -s "${outputs[0]}" "${outputs[$i]}"; then echo "same file: build 1 and build $((i + 1))"
  else echo "DIFFERENT files: build 1 and build $((i + 1))"; fi
done
