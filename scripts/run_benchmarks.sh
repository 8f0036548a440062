#!/usr/bin/env bash
# Regenerates docs/benchmarks.md (scripts/bench_*.sh) and docs/evaluation.md (scripts/eval_*.sh)
# from a Release build. Each script prints one Markdown section; this adds the machine and date.
# Usage: bash scripts/run_benchmarks.sh [BUILD_DIR] [bench|eval|all]
set -euo pipefail
cd "$(dirname "$0")/.."
BUILD_DIR=$(realpath "${1:-build}")
WHAT=${2:-all}
grep -q 'CMAKE_BUILD_TYPE:STRING=Release' "$BUILD_DIR/CMakeCache.txt" ||
  { echo "error: $BUILD_DIR is not a Release build; timings would mislead" >&2; exit 1; }
machine() {
  # The speed ratios against PCL's classes hold per machine only: on two machines with the same
  # CPU name and PCL package, ICP and NDT took 2-3 times as long on one as on the other while
  # BhattacharyaRegistration took the same time (docs/benchmarks.md, 2026-11-25 vs 2026-12-01).
  # The clock and FLANN (the kd-tree ICP and NDT search in) tell such machines apart.
  echo "Machine: $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2- | sed 's/^ *//') at $(grep -m1 'cpu MHz' /proc/cpuinfo | cut -d: -f2 | awk '{printf "%.0f", $1}') MHz, $(nproc) cores, $(free -g | awk '/Mem:/{print $2}') GiB RAM; $(g++ --version | head -1); PCL $(dpkg-query -W -f='${Version}' libpcl-dev 2>/dev/null || echo '?'), FLANN $(dpkg-query -W -f='${Version}' libflann-dev 2>/dev/null || echo '?')."
  echo "Generated $(date -u '+%Y-%m-%d %H:%M UTC') by \`scripts/run_benchmarks.sh\` — do not edit by hand."
}
generate() {  # $1 = bench|eval, $2 = output, $3 = title
  local tmp; tmp=$(mktemp)
  { echo "# $3"; echo; machine; echo; } >"$tmp"
  for s in scripts/$1_*.sh; do
    [ -e "$s" ] || continue
    echo "running $s ..." >&2
    if ! bash "$s" "$BUILD_DIR" >>"$tmp"; then echo "error: $s failed" >&2; rm -f "$tmp"; exit 1; fi
    echo >>"$tmp"
  done
  mv "$tmp" "$2"
  echo "wrote $2" >&2
}
mkdir -p docs
[ "$WHAT" = eval ] || generate bench docs/benchmarks.md "Benchmarks"
[ "$WHAT" = bench ] || generate eval docs/evaluation.md "Evaluation"
