#!/usr/bin/env bash
# The CI sanitizer + fuzz job (issue #8, docs/reliability.md). One Clang build serves both:
#   1. configure BUILD_DIR (default build-san) RelWithDebInfo at -O1 -gline-tables-only with
#      -DPCL_MOVERS_SANITIZE=ON (ASan+UBSan on everything) and -DPCL_MOVERS_BUILD_FUZZERS=ON
#      (coverage instrumentation, libFuzzer targets), no benchmarks, no long-run driver;
#   2. build the library, every tool, every test and both fuzz targets;
#   3. run the whole ctest suite (viewer tests under xvfb-run) with leak detection on and any UB
#      report fatal;
#   4. simulate the sample scenario and run pcl_movers_detect on it twice, requiring
#      byte-identical tracks.csv (determinism);
#   5. run each fuzz target for FUZZ_SECONDS (default 60) from its seed corpus
#      (scripts/ci_fuzz.sh, on the same build).
# Any sanitizer report aborts the process, so a non-zero exit of this script means a finding.
# Needs clang, libclang-rt-14-dev (ASan/UBSan/libFuzzer runtimes) and llvm (llvm-symbolizer, for
# readable stack traces): scripts/setup.sh installs them.
# Usage: scripts/ci_sanitizers.sh [BUILD_DIR] [JOBS] [FUZZ_SECONDS]   (FUZZ_SECONDS=0: no fuzzing)
set -euo pipefail
ROOT="$(cd "$(dirname "$0")/.." && pwd)"
BUILD="${1:-$ROOT/build-san}"
JOBS="${2:-2}"
FUZZ_SECONDS="${3:-60}"
CC_BIN="${CC_SAN:-clang}"
CXX_BIN="${CXX_SAN:-clang++}"
command -v "$CXX_BIN" >/dev/null || {
  echo "error: $CXX_BIN not found (apt-get install clang libclang-rt-14-dev)" >&2
  exit 1
}
LAUNCHER=()
command -v ccache >/dev/null && LAUNCHER=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache)
GENERATOR=()
command -v ninja >/dev/null && GENERATOR=(-G Ninja)

# PCL/VTK/Boost are not instrumented; ASan still sees every malloc/free of the process. Third-party
# leaks go in scripts/lsan.supp with a comment naming the library and why the leak is not ours
# (two today: libpcap's handle in PCL's capture thread, and the packets left in PCL's HDLGrabber queue
# when a live grabber stops; see docs/reliability.md).
export ASAN_OPTIONS="detect_leaks=1:abort_on_error=1:strict_string_checks=1:detect_stack_use_after_return=1:check_initialization_order=1"
export UBSAN_OPTIONS="halt_on_error=1:print_stacktrace=1"
if [[ -f "$ROOT/scripts/lsan.supp" ]]; then
  export LSAN_OPTIONS="suppressions=$ROOT/scripts/lsan.supp:print_suppressions=0"
fi
# Clang's runtime symbolizes stack traces with llvm-symbolizer (Debian: package llvm).
for s in llvm-symbolizer llvm-symbolizer-14; do
  if command -v "$s" >/dev/null; then
    export ASAN_SYMBOLIZER_PATH="$(command -v "$s")"
    break
  fi
done

t0=$(date +%s)
stamp() { echo "-- $1: $(($(date +%s) - t0)) s since start of the sanitizer job"; }

echo "== configure + build (Clang, ASan+UBSan, libFuzzer instrumentation) in $BUILD"
mkdir -p "$BUILD"
# -gline-tables-only: file:line in sanitizer stack traces is all we need; full -g makes every
# PCL-heavy translation unit and every link markedly slower.
cmake -S "$ROOT" -B "$BUILD" "${GENERATOR[@]}" -DCMAKE_BUILD_TYPE=RelWithDebInfo "${LAUNCHER[@]}" \
  -DCMAKE_C_COMPILER="$CC_BIN" -DCMAKE_CXX_COMPILER="$CXX_BIN" \
  -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O1 -gline-tables-only" \
  -DCMAKE_C_FLAGS_RELWITHDEBINFO="-O1 -gline-tables-only" \
  -DPCL_MOVERS_SANITIZE=ON -DPCL_MOVERS_BUILD_FUZZERS=ON -DPCL_MOVERS_BUILD_BENCHMARKS=OFF \
  >"$BUILD/configure.log" 2>&1 || { cat "$BUILD/configure.log" >&2; exit 1; }
