#!/usr/bin/env bash
# libFuzzer job (issue #8, docs/reliability.md): runs the fuzz targets of test/fuzz for SECONDS
# (default 60) each from their seed corpus. Fails on any crash, leak, UB, timeout (> 30 s per
# input: a hang, not a slow input — the long_run.yaml seed alone takes ~9 s CPU to simulate one
# frame in the instrumented -O1 build, so 10 s flagged it on a loaded machine) or out-of-memory
# (> 2 GiB). Findings are written to BUILD_DIR/fuzz-artifacts/; turn each
# into a corpus file plus a regression test before fixing it.
#
# BUILD_DIR already configured with -DPCL_MOVERS_BUILD_FUZZERS=ON (as scripts/ci_sanitizers.sh
# does in CI) is reused as it is; otherwise it is configured as a lean fuzz-only build (Clang,
# -fsanitize=fuzzer,address,undefined, no tools, tests or benchmarks).
# With JOBS >= 2 the targets run at the same time: each libFuzzer process is single-threaded, so
# two of them on two cores take SECONDS in all instead of 2 x SECONDS, with the same inputs per
# second each as run one after the other on an otherwise idle machine.
# FUZZ_SEED (environment): libFuzzer's -seed. Unset or 0, libFuzzer draws one (exploration: run
# it long and often before a release). CI sets a fixed seed so a commit's fuzz result can be
# replayed: the same seed on the same build runs the same input sequence, a faster machine just
# gets further along it (`FUZZ_SEED=1 scripts/ci_fuzz.sh build-san 300` on the sanitizer build of
# scripts/ci_sanitizers.sh, with its build-san/fuzz-corpus removed, covers what CI reaches in 60 s).
# Needs: clang, libclang-rt-14-dev (Debian bookworm) or the matching compiler-rt for your clang.
# Usage: [FUZZ_SEED=N] scripts/ci_fuzz.sh [BUILD_DIR] [SECONDS] [JOBS]
set -euo pipefail
ROOT="$(cd "$(dirname "$0")/.." && pwd)"
BUILD="${1:-$ROOT/build-fuzz}"
SECONDS_PER_TARGET="${2:-60}"
JOBS="${3:-2}"
SEED="${FUZZ_SEED:-0}"
TARGETS=(fuzz_pcd_pipeline:corpus_pcd fuzz_scenario:corpus_scenario)

if ! grep -qs "^PCL_MOVERS_BUILD_FUZZERS:BOOL=ON" "$BUILD/CMakeCache.txt"; then
  LAUNCHER=()
  command -v ccache >/dev/null && LAUNCHER=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache)
  GENERATOR=()
  command -v ninja >/dev/null && GENERATOR=(-G Ninja)
  cmake -S "$ROOT" -B "$BUILD" "${GENERATOR[@]}" -DCMAKE_BUILD_TYPE=RelWithDebInfo "${LAUNCHER[@]}" \
    -DCMAKE_C_COMPILER=clang -DCMAKE_CXX_COMPILER=clang++ \
    -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O1 -gline-tables-only" \
    -DCMAKE_C_FLAGS_RELWITHDEBINFO="-O1 -gline-tables-only" \
    -DPCL_MOVERS_BUILD_FUZZERS=ON -DPCL_MOVERS_BUILD_APPS=OFF -DPCL_MOVERS_BUILD_TESTS=OFF \
    -DPCL_MOVERS_BUILD_BENCHMARKS=OFF
fi
cmake --build "$BUILD" --target "${TARGETS[@]%%:*}" -j"$JOBS"

export ASAN_OPTIONS="detect_leaks=1:abort_on_error=1"
export UBSAN_OPTIONS="halt_on_error=1:print_stacktrace=1"
for s in llvm-symbolizer llvm-symbolizer-14; do
  if command -v "$s" >/dev/null; then
    export ASAN_SYMBOLIZER_PATH="$(command -v "$s")"
    break
  fi
done
ARTIFACTS="$BUILD/fuzz-artifacts"
mkdir -p "$ARTIFACTS"

run_target() {  # target seeds: runs one fuzzer, output in $BUILD/<target>.log
  local target="$1" seeds="$2"
  # New inputs go to a scratch corpus so the repository's seed corpus stays small.
  local work="$BUILD/fuzz-corpus/$target"
  mkdir -p "$work"
  "$BUILD/test/fuzz/$target" "$work" "$seeds" -max_total_time="$SECONDS_PER_TARGET" \
    -seed="$SEED" -timeout=30 -rss_limit_mb=2048 -max_len=65536 -print_final_stats=1 \
    -artifact_prefix="$ARTIFACTS/$target-" >"$BUILD/$target.log" 2>&1
}

report() {  # target rc
  local target="$1" rc="$2"
  if [ "$rc" -ne 0 ]; then
    echo "FAIL: $target found a crash/leak/timeout (exit $rc); see $BUILD/$target.log and $ARTIFACTS" >&2
    grep -E "ERROR|SUMMARY|Test unit written|runtime error" "$BUILD/$target.log" | head -20 >&2 || true
    return 1
  fi
  echo "$target: $(grep -E "^stat::number_of_executed_units" "$BUILD/$target.log" | awk '{print $2}') inputs," \
    "peak RSS $(grep -E "^stat::peak_rss_mb" "$BUILD/$target.log" | awk '{print $2}') MB," \
    "$(grep -oE "cov: [0-9]+ ft: [0-9]+ corp: [0-9]+" "$BUILD/$target.log" | tail -1)"
}

status=0
if [ "$JOBS" -ge 2 ]; then
  echo "== ${TARGETS[*]%%:*}: ${SECONDS_PER_TARGET} s, side by side, seed ${SEED} (0: random)"
  pids=()
  for pair in "${TARGETS[@]}"; do
    run_target "${pair%%:*}" "$ROOT/test/fuzz/${pair##*:}" &
    pids+=($!)
  done
  for i in "${!TARGETS[@]}"; do
    rc=0
    wait "${pids[$i]}" || rc=$?
    report "${TARGETS[$i]%%:*}" "$rc" || status=1
  done
else
  for pair in "${TARGETS[@]}"; do
    echo "== ${pair%%:*}: ${SECONDS_PER_TARGET} s"
    rc=0
    run_target "${pair%%:*}" "$ROOT/test/fuzz/${pair##*:}" || rc=$?
    report "${pair%%:*}" "$rc" || status=1
  done
fi
exit $status
