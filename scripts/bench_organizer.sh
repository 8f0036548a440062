#!/usr/bin/env bash
# Range image organizer: quality on all KITTI frames and speed against pcl::RangeImage.
# Usage: scripts/bench_organizer.sh BUILD_DIR   (a Release build) — prints one Markdown section.
set -euo pipefail
build_dir="${1:?usage: $0 BUILD_DIR}"
bench="$build_dir/bench/bench_organizer"
if [[ ! -x "$bench" ]]; then
  echo "error: $bench not found; build the bench_organizer target in $build_dir first" >&2
  exit 1
fi
"$bench" --report