cmake --build "$BUILD" -j"$JOBS"
stamp "build"

echo "== ctest under ASan+UBSan"
CTEST=(ctest --test-dir "$BUILD" --output-on-failure -j"$JOBS" --timeout 900)
XVFB=()
if [ -z "${DISPLAY:-}" ] && command -v xvfb-run >/dev/null; then
  XVFB=(xvfb-run -a -s "-screen 0 1280x1024x24")
fi
"${XVFB[@]}" "${CTEST[@]}" -E '^(ViewerTool|LiveViewer|BadInputs|VelodyneCapture|LiveInput|FrameStream)\.'
# The viewer tests run pcl_movers_viewer, which loads the Mesa GL driver under Xvfb. That driver
# leaves ~112 bytes allocated at exit from a module it has already unloaded (LSan reports
# "<unknown module>", so no suppression file can name it). Leak detection is therefore off for
# the viewer tests only; every ASan memory-error check and UBSan stay on. The viewer reads
# captures and sensors through PCL's grabbers too (--pcap, --live): see the mismatch note below.
ASAN_OPTIONS="${ASAN_OPTIONS/detect_leaks=1/detect_leaks=0}:alloc_dealloc_mismatch=0" \
  "${XVFB[@]}" "${CTEST[@]}" -R '^(ViewerTool|LiveViewer)\.'
# PCL's Velodyne grabbers (pcl::HDLGrabber::initialize, used to decode captures and for their laser
# tables) allocate point clouds inside Debian's libpcl_io, built as C++14, where pcl::PointCloud
# has Eigen's aligned operator new; our C++17 code releases them through shared_ptr with the
# global operator delete. ASan reports alloc-dealloc-mismatch; on x86-64 glibc both sides are
# malloc/free (Eigen's aligned malloc is plain malloc there), and nothing on our side can pair
# them. The tests that construct a grabber (the capture tests, the live-input and frame-source
# tests, and the bad-input matrix, whose fixture writes a capture) run with that one check off;
# every other check stays on.
ASAN_OPTIONS="$ASAN_OPTIONS:alloc_dealloc_mismatch=0" "${XVFB[@]}" "${CTEST[@]}" \
  -R '^(BadInputs|VelodyneCapture|LiveInput|FrameStream)\.'
stamp "ctest"

echo "== simulate + detect on data/scenarios/sample.yaml under ASan+UBSan"
WORK="$(mktemp -d)"
trap 'rm -rf "$WORK"' EXIT
"$BUILD/apps/pcl_movers_simulate" "$ROOT/data/scenarios/sample.yaml" "$WORK/sample"
"$BUILD/apps/pcl_movers_detect" "$WORK/sample" "$WORK/run1"
"$BUILD/apps/pcl_movers_detect" "$WORK/sample" "$WORK/run2"
test -s "$WORK/run1/tracks.csv"
if ! cmp "$WORK/run1/tracks.csv" "$WORK/run2/tracks.csv"; then
  echo "FAIL: two detect runs on the same input gave different tracks.csv" >&2
  diff "$WORK/run1/tracks.csv" "$WORK/run2/tracks.csv" | head -20 >&2
  exit 1
fi
echo "tracks.csv: $(($(wc -l <"$WORK/run1/tracks.csv") - 1)) rows, identical in both runs"
stamp "detect"

if [ "$FUZZ_SECONDS" -gt 0 ]; then
  bash "$ROOT/scripts/ci_fuzz.sh" "$BUILD" "$FUZZ_SECONDS" "$JOBS"
  stamp "fuzz"
fi
echo "OK: no sanitizer reports, deterministic output, no fuzzer finding"
