#!/usr/bin/env bash
# Ablation of the detector's rules on the scene corpus's tune split: each rule switched off alone
# (its documented "off" value), everything else at its default, side by side with the defaults,
# in both tracker modes: a rule idle with registered positions can still carry centroid mode (the
# displacement check does). Which rules earn their place is decided on these rows (issue #28),
# never on the check split. Uses the corpus cached in BUILD_DIR/corpus (scripts/eval_corpus.sh).
# Prints one Markdown section. Usage: bash scripts/eval_ablation.sh BUILD_DIR
set -euo pipefail
BUILD_DIR=$(cd "${1:?usage: eval_ablation.sh BUILD_DIR}" && pwd)
CORPUS="$BUILD_DIR/apps/pcl_movers_corpus"
[ -x "$CORPUS" ] || { echo "error: $CORPUS not built (cmake --build $BUILD_DIR)" >&2; exit 1; }
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT

# rule | the setting that switches it off | what it does
rules=(
  "defaults||"
  "ground local-slope test|--ground.local_slope 0|column slope test of the ground filter"
  "turned registration|--registration.turn_yaw_samples 1|a failed match tried again with yaw layers"
  "velocity from scatter|--track.sigma_from_scatter 0|reported velocity from a second filter"
  "line-fit restart|--track.velocity_fit_init 0|Kalman filter restarted from a line at the 3rd update"
  "occlusion-aware|--track.occluded_fraction 0|occluded views skipped by the velocity filter"
  "merged clusters split|--track.split_merged 0|a cluster claimed by two moving tracks split"
  "re-acquisition|--track.reacquire_velocity 0|a track born at a lost mover inherits its velocity"
  "swept edges|--track.swept_edges 0|a growing or shrinking view's position from its confirmed edge"
  "confirmed movers hold|--track.hold_confirmed 0|a low-B cluster kept by its confirmed mover"
  "coasting|--track.max_missed_frames 0|tracks kept through missed frames"
  "speed significance|--decision.speed_sigmas 0|a fast vote must be significant"
  "sustained slow motion|--decision.slow_window 0|slow walkers by a line over 1.5 s"
  "displacement check|--decision.displacement_ratio 0|net displacement consistent with the speed"
  "early confirmation|--decision.confirm_false_rate 0|F-test confirmation of well-measured motion"
  "mover latch|--decision.latch 0|a confirmed mover stays one while tracked"
  "height from what it stands on|--decision.standing_height 0|top above the ground or an occluder below"
  "minimum height|--decision.min_height 0|clusters lower than 0.8 m are not movers"
  "free-space test|--free_space.lag 0|a mover must occupy space seen empty"
  "long-lag free space|--free_space.long_lag 0|a second, longer lag for slow and far objects"
  "silent rays seen empty|--free_space.no_return 0|downward no-returns count as empty space"
  "motion-aware split|--free_space.split 0|a cluster's seen-through part split off its static rest"
)

echo "## Ablation of the detector's rules (tune split)"
echo
echo "Each rule switched off alone (the setting shown), all other parameters at their defaults;"
echo "\`pcl_movers_corpus --split tune --modes registration,centroid\` on the cached corpus, 30 scenes"
echo "of 150 frames. Deltas are against the defaults row. A rule earns its place when switching it"
echo "off costs hit rate, false alarms, moving-point IoU or velocity error across families, in"
echo "either mode (centroid mode: the paper's simplest association, the comparison baseline)."
echo
echo "| rule (off) | setting | hit % | FA / frame | moving IoU % | median delay | vel. RMS [m/s] | hit % by family: highway / urban / parking / open / trail | centroid: hit % | centroid: FA / frame |"
echo "|---|---|---:|---:|---:|---:|---:|---|---:|---:|"
i=0
for row in "${rules[@]}"; do
  IFS='|' read -r name setting _ <<<"$row"
  report="$tmp/r$i.md"
  i=$((i + 1))
  # shellcheck disable=SC2086
  if ! (cd "$BUILD_DIR" && "$CORPUS" corpus --split tune --modes registration,centroid \
    --detect-args "$setting" --report "$report" >"$tmp/log" 2>&1); then
    echo "error: pcl_movers_corpus failed for '$setting':" >&2
    tail -20 "$tmp/log" >&2
    exit 1
  fi
  python3 - "$report" "$name" "$setting" <<'EOF'
import sys
report, name, setting = sys.argv[1:4]
lines = open(report).read().splitlines()
overall = next(l for l in lines if l.startswith("| all |")).split("|")
fam = {}
section = None
for l in lines:
    if l.startswith("### "):
        section = l
    elif section == "### By family" and l.startswith("| ") and not l.startswith("| family"):
        cells = [c.strip() for c in l.split("|")]
        if len(cells) > 4 and cells[1] and not cells[1].startswith("-"):
            fam[cells[1]] = cells[4]
hits = " / ".join(fam.get(f, "-") for f in ["highway", "urban", "parking", "open", "trail"])
cells = [c.strip() for c in overall]
# | all | scenes | targets | hit | FA | IoU | delay | never hit | vel | centroid: hit | FA | ...
print(f"| {name} | `{setting or '(defaults)'}` | {cells[4]} | {cells[5]} | {cells[6]} | {cells[7]} | {cells[9]} | {hits} | {cells[10]} | {cells[11]} |")
EOF
done
