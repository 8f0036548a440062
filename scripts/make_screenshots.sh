#!/usr/bin/env bash
# Regenerates the viewer screenshots of docs/viewer.md (docs/images/viewer_*.png) with the tools
# of a build dir: pcl_movers_detect on the simulated sample, on KITTI tracking 0000 and on the
# unlabelled KITTI city-22 drive, then pcl_movers_viewer off-screen. Runs under xvfb-run when
# there is no X display.
#
#   scripts/make_screenshots.sh BUILD_DIR [SHARED_DATA_DIR]
#
# SHARED_DATA_DIR defaults to ../shared/data next to the source tree; the KITTI image is skipped
# (with a message) when it is missing.
set -euo pipefail

source "$(dirname "$0")/viewer_common.sh"
images="$root/docs/images"
mkdir -p "$images"

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

# 3. KITTI city-22 (real, unlabelled, no poses: pcl_movers_detect estimates them): frame 4.
city="$shared/kitti-city-22"
if [[ -d "$city" ]]; then
  "$apps/pcl_movers_detect" "$city" "$work/city_det" --labelled-clouds >/dev/null
  run_viewer "$city" --detections "$work/city_det" --frames 4 \
    --size 1280x720 --camera chase --screenshot-dir "$work/city_chase" >/dev/null
  cp "$work/city_chase/000004.png" "$images/viewer_city.png"
  echo "wrote docs/images/viewer_city.png"
else
  echo "KITTI data not found in $city: skipped the city-22 screenshot" >&2
fi
