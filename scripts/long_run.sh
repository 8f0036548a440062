#!/usr/bin/env bash
# Long-run check (issue #8, docs/reliability.md): MoverDetector on a 3000-frame simulated sequence
# (test/long_run/long_run.yaml: a VLP-16 circling a small scene with circling movers, 5 min at
# 10 Hz), frame by frame in one process. Prints a Markdown section with VmRSS at frames
# 300/1000/2000/3000 and detector ms/frame per 500 frames. Fails when RSS after frame 3000 is more
# than 10 % above its value at frame 300, or the last full 500-frame block is more than 25 %
# slower than the second (the first one includes warm-up).
# Usage: scripts/long_run.sh BUILD_DIR [FRAMES]   (BUILD_DIR: a Release build with tests on)
set -euo pipefail
ROOT="$(cd "$(dirname "$0")/.." && pwd)"
BUILD="${1:?usage: scripts/long_run.sh BUILD_DIR [FRAMES]}"
FRAMES="${2:-3000}"
DRIVER="$BUILD/test/long_run/pcl_movers_long_run"
if [[ ! -x "$DRIVER" ]]; then
  cmake --build "$BUILD" --target pcl_movers_long_run -j2 >&2
fi
start=$(date +%s)
set +e
table="$("$DRIVER" "$ROOT/test/long_run/long_run.yaml" --frames "$FRAMES" --block 500)"
rc=$?
set -e
end=$(date +%s)
echo "## Long run: $FRAMES frames"
echo
echo "\`scripts/long_run.sh\`: \`MoverDetector<PointXYZI>\` with default parameters on"
echo "\`test/long_run/long_run.yaml\` (VLP-16, 16×1800 range image, ego and movers on circles so the"
echo "scene stays busy), simulated in memory frame by frame; VmRSS from \`/proc/self/status\`."
echo "Wall time $((end - start)) s including the simulation, $(nproc) cores, $(date -u +%Y-%m-%d)."
echo
echo "$table"
exit $rc
