#!/usr/bin/env bash
# The whole test suite: install what is missing, check the format (scripts/check_format.sh), build,
# run every test that is not labelled slow,
# then the VTK module and its image tests against VTK alone (scripts/plain_vtk.sh), the sanitizer
# builds (scripts/sanitize.sh: ASan+UBSan over the Core and CLI tests, TSan over the threaded ones) and a fixed number of executions of every fuzz target (scripts/fuzz.sh).
# .ci/run calls exactly this. Usage: scripts/test.sh [BUILD_DIR]
# AFAM_SKIP_PLAIN_VTK=1 / AFAM_SKIP_SANITIZE=1 / AFAM_SKIP_FUZZ=1 leave out those steps (local runs).
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
build="${1:-$root/build}"
"$root/scripts/install-deps.sh"
"$root/scripts/check_format.sh"  # fails on a file clang-format would change
"$root/scripts/build.sh" "$build"
ctest --test-dir "$build" --output-on-failure --timeout 900 -LE slow -j "${AFAM_TEST_JOBS:-2}"
if [ -z "${AFAM_SKIP_PLAIN_VTK:-}" ]; then
  "$root/scripts/plain_vtk.sh" "$build-vtk"
fi
if [ -z "${AFAM_SKIP_SANITIZE:-}" ]; then
  "$root/scripts/sanitize.sh" all "$build-sanitize"
fi
if [ -z "${AFAM_SKIP_FUZZ:-}" ]; then
  "$root/scripts/fuzz.sh" --build "$build-fuzz"
fi
