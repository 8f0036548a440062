#!/usr/bin/env bash
# Speed of the scene simulator (LidarSimulator::simulate: ray casting + ground truth of one frame,
# no file writing) on the shipped scenarios. Prints one Markdown section.
# Usage: bash scripts/bench_simulator.sh BUILD_DIR
set -euo pipefail
BUILD_DIR=${1:?usage: bench_simulator.sh BUILD_DIR}
BENCH="$BUILD_DIR/bench/bench_simulator"
[ -x "$BENCH" ] || { echo "error: $BENCH not built" >&2; exit 1; }
json=$(mktemp)
trap 'rm -f "$json"' EXIT
"$BENCH" --benchmark_format=json --benchmark_min_time=1.0 --benchmark_repetitions=3 \
  --benchmark_report_aggregates_only=true >"$json" 2>/dev/null
python3 - "$json" <<'PY'
import json, sys
data = json.load(open(sys.argv[1]))
rows = [b for b in data["benchmarks"] if b.get("aggregate_name") == "median"]
print("## Scene simulator (`LidarSimulator`)")
print()
print("Time to ray-cast one organized frame and compute its point labels and `objects.txt` rows")
print("(`bench/bench_simulator.cpp`; median of 3 runs, one core, file writing excluded). Target:")
print("≥ 20 HDL-64E frames/s for a scene of ~200 objects (`wooded`: rolling terrain, 130 trees,")
print("70 bushes with porous foliage, 6 movers). Frames/s are from CPU time: wall time is also")
print("shown and is only meaningful on an otherwise idle machine.")
print()
print("| scenario | sensor | objects | returns / frame | CPU ms / frame | wall ms / frame | frames / s (CPU) | Mrays / s (CPU) |")
print("|---|---|---:|---:|---:|---:|---:|---:|")
for b in rows:
    name = b["run_name"].split("/", 1)[-1]
    scene, sensor = name.rsplit("_", 1)
    scale = {"ns": 1e-6, "us": 1e-3, "ms": 1.0, "s": 1e3}[b["time_unit"]]
    cpu, real = b["cpu_time"] * scale, b["real_time"] * scale
    print(f"| {scene} | {sensor} | {b['objects']:.0f} | {b['returns']:.0f} | {cpu:.1f} | "
          f"{real:.1f} | {1000.0 / cpu:.1f} | {b['rays/s'] / 1e6:.2f} |")
print()
print("Culling: each object's bounding sphere is listed only in the azimuth columns it covers,")
print("nearest first, so a ray stops testing objects once the next one cannot be nearer than its hit.")
PY
