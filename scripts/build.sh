#!/usr/bin/env bash
# Configures and builds pseudo3d into build/ (CUDA code too when nvcc is
# found). Extra arguments are meson options, e.g. -Dcuda=disabled or
# -Dgpu_arch=86: they configure a new build/ and reconfigure an existing
# one, so an option given later is not ignored. Meson prints what it found
# and what it will build (CUDA on or off, the GPU architectures); ninja
# shows each file as it compiles.
set -euo pipefail
top=$(cd "$(dirname "$0")/.." && pwd)
cd "$top"
if [ ! -f build/build.ninja ]; then
  meson setup build "$@"
elif [ $# -gt 0 ]; then
  meson configure build "$@"
fi
ninja -C build
