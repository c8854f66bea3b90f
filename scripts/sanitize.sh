#!/usr/bin/env bash
# Sanitizer builds of Core + Apps (no ParaView, no CUDA) and their tests:
#   asan: AddressSanitizer + UndefinedBehaviorSanitizer (-fno-sanitize-recover=all: any undefined
#         behaviour fails the test), runs every non-slow Core and CLI test (ctest -L core -LE slow);
#   tsan: ThreadSanitizer, runs the tests that start threads (cache, prefetch thread, encoder
#         workers, CPU ray caster, replay) and the fault tests.
# Usage: scripts/sanitize.sh [asan|tsan|all] [BUILD_ROOT]   (default: all, BUILD_ROOT=build-sanitize)
# scripts/test.sh runs it after the main suite. Build dirs: BUILD_ROOT/asan, BUILD_ROOT/tsan.
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
what="${1:-all}"
base="${2:-$root/build-sanitize}"
jobs="${AFAM_JOBS:-$(nproc)}"
generator=()
if command -v ninja >/dev/null 2>&1; then generator=(-G Ninja); fi

# Tests that run more than one thread (regex over ctest names); kept in one place.
tsan_tests='^(Cache|BlockLoader|Prefetch|Encoder|EncodeTeam|EncodeRun|RunTeam|ResidualCoding|StepSharing|GrayScott|Raycast|Renderer|Limits|Fault|TemporaryFile|NcpVerdicts|RankRenderers|BlockSampling|TaskStream|WorkerPool|PipelineRun|SlotCache)\.|^VolumeFormats\.EveryLayout|ConcurrentReads|^afam_cli_roundtrip$'
# Left out of TSan: the two fast-vs-exhaustive search comparisons. They run the same worker pool
# as the other encoder tests but take 12 CPU minutes under TSan; ASan+UBSan runs them.
tsan_skip='FastEqualsExhaustive'

configure_and_build() {  # dir, sanitizer flags
  local dir="$1" flags="$2"
  cmake -S "$root" -B "$dir" "${generator[@]}" -DCMAKE_BUILD_TYPE=Debug \
    -DCMAKE_CXX_FLAGS_DEBUG="-O1 -g" -DCMAKE_C_FLAGS_DEBUG="-O1 -g" \
    -DCMAKE_CXX_FLAGS="$flags" -DCMAKE_EXE_LINKER_FLAGS="$flags" \
    -DAFAM_ENABLE_PARAVIEW=OFF -DAFAM_ENABLE_CUDA=OFF >"$base/$(basename "$dir").configure.log" 2>&1 ||
    { tail -30 "$base/$(basename "$dir").configure.log"; return 1; }
  cmake --build "$dir" -j "$jobs" --target afam afam_core_tests afam_pool_ledger_tests
}

run_asan() {
  local dir="$base/asan"
  mkdir -p "$base"
  configure_and_build "$dir" "-fsanitize=address,undefined -fno-sanitize-recover=all -fno-omit-frame-pointer"
  ASAN_OPTIONS="detect_leaks=1:abort_on_error=0:halt_on_error=1:strict_string_checks=1:detect_stack_use_after_return=1" \
  UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=1" \
    ctest --test-dir "$dir" --output-on-failure --timeout 900 -L core -LE slow -j "${AFAM_TEST_JOBS:-2}"
}

run_tsan() {
  local dir="$base/tsan"
  mkdir -p "$base"
  configure_and_build "$dir" "-fsanitize=thread -fno-omit-frame-pointer"
  TSAN_OPTIONS="halt_on_error=1:second_deadlock_stack=1" \
    ctest --test-dir "$dir" --output-on-failure --timeout 900 -L core -LE slow -R "$tsan_tests" -E "$tsan_skip" \
      -j "${AFAM_TEST_JOBS:-2}"
}

case "$what" in
  asan) run_asan ;;
  tsan) run_tsan ;;
  all) run_asan; run_tsan ;;
  *) echo "usage: scripts/sanitize.sh [asan|tsan|all] [BUILD_ROOT]" >&2; exit 2 ;;
esac
