#!/usr/bin/env bash
# Encodes what a refactoring must leave byte for byte unchanged and prints one checksum per file:
# every volume of Testing/Data/volumes at relative RMSE bounds 1e-2 and 1e-3 (defaults otherwise)
# and Marschner-Lobb 256^3 at the paper's settings (4 levels, 16 finest blocks, p = 2, bound 1e-4).
# Run it with the build before and after a change and compare the outputs (diff / cmp).
# Usage: Testing/Benchmarks/encode_identity.sh BUILD_DIR OUT_DIR
set -euo pipefail
root="$(cd "$(dirname "$0")/../.." && pwd)"
build="${1:?usage: encode_identity.sh BUILD_DIR OUT_DIR}"
out="${2:?usage: encode_identity.sh BUILD_DIR OUT_DIR}"
afam="$build/Apps/afam"
mkdir -p "$out"
for raw in "$root"/Testing/Data/volumes/*.raw; do
  name="$(basename "$raw" .raw)"
  for bound in 1e-2 1e-3; do
    "$afam" encode "$raw" "$out/${name}_${bound}.afam" --error-bound "$bound" --relative >/dev/null
  done
done
[ -f "$out/ml_256x256x256_float32.raw" ] || "$afam" ml --size 256 "$out/ml_256x256x256_float32.raw" >/dev/null
"$afam" encode "$out/ml_256x256x256_float32.raw" "$out/ml_256_paper.afam" --levels 4 --blocks 16 \
  --error-bound 1e-4 >/dev/null
(cd "$out" && sha256sum -- *.afam)
