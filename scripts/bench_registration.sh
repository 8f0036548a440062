#!/usr/bin/env bash
# Registration benchmark: BhattacharyaRegistration vs pcl::IterativeClosestPoint,
# pcl::GeneralizedIterativeClosestPoint and pcl::NormalDistributionsTransform on the same object
# pairs (simulated + real KITTI), printed as one Markdown section on stdout.
# Usage: scripts/bench_registration.sh BUILD_DIR   (a Release build with bench_registration built)
set -euo pipefail
if [[ $# -ne 1 ]]; then
  echo "usage: $0 BUILD_DIR" >&2
  exit 2
fi
exe="$1/bench/bench_registration"
if [[ ! -x "$exe" ]]; then
  echo "$0: $exe not found; build the bench_registration target first" >&2
  exit 1
fi
"$exe" --report
echo
echo "Google Benchmark, one \`align()\` per iteration on 40 simulated pairs (real time is wall clock"
echo "on a shared machine, CPU is this thread's time):"
echo
echo '```'
"$exe" --benchmark_min_time=0.2 2>/dev/null | sed -n '/^Benchmark/,$p'
echo '```'
