#!/usr/bin/env bash
# Regenerates the viewer screenshots of docs/viewer.md (docs/images/viewer_*.png) with the tools
# of a build dir: pcl_movers_detect on the simulated sample and on KITTI tracking 0000, then
# pcl_movers_viewer off-screen. Runs under xvfb-run when there is no X display.
#
#   scripts/make_screenshots.sh BUILD_DIR [SHARED_DATA_DIR]
#
# SHARED_DATA_DIR defaults to ../shared/data next to the source tree; the KITTI image is skipped
# (with a message) when it is missing.
set -euo pipefail

if [[ $# -lt 1 || "$1" == "-h" || "$1" == "--help" ]]; then
  sed -n '2,9p' "$0" | sed 's/^# \{0,1\}//'
  exit $([[ $# -lt 1 ]] && echo 1 || echo 0)
fi
root="$(cd "$(dirname "$0")/.." && pwd)"
build="$(cd "$1" && pwd)"
shared="${2:-$root/../shared/data}"
apps="$build/apps"
for tool in pcl_movers_viewer pcl_movers_detect pcl_movers_simulate; do
  [[ -x "$apps/$tool" ]] || { echo "error: $apps/$tool not built" >&2; exit 1; }
done
images="$root/docs/images"
mkdir -p "$images"
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT

# Off-screen rendering still needs an X server (Debian's VTK is built for X11).
run_viewer() {
  if [[ -n "${DISPLAY:-}" ]]; then
    "$apps/pcl_movers_viewer" "$@"
  else
    xvfb-run -a -s "-screen 0 1920x1080x24" "$apps/pcl_movers_viewer" "$@"
  fi
}

# 1. Simulated scene: data/sample if it exists, else simulated from data/scenarios/sample.yaml.
sample="$root/data/sample"
if [[ ! -d "$sample" ]]; then
  echo "data/sample not found: simulating data/scenarios/sample.yaml" >&2
  "$apps/pcl_movers_simulate" "$root/data/scenarios/sample.yaml" "$work/sample" >/dev/null
  sample="$work/sample"
fi
"$apps/pcl_movers_detect" "$sample" "$work/sample_det" --labelled-clouds >/dev/null
run_viewer "$sample" --detections "$work/sample_det" --ground-truth --frames 25 \
  --size 1280x720 --camera chase --screenshot-dir "$work/sample_shots" >/dev/null
cp "$work/sample_shots/000025.png" "$images/viewer_sample.png"
echo "wrote docs/images/viewer_sample.png"

# 2. KITTI tracking 0000 (real HDL-64E scans): chase and bird's-eye views of frame 30.
kitti="$shared/kitti-tracking-0000-a"
if [[ -d "$kitti" ]]; then
  "$apps/pcl_movers_detect" "$kitti" "$work/kitti_det" --labelled-clouds >/dev/null
  run_viewer "$kitti" --detections "$work/kitti_det" --ground-truth --frames 30 \
    --size 1280x720 --camera chase --screenshot-dir "$work/kitti_chase" >/dev/null
  cp "$work/kitti_chase/000030.png" "$images/viewer_kitti.png"
  run_viewer "$kitti" --detections "$work/kitti_det" --ground-truth --frames 30 \
    --size 1280x720 --camera bird --screenshot-dir "$work/kitti_bird" >/dev/null
  cp "$work/kitti_bird/000030.png" "$images/viewer_kitti_bird.png"
  echo "wrote docs/images/viewer_kitti.png, docs/images/viewer_kitti_bird.png"
else
  echo "KITTI data not found in $kitti: skipped the KITTI screenshots" >&2
fi
