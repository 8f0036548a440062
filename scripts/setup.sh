#!/usr/bin/env bash
# Installs the Debian packages pcl_movers needs and builds it (Release) into ./build.
# Usage: bash scripts/setup.sh [BUILD_DIR]      (env: CMAKE_ARGS, JOBS, SKIP_APT=1, SKIP_BUILD=1)
set -euo pipefail
cd "$(dirname "$0")/.."
BUILD_DIR=${1:-build}
JOBS=${JOBS:-$(nproc)}
if [ "${SKIP_APT:-0}" != 1 ]; then
  SUDO=""
  [ "$(id -u)" -eq 0 ] || SUDO=sudo
  export DEBIAN_FRONTEND=noninteractive
  $SUDO apt-get update -qq
  # libpcl-dev's CMake config needs libpcap-dev and libpng-dev beside it; xvfb runs the viewer tests.
  # clang + libclang-rt-14-dev (ASan/UBSan/libFuzzer runtimes, only recommended by clang-14) + llvm
  # (llvm-symbolizer) are for the sanitizer/fuzz job, scripts/ci_sanitizers.sh.
  $SUDO apt-get install -y -qq --no-install-recommends \
    build-essential cmake ninja-build pkg-config ccache \
    libpcl-dev libpcap-dev libpng-dev libeigen3-dev libboost-dev \
    libgtest-dev libgmock-dev libbenchmark-dev \
    xvfb xauth clang-format clang libclang-rt-14-dev llvm >/dev/null
fi
[ "${SKIP_BUILD:-0}" != 1 ] || exit 0
LAUNCHER=""
command -v ccache >/dev/null && LAUNCHER="-DCMAKE_CXX_COMPILER_LAUNCHER=ccache"
cmake -S . -B "$BUILD_DIR" -G Ninja -DCMAKE_BUILD_TYPE=Release $LAUNCHER ${CMAKE_ARGS:-}
cmake --build "$BUILD_DIR" -j "$JOBS"
