#!/usr/bin/env bash
# End to end on the 77 real KITTI HDL-64E frames of kitti-tracking-0000-a: pcl_movers_detect
# (reading the PCDs on its reading thread, detecting, writing tracks.csv/json/summary.json) beside
# a PCL-only baseline (bench/bench_end_to_end.cpp: SACSegmentation RANSAC plane + Euclidean
# clustering + nearest-centroid association, reading and writing the same way), in one run.
# Usage: scripts/bench_end_to_end.sh BUILD_DIR   — prints one Markdown section to stdout.
set -euo pipefail
build=${1:?usage: $0 BUILD_DIR}
cd "$(dirname "$0")/.."
seq=$(realpath -m "${PCL_MOVERS_SHARED_DATA:-../shared/data}")/kitti-tracking-0000-a
detect="$build/apps/pcl_movers_detect"
bench="$build/bench/bench_end_to_end"
for x in "$detect" "$bench"; do
  [[ -x "$x" ]] || { echo "error: $x not found (build it in a Release build)" >&2; exit 1; }
done
echo "## End to end: files in, tracks out"
echo
if [[ ! -d "$seq/frames" ]]; then
  echo "Skipped: $seq is absent (../shared/data, KITTI tracking 0000 frames 0-76)."
  exit 0
fi
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
runs=3
detect_ms=()
for r in $(seq 1 $runs); do
  rm -rf "$tmp/out"
  t0=$(date +%s.%N)
  "$detect" "$seq" "$tmp/out" >/dev/null 2>&1
  t1=$(date +%s.%N)
  detect_ms+=("$(python3 -c "print(($t1 - $t0) * 1000 / 77)")")
done
cp "$tmp/out/summary.json" "$tmp/summary.json"
baseline_ms=()
for r in $(seq 1 $runs); do
  "$bench" --benchmark_format=json >"$tmp/b.json" 2>/dev/null
  baseline_ms+=("$(python3 -c "import json; print(json.load(open('$tmp/b.json'))['benchmarks'][0]['wall_ms_per_frame'])")")
done
python3 - "$tmp/summary.json" "${detect_ms[*]}" "${baseline_ms[*]}" <<'PY'
import json, statistics, sys
summary = json.load(open(sys.argv[1]))
d = sorted(float(x) for x in sys.argv[2].split())
b = sorted(float(x) for x in sys.argv[3].split())
md, mb = statistics.median(d), statistics.median(b)
t = summary["timings_ms"]
print("`scripts/bench_end_to_end.sh`: wall time of the whole run over the 77 frames (process start to")
print("exit for `pcl_movers_detect SEQ OUT`, defaults: poses.txt, registration mode; reading on its")
print("own thread, queue of 4), divided by 77; the baseline (`bench/bench_end_to_end.cpp`) reads the")
print("same PCDs, removes the RANSAC plane (`pcl::SACSegmentation`, 0.2 m, 100 iterations), clusters")
print("(`pcl::EuclideanClusterExtraction`, 0.5 m, 20-25000 points), associates by nearest centroid")
print("(2 m) and writes a row per cluster. Median of 3 runs each, same machine, same run.\n")
print("| pipeline | wall ms / frame (median of 3) | runs [ms/frame] |")
print("|---|---:|---|")
print(f"| pcl_movers_detect (end to end) | **{md:.1f}** | {', '.join(f'{x:.1f}' for x in d)} |")
print(f"| PCL baseline (SAC + Euclidean + nearest centroid) | **{mb:.1f}** | {', '.join(f'{x:.1f}' for x in b)} |")
print(f"\nRatio baseline / pcl_movers: **{mb / md:.2f}x**. pcl_movers' detection alone (summary.json")
print(f"`timings_ms.total`, without reading or writing): median {t['total']['median']:.1f} ms, mean "
      f"{t['total']['mean']:.1f} ms per frame; the issue's target is 10 ms wall per frame.")
PY
