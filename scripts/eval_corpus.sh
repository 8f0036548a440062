#!/usr/bin/env bash
# The scene corpus (pcl_movers_corpus): every family and sensor, seeds 1-12 per family, odd seeds
# the tune split, even seeds the check split; the check split's report first. Scenes are cached
# in BUILD_DIR/corpus (about 13 GB) and simulated again only when the generator changes them.
# Prints one Markdown section. Usage: bash scripts/eval_corpus.sh BUILD_DIR
set -euo pipefail
BUILD_DIR=$(cd "${1:?usage: eval_corpus.sh BUILD_DIR}" && pwd)
CORPUS="$BUILD_DIR/apps/pcl_movers_corpus"
[ -x "$CORPUS" ] || { echo "error: $CORPUS not built (cmake --build $BUILD_DIR)" >&2; exit 1; }
echo "## Scene corpus"
echo
echo "Scenes drawn by \`pcl_movers_simulate --family FAMILY --seed SEED\` (docs/design.md, \"Scene"
echo "corpus\"): highway, urban street and junction, parking lot, open rolling terrain, forest trail;"
echo "each with its sensor (seeds 2k-1 and 2k: hdl64, hdl32, vlp16, os1_64, ladar2d by k mod 5), a"
echo "mounting height of 1.5-2.5 m, noise, dropouts and, in half of them, 1-3 blind frames."
echo "**Odd seeds are the tune split, even seeds the check split: parameters and rules are chosen on"
echo "tune only; check is reported and never tuned on.** Scored as docs/design.md defines it, all"
echo "around (sector ±180°), 150 frames a scene, default detector parameters. *Moving IoU* is the"
echo "moving-point IoU of \`pcl_movers_detect --point-labels\` against the scenes' point labels, scored"
echo "as SemanticKITTI-MOS does (\`pcl_movers_eval --mos\`: TP / (TP + FP + FN) over all points; moving"
echo "= moving in that frame, faster than 0.1 m/s)."
echo
cd "$BUILD_DIR"  # the report quotes the command: no host paths in it
"$CORPUS" corpus --split all 2>corpus.err |
  sed -e 's/^## Scene corpus, check split/### Check split (reported, never tuned on)/' \
      -e 's/^## Scene corpus, tune split/### Tune split (parameters are chosen here)/' \
      -e 's/^### /#### /' -e 's/^#### \(Check\|Tune\) split/### \1 split/' ||
  { echo "error: pcl_movers_corpus failed:" >&2; tail -20 corpus.err >&2; exit 1; }
