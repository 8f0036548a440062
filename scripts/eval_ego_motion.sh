#!/usr/bin/env bash
# Drift of EgoMotionEstimator (pcl_movers_ego_motion) against reference poses: KITTI odometry 00
# (6 frames, GPS/INS ground truth of camera 0 mapped to the velodyne with calib Tr), KITTI
# tracking 0000-a (77 frames, reference poses from GICP) and, when they can be generated, the
# simulated scenes (exact poses). Prints one Markdown section.
# Usage: bash scripts/eval_ego_motion.sh BUILD_DIR [SHARED_DATA]
set -euo pipefail
BUILD_DIR=$(cd "${1:?usage: eval_ego_motion.sh BUILD_DIR [SHARED_DATA]}" && pwd)
SRC_DIR=$(cd "$(dirname "$0")/.." && pwd)
DATA=${2:-$SRC_DIR/../shared/data}
EGO="$BUILD_DIR/apps/pcl_movers_ego_motion"
SIM="$BUILD_DIR/apps/pcl_movers_simulate"
[ -x "$EGO" ] || { echo "error: $EGO not built (cmake --build $BUILD_DIR --target pcl_movers_ego_motion)" >&2; exit 1; }
SCENES="$BUILD_DIR/eval-scenes"
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

# run NAME SEQ REFERENCE [extra args]: one table row
run() {
  local name=$1 seq=$2 ref=$3
  shift 3
  local out="$work/$name.md" start end
  start=$(date +%s.%N)
  if ! "$EGO" "$seq" "$work/$name.poses" --reference "$ref" "$@" >"$out" 2>"$work/$name.err"; then
    echo "error: pcl_movers_ego_motion failed on $seq:" >&2
    cat "$work/$name.err" >&2
    exit 1
  fi
  end=$(date +%s.%N)
  get() { awk -F'|' -v k="$1" '$2 ~ k {gsub(/ /, "", $3); print $3}' "$out"; }
  printf '| %s | %s | %s | %s | %s | %s | %s | %s |\n' "$name" "$(get '^ frames')" \
    "$(get 'distance travelled')" "$(get 'final translation error')" \
    "$(get 'error per metre')" "$(get 'final yaw error')" "$(get 'final rotation error')" \
    "$(get 'time per frame')"
}

echo "## Ego-motion estimation (\`EgoMotionEstimator\`, \`pcl_movers_ego_motion\`)"
echo
echo "Poses estimated from the scans alone (point-to-plane ICP against a local map of the last 8"
echo "keyframes, 0.5 m voxels, coarse-then-trimmed iterations, constant-velocity guess; default"
echo "parameters for every set), compared with the reference poses after re-basing both on frame 0."
echo "Error per metre = final translation error / distance travelled. Rotation error includes"
echo "roll and pitch. Time per frame is wall-clock on the machine that ran this script (reading"
echo "the scan excluded), so it depends on the load."
echo
echo "| sequence | frames | travelled [m] | final transl. error [m] | error / metre [%] | final yaw error [deg] | final rotation error [deg] | ms / frame |"
echo "|---|---:|---:|---:|---:|---:|---:|---:|"
if [ -d "$DATA/kitti-odometry-00" ]; then
  run kitti-odometry-00 "$DATA/kitti-odometry-00" "$DATA/kitti-odometry-00/poses_cam0.txt" \
    --calib "$DATA/kitti-odometry-00/calib.txt"
fi
if [ -d "$DATA/kitti-tracking-0000-a" ]; then
  run kitti-tracking-0000-a "$DATA/kitti-tracking-0000-a" "$DATA/kitti-tracking-0000-a/poses.txt"
fi
for scene in open urban wooded; do
  seq="$SCENES/$scene"
  if [ ! -f "$seq/poses.txt" ] && [ -x "$SIM" ] && [ -f "$SRC_DIR/data/scenarios/$scene.yaml" ]; then
    mkdir -p "$SCENES"
    "$SIM" "$SRC_DIR/data/scenarios/$scene.yaml" "$seq" --overwrite >/dev/null 2>"$work/sim.err" ||
      { echo "error: pcl_movers_simulate failed on $scene:" >&2; cat "$work/sim.err" >&2; exit 1; }
  fi
  [ -f "$seq/poses.txt" ] && run "sim-$scene" "$seq" "$seq/poses.txt"
done
echo
if [ ! -d "$DATA/kitti-odometry-00" ]; then echo "(KITTI data not found at $DATA: KITTI rows skipped.)"; echo; fi
cat <<'EOF'
Notes. The KITTI tracking reference is itself a GICP estimate (see the data README), so agreement
there bounds consistency rather than absolute accuracy; its reference poses carry no roll or
pitch, which is most of the rotation error listed. On KITTI odometry 00 the estimate is
consistently ~0.71 m per frame where the GPS/INS ground truth says 0.86 m: a brute-force search
of the horizontal shift that best overlaps the non-ground points of consecutive raw scans also
gives 0.70–0.73 m, so the scans themselves disagree with the ground-truth scale over these 6
frames; we have not found why, and the shortfall is reported, not tuned away.
EOF
