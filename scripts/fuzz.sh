#!/usr/bin/env bash
# Builds the libFuzzer targets of Testing/Fuzz with clang (AddressSanitizer + UndefinedBehavior-
# Sanitizer, -fno-sanitize-recover=all), writes their seed corpus (make_fuzz_seeds: small valid
# files made by the encoder and writer) and runs each target.
#   scripts/fuzz.sh [--runs N | --seconds S] [--parallel P] [--build DIR] [--prebuilt DIR] [TARGET...]
# --runs N: N executions per target and process (default $AFAM_FUZZ_RUNS or 30000, the CI step);
# --seconds S: run each target for S seconds instead; --parallel P: P processes per target
# sharing one corpus (default 1); --prebuilt DIR: run the binaries and seeds (DIR/fuzz-seeds)
# already in DIR, no compiler needed (a machine without clang). TARGETs: afam_file raw_file trajectory lstm_weights (default all).
# A crash, a sanitizer report, a leak, an out-of-memory (> 2 GB) or a hang (one input > 10 s)
# fails the script; the input is left in BUILD/fuzz-artifacts/. Prints executions per target.
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
build="$root/build-fuzz"
runs="${AFAM_FUZZ_RUNS:-30000}"
seconds=""
parallel=1
prebuilt=""
targets=()
while [ $# -gt 0 ]; do
  case "$1" in
    --runs) runs="$2"; shift 2 ;;
    --seconds) seconds="$2"; shift 2 ;;
    --parallel) parallel="$2"; shift 2 ;;
    --build) build="$2"; shift 2 ;;
    --prebuilt) prebuilt="$(cd "$2" && pwd)"; shift 2 ;;
    -h|--help) sed -n 2,13p "$0"; exit 0 ;;
    *) targets+=("$1"); shift ;;
  esac
done
[ ${#targets[@]} -gt 0 ] || targets=(afam_file raw_file volume_header trajectory lstm_weights)
jobs="${AFAM_JOBS:-$(nproc)}"
generator=()
if command -v ninja >/dev/null 2>&1; then generator=(-G Ninja); fi
clangxx="${AFAM_FUZZ_CXX:-$(command -v clang++-14 || command -v clang++)}"
clangc="${AFAM_FUZZ_CC:-$(command -v clang-14 || command -v clang)}"

bins="$build/Testing/Fuzz"
seeds="$build/fuzz-seeds"
build_fuzzers() {
  flags="-fsanitize=fuzzer-no-link,address,undefined -fno-sanitize-recover=all -fno-omit-frame-pointer"
  mkdir -p "$build"
  cmake -S "$root" -B "$build" "${generator[@]}" -DCMAKE_BUILD_TYPE=RelWithDebInfo \
    -DCMAKE_CXX_COMPILER="$clangxx" -DCMAKE_C_COMPILER="$clangc" \
    -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O1 -g" -DCMAKE_CXX_FLAGS="$flags" \
    -DCMAKE_EXE_LINKER_FLAGS="-fsanitize=address,undefined" \
    -DAFAM_ENABLE_PARAVIEW=OFF -DAFAM_ENABLE_CUDA=OFF -DAFAM_BUILD_FUZZERS=ON >"$build/configure.log" 2>&1 ||
    { tail -30 "$build/configure.log"; exit 1; }
  cmake --build "$build" -j "$jobs" --target make_fuzz_seeds $(printf 'fuzz_%s ' "${targets[@]}")
  rm -rf "$seeds"
  "$bins/make_fuzz_seeds" "$seeds"
}
if [ -n "$prebuilt" ]; then
  bins="$prebuilt"
  seeds="$prebuilt/fuzz-seeds"
  mkdir -p "$build"
else
  build_fuzzers
fi
mkdir -p "$build/fuzz-artifacts" "$build/fuzz-logs"

max_len() {
  case "$1" in
    afam_file) echo 8192 ;;
    *) echo 4096 ;;
  esac
}

failed=0
for t in "${targets[@]}"; do
  corpus="$build/fuzz-corpus/$t"
  mkdir -p "$corpus"
  limit=(-runs="$runs")
  [ -z "$seconds" ] || limit=(-max_total_time="$seconds")
  t0=$(date +%s)
  pids=()
  rm -f "$build"/fuzz-logs/"$t"-*.log
  for ((p = 0; p < parallel; ++p)); do
    "$bins/fuzz_$t" "$corpus" "$seeds/$t" "${limit[@]}" -seed=$((1000 + p)) \
      -max_len="$(max_len "$t")" -timeout=10 -rss_limit_mb=2048 -print_final_stats=1 \
      -artifact_prefix="$build/fuzz-artifacts/$t-" >"$build/fuzz-logs/$t-$p.log" 2>&1 &
    pids+=($!)
  done
  rc=0
  for pid in "${pids[@]}"; do wait "$pid" || rc=$?; done
  execs=$(cat "$build"/fuzz-logs/"$t"-*.log | { grep -oE 'stat::number_of_executed_units: [0-9]+' || true; } |
          awk '{s += $2} END {print s + 0}')
  cov=$({ grep -hoE 'cov: [0-9]+' "$build"/fuzz-logs/"$t"-0.log || true; } | tail -1 | awk '{print $2}')
  printf 'fuzz_%-13s executions=%s processes=%s seconds=%s coverage_edges=%s %s\n' "$t" "$execs" "$parallel" \
    "$(( $(date +%s) - t0 ))" "${cov:-?}" "$([ $rc -eq 0 ] && echo clean || echo "FAILED rc=$rc")"
  if [ $rc -ne 0 ]; then
    failed=1
    grep -hE "ERROR|SUMMARY|runtime error|Test unit written" "$build"/fuzz-logs/"$t"-*.log | head -20 || true
  fi
done
exit $failed
