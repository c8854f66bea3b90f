#!/usr/bin/env bash
# Fails when clang-format would change a C++ or CUDA file of the repository (the style files:
# .clang-format at the root for Core, CudaKernels, Apps and the Core tests; VTK's style in the
# VTK module's folders). `scripts/check_format.sh --fix` rewrites them instead.
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
cd "$root"
formatter="${CLANG_FORMAT:-clang-format}"
command -v "$formatter" >/dev/null || { echo "check_format: $formatter not found (scripts/install-deps.sh installs it)" >&2; exit 1; }
mapfile -t files < <(git ls-files -- '*.h' '*.hpp' '*.cxx' '*.cpp' '*.cu' '*.cuh')
if [ "${1:-}" = "--fix" ]; then
  "$formatter" -i --style=file "${files[@]}"
  exit 0
fi
bad=()
for f in "${files[@]}"; do
  if ! "$formatter" --style=file --dry-run --Werror "$f" >/dev/null 2>&1; then bad+=("$f"); fi
done
if [ ${#bad[@]} -gt 0 ]; then
  echo "check_format: clang-format ($("$formatter" --version | grep -o 'version [0-9.]*')) would change ${#bad[@]} file(s):" >&2
  printf '  %s\n' "${bad[@]}" >&2
  echo "run scripts/check_format.sh --fix and commit the result" >&2
  exit 1
fi
echo "check_format: ${#files[@]} files as clang-format writes them"
