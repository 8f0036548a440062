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
# run NAME SEQ REFERENCE [extra args]: one table row (REFERENCE "-" = none)
run() {
  local name=$1 seq=$2 ref=$3
  shift 3
  local out="$work/$name.md" refargs=()
  [ "$ref" != "-" ] && refargs=(--reference "$ref")
  if ! "$EGO" "$seq" "$work/$name.poses" "${refargs[@]}" "$@" >"$out" 2>"$work/$name.err"; then
    echo "error: pcl_movers_ego_motion failed on $seq:" >&2
    cat "$work/$name.err" >&2
    exit 1
  fi
  get() { awk -F'|' -v k="$1" '$2 ~ k {gsub(/^ +| +$/, "", $3); print $3; exit}' "$out"; }
  printf '| %s | %s | %s | %s | %s | %s | %s | %s | %s | %s |\n' "$name" "$(get '^ frames')" \
    "$(get 'distance travelled')" "$(get 'final translation error')" \
    "$(get 'error per metre')" "$(get 'RMS frame-to-frame translation')" \
    "$(get 'RMS frame-to-frame rotation')" "$(get 'final rotation error')" \
    "$(get 'estimated speed')" "$(get 'CPU time per frame')"
}

echo "## Ego-motion estimation (\`EgoMotionEstimator\`, \`pcl_movers_ego_motion\`)"
echo
echo "Poses estimated from the scans alone (point-to-plane/line ICP of one point per 1 m voxel"
echo "against the planes of a voxel-moment map of the last 8 keyframes, coarse-then-trimmed"
echo "iterations, constant-velocity guess; default parameters for every set), compared with the"
echo "reference poses after re-basing both on frame 0. Error / metre = final translation error /"
echo "distance travelled. Frame-to-frame (f2f) errors are RMS over consecutive frame pairs."
echo "Rotation error includes roll and pitch. CPU ms / frame is the estimator's thread CPU time"
echo "(reading the scan excluded) on the machine that ran this script."
echo
echo "| sequence | frames | travelled [m] | final transl. error [m] | error / metre [%] | f2f transl. RMS [m] | f2f rot. RMS [deg] | final rotation error [deg] | speed mean / min / max [m/s] | CPU ms / frame |"
echo "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|"
if [ -d "$DATA/kitti-odometry-00" ]; then
  run kitti-odometry-00 "$DATA/kitti-odometry-00" "$DATA/kitti-odometry-00/poses_cam0.txt" \
    --calib "$DATA/kitti-odometry-00/calib.txt" --per-pair
fi
if [ -d "$DATA/kitti-tracking-0000-a" ]; then
  run kitti-tracking-0000-a "$DATA/kitti-tracking-0000-a" "$DATA/kitti-tracking-0000-a/poses.txt"
fi
if [ -d "$DATA/kitti-city-22" ]; then
  run kitti-city-22 "$DATA/kitti-city-22" -
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
if [ -f "$work/kitti-odometry-00.md" ]; then
  echo "KITTI odometry 00 per frame pair (velodyne frame; reference = GPS/INS poses of camera 0"
  echo "mapped with calib \`Tr\`):"
  echo
  awk '/^\| pair/{p=1} p&&/^\|/{print} p&&/^$/{exit}' "$work/kitti-odometry-00.md"
  echo
fi
cat <<'EOF'
Notes. The KITTI tracking reference is itself a GICP estimate (see the data README), so agreement
there bounds consistency rather than absolute accuracy; its reference poses carry no roll or
pitch, which is most of the rotation error listed. kitti-city-22 has no reference: its row shows
the speed profile of the estimate (a car at a steady ~8 m/s, smooth from frame to frame).

KITTI odometry 00 (6 frames, 0.52 s) is not a usable reference at this scale. Its ground truth
moves 0.859-0.860 m and 0.118 deg of yaw every frame (constant to 1 mm), while the scans say the
car accelerates from ~0.68 to ~0.74 m per frame and yaws 0.18-0.28 deg per frame. The
disagreement is not this estimator's: PCL's own GICP (`pcl::GeneralizedIterativeClosestPoint`,
0.2 m voxels, 3-60 m, started from identity or from the ground truth) on consecutive raw scans
gives 0.681, 0.696, 0.719, 0.727, 0.739 m (0.685 and 0.695 m for pairs 0-1 and 1-2 when only
the SemanticKITTI static classes are registered: buildings, poles, trunks, signs, parked cars,
vegetation), within 2-3 cm of this estimator whatever the start. Frame indexing (times 0.104 s
apart, consecutive frames) and the velodyne conversion (pose_velo = Tr^-1 pose_cam Tr; a step's
length does not depend on Tr) were checked. KITTI notes that its GPS/OXTS ground truth is
inaccurate over short sub-sequences (it evaluates on 100-800 m); a constant step over 0.5 s looks
like an interpolated stretch. The 17 % is the reference's error, not a tuning target.
EOF
