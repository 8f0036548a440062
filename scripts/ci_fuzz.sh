#!/usr/bin/env bash
# libFuzzer CI job (issue #8, docs/reliability.md): builds the fuzz targets of test/fuzz with Clang
# (-fsanitize=fuzzer,address,undefined) in BUILD_DIR (default build-fuzz) and runs each for
# SECONDS (default 60) from its seed corpus. Fails on any crash, leak, timeout (> 10 s per input)
# or out-of-memory (> 2 GiB). Findings are written to BUILD_DIR/fuzz-artifacts/; turn each into a
# corpus file plus a regression test before fixing it.
# Needs: clang, libclang-rt-14-dev (Debian bookworm) or the matching compiler-rt for your clang.
# Usage: scripts/ci_fuzz.sh [BUILD_DIR] [SECONDS] [JOBS]
set -euo pipefail
ROOT="$(cd "$(dirname "$0")/.." && pwd)"
BUILD="${1:-$ROOT/build-fuzz}"
SECONDS_PER_TARGET="${2:-60}"
JOBS="${3:-2}"
LAUNCHER=()
command -v ccache >/dev/null && LAUNCHER=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache)

cmake -S "$ROOT" -B "$BUILD" -DCMAKE_BUILD_TYPE=RelWithDebInfo "${LAUNCHER[@]}" \
  -DCMAKE_C_COMPILER=clang -DCMAKE_CXX_COMPILER=clang++ \
  -DPCL_MOVERS_BUILD_FUZZERS=ON -DPCL_MOVERS_BUILD_APPS=OFF -DPCL_MOVERS_BUILD_TESTS=OFF \
  -DPCL_MOVERS_BUILD_BENCHMARKS=OFF
cmake --build "$BUILD" --target fuzz_pcd_pipeline fuzz_scenario -j"$JOBS"

export ASAN_OPTIONS="detect_leaks=1:abort_on_error=1"
export UBSAN_OPTIONS="halt_on_error=1:print_stacktrace=1"
ARTIFACTS="$BUILD/fuzz-artifacts"
mkdir -p "$ARTIFACTS"
status=0
for pair in "fuzz_pcd_pipeline:corpus_pcd" "fuzz_scenario:corpus_scenario"; do
  target="${pair%%:*}"
  seeds="$ROOT/test/fuzz/${pair##*:}"
  # New inputs go to a scratch corpus so the repository's seed corpus stays small.
  work="$BUILD/fuzz-corpus/$target"
  mkdir -p "$work"
  echo "== $target: ${SECONDS_PER_TARGET}s from $seeds"
  if ! "$BUILD/test/fuzz/$target" "$work" "$seeds" -max_total_time="$SECONDS_PER_TARGET" \
      -timeout=10 -rss_limit_mb=2048 -max_len=65536 -print_final_stats=1 \
      -artifact_prefix="$ARTIFACTS/$target-" 2>"$BUILD/$target.log"; then
    echo "FAIL: $target found a crash/leak/timeout; see $BUILD/$target.log and $ARTIFACTS" >&2
    grep -E "ERROR|SUMMARY|Test unit written" "$BUILD/$target.log" | head -20 >&2 || true
    status=1
  fi
  grep -E "stat::number_of_executed_units|stat::peak_rss_mb|cov:" "$BUILD/$target.log" | tail -3
done
exit $status
