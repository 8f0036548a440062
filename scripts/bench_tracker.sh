#!/usr/bin/env bash
# Thread CPU time of the tracking stage alone (MoverTracker::update) on the 77 real KITTI HDL-64E
# frames of kitti-tracking-0000-a, from a Release build.
# Usage: scripts/bench_tracker.sh BUILD_DIR   — prints one Markdown section to stdout.
set -euo pipefail
build=${1:?usage: $0 BUILD_DIR}
bench="$build/bench/bench_tracker"
if [[ ! -x "$bench" ]]; then
  echo "error: $bench not found (build the bench_tracker target in a Release build)" >&2
  exit 1
fi
json=$(mktemp)
trap 'rm -f "$json"' EXIT
"$bench" --benchmark_format=json >"$json" 2>/dev/null
python3 - "$json" <<'PY'
import json, sys
data = json.load(open(sys.argv[1]))
print("## Tracker (tracking stage alone)\n")
print("`bench/bench_tracker.cpp`: `MoverTracker<PointXYZI>::update()` over the 77 real KITTI HDL-64E")
print("frames of `kitti-tracking-0000-a`; its inputs (world-frame clusters, free-space scans) are")
print("computed before timing. Thread CPU time per frame (the fastest of 3 repetitions of each frame,")
print("then the median and the mean over the frames) and Bhattacharyya registrations per frame.\n")
print("| mode | track CPU median [ms] | track CPU mean [ms] | registrations median | registrations mean |")
print("|---|---:|---:|---:|---:|")
for b in data.get("benchmarks", []):
    if b.get("error_occurred"):
        print(f"| {b['name']} | skipped: {b.get('error_message', '')} |")
        continue
    mode = "registration" if "Registration" in b["name"] else "centroid"
    print(f"| {mode} | {b.get('track_cpu_ms', float('nan')):.1f} | {b.get('track_cpu_mean_ms', float('nan')):.1f}"
          f" | {b.get('registrations', 0):.0f} | {b.get('registrations_mean', 0):.1f} |")
PY
