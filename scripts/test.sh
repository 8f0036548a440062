#!/usr/bin/env bash
# Runs the whole test suite (ctest, one entry per GoogleTest case) of an existing build.
# Viewer tests need an X display: without one, the suite runs under xvfb-run when available.
# Usage: bash scripts/test.sh [BUILD_DIR]
set -euo pipefail
cd "$(dirname "$0")/.."
BUILD_DIR=${1:-build}
[ -d "$BUILD_DIR" ] || { echo "error: build folder '$BUILD_DIR' missing: run 'bash scripts/setup.sh' first" >&2; exit 1; }
CTEST=(ctest --test-dir "$BUILD_DIR" --output-on-failure -j "${JOBS:-$(nproc)}")
if [ -z "${DISPLAY:-}" ] && command -v xvfb-run >/dev/null; then
  exec xvfb-run -a -s "-screen 0 1280x1024x24" "${CTEST[@]}"
fi
exec "${CTEST[@]}"
