#!/usr/bin/env bash
# Runs pcl_movers_eval_segmentation from a Release build dir on the labelled KITTI frames and on
# simulated scenes, and prints one Markdown section (ground precision/recall against a height
# threshold baseline, object recovery, a small parameter-sensitivity table).
# Usage: scripts/eval_segmentation.sh BUILD_DIR
# The KITTI data folder is taken from $PCL_MOVERS_SHARED_DATA, else from BUILD_DIR's CMake cache.
set -euo pipefail
build=${1:?usage: $0 BUILD_DIR}
eval_bin="$build/apps/pcl_movers_eval_segmentation"
sim_bin="$build/apps/pcl_movers_simulate"
src=$(cd "$(dirname "$0")/.." && pwd)
if [[ ! -x "$eval_bin" ]]; then
  echo "eval_segmentation.sh: $eval_bin not found (build target pcl_movers_eval_segmentation)" >&2
  exit 1
fi
data=${PCL_MOVERS_SHARED_DATA:-}
if [[ -z "$data" && -f "$build/CMakeCache.txt" ]]; then
  data=$(sed -n 's/^PCL_MOVERS_SHARED_DATA:PATH=//p' "$build/CMakeCache.txt")
fi
kitti="$data/kitti-odometry-00"
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT

echo "## Ground removal and segmentation quality"
echo
echo "Produced by \`scripts/eval_segmentation.sh\` (\`pcl_movers_eval_segmentation\`). Ground truth is"
echo "point-wise: SemanticKITTI labels for KITTI odometry 00 frames 0-2, and the simulator's labels"
echo "for simulated scenes (3 frames each of \`data/scenarios/{open,urban,wooded}.yaml\`: rolling"
echo "terrain with slopes, a city block with kerbs and sidewalks, a forest on rolling ground). Ground ="
echo "road, parking, sidewalk, other-ground, terrain, lane-marking; unlabelled points are not scored."
echo "The baseline calls every point lower than 0.25 m above the nominal road plane ground. Objects are"
echo "labelled instances with >= 30 points (vehicles and people by instance id; trunks and poles, which"
echo "SemanticKITTI gives no instance ids, split by 3D connected components at 0.5 m). *Recovered*: one"
echo "cluster holds >= 80 % of the object's points; *merged*: the object is less than half of that"
echo "cluster (joined with another object, a wall, vegetation or left-over ground); *over-segmented*:"
echo "not recovered and split over >= 2 clusters. Timings here are single runs on a shared machine;"
echo "see the benchmark section for measured speed."
echo

args=()
if [[ -f "$kitti/labels/000000.label" ]]; then
  args+=(--kitti "$kitti")
else
  echo "_KITTI odometry 00 not found (looked in \`$kitti\`): KITTI rows skipped._"
  echo
fi
if [[ -x "$sim_bin" ]]; then
  for scene in open urban wooded; do
    if "$sim_bin" "$src/data/scenarios/$scene.yaml" "$tmp/$scene" --frames 3 >/dev/null 2>&1; then
      args+=(--sequence "$tmp/$scene")
    else
      echo "_Simulating \`$scene\` failed: its rows are missing._"
      echo
    fi
  done
else
  echo "_\`pcl_movers_simulate\` not built in \`$build\`: simulated rows skipped._"
  echo
fi
if [[ ${#args[@]} -eq 0 ]]; then
  echo "_No labelled data available: nothing evaluated._"
  exit 0
fi
"$eval_bin" "${args[@]}" --per-frame 2>/dev/null

if [[ ${#args[@]} -gt 0 ]]; then
  echo
  echo "Ground precision / recall trade-off of the local-slope test (defaults, GroundParameters:"
  echo "20°, 0.02 m range noise, 0.3 m neighbour band; the angle was chosen as steeper than drivable"
  echo "ground, not tuned on these frames). Each cell: precision / recall."
  echo
  header="| setting |"
  rule="|---|"
  for a in "${args[@]}"; do
    [[ "$a" == --* ]] && continue
    header="$header $(basename "$a") |"
    rule="$rule---|"
  done
  echo "$header"
  echo "$rule"
  for setting in "--local-slope 0" "--local-slope-deg 10" "--local-slope-deg 15" \
    "--local-slope-deg 20" "--local-slope-deg 25" "--local-slope-deg 30"; do
    # shellcheck disable=SC2086
    out=$("$eval_bin" "${args[@]}" $setting 2>/dev/null)
    row="| \`$setting\` |"
    while IFS= read -r line; do
      p=$(echo "$line" | awk -F'|' '{gsub(/ /,"",$4); gsub(/ /,"",$5); print $4 " / " $5}')
      row="$row $p |"
    done < <(echo "$out" | awk '/^\| data \| frames \|/{f=1; next} f && /^\|---/{next} f && /^\|/{print; next} f{exit}')
    echo "$row"
  done
fi

if [[ -f "$kitti/labels/000000.label" ]]; then
  echo
  echo "Sensitivity on KITTI (frames 0-2) to the segmentation parameters and the ground distance"
  echo "threshold (defaults, shared with pcl_movers_detect: depth ratio 0.05, max gap 2, row bridge"
  echo "0, ground distance 0.1 m, plane tilt 15°):"
  echo
  echo "| setting | ground precision | ground recall | recovered | not merged | over-segmented | merged |"
  echo "|---|---|---|---|---|---|---|"
  for setting in "--depth-ratio 0.03" "--depth-ratio 0.04" "--max-gap 0" "--max-gap 3" \
    "--distance 0.15" "--distance 0.25" "--max-slope-deg 10"; do
    # shellcheck disable=SC2086
    out=$("$eval_bin" --kitti "$kitti" $setting 2>/dev/null)
    g=$(echo "$out" | grep '^| kitti' | sed -n 1p | awk -F'|' '{print $4 "|" $5}')
    o=$(echo "$out" | awk '/^\| data \| instances/{f=1; next} f && /^\| kitti/{print; exit}' |
      awk -F'|' '{print $4 "|" $5 "|" $6 "|" $7}')
    echo "| \`$setting\` |$g|$o|"
  done
fi
