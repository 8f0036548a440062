#!/usr/bin/env bash
# The main job on the bundled sample: simulated sequence → movers (tracks.csv) → the paper's metrics.
# Usage: bash scripts/demo.sh [BUILD_DIR] [OUT_DIR]
set -euo pipefail
cd "$(dirname "$0")/.."
BUILD_DIR=${1:-build}
OUT=${2:-out/sample}
BIN="$BUILD_DIR/apps"
for tool in pcl_movers_simulate pcl_movers_detect pcl_movers_eval; do
  [ -x "$BIN/$tool" ] || { echo "error: $BIN/$tool not built: run 'bash scripts/setup.sh' first" >&2; exit 1; }
done
SAMPLE=data/sample
if [ ! -d "$SAMPLE/frames" ]; then
  # The sample is generated, not stored: same scenario + seed give byte-identical frames.
  SAMPLE="$BUILD_DIR/sample"
  [ -d "$SAMPLE/frames" ] || "$BIN/pcl_movers_simulate" data/scenarios/sample.yaml "$SAMPLE" --overwrite
fi
"$BIN/pcl_movers_detect" "$SAMPLE" "$OUT" --overwrite
"$BIN/pcl_movers_eval" "$SAMPLE/objects.txt" "$OUT/tracks.csv" --sequence "$SAMPLE" --sector-deg 180
