#!/usr/bin/env bash
# Compiles the CUDA kernels (and everything that links them) for every
# supported GPU architecture into build-allarch/, as a release would ship
# them; the test suites are left out. Without nvcc there is nothing to do.
set -euo pipefail
top=$(cd "$(dirname "$0")/.." && pwd)
cd "$top"
if ! command -v nvcc >/dev/null && [ ! -x /usr/local/cuda/bin/nvcc ]; then
  echo "build-all-archs: no nvcc, no CUDA code to compile"
  exit 0
fi
[ -f build-allarch/build.ninja ] || meson setup build-allarch -Dgpu_arch=all -Dcuda=enabled -Dtests=disabled
ninja -C build-allarch
