#!/usr/bin/env bash
# The whole test suite: install what is missing, build, run every test that is not labelled slow.
# .ci/run calls exactly this. Usage: scripts/test.sh [BUILD_DIR]
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
build="${1:-$root/build}"
"$root/scripts/install-deps.sh"
"$root/scripts/build.sh" "$build"
ctest --test-dir "$build" --output-on-failure --timeout 900 -LE slow -j "${AFAM_TEST_JOBS:-2}"
