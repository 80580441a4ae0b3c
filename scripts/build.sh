#!/usr/bin/env bash
# Configures (once) and builds pseudo3d into build/ (CUDA code too when nvcc
# is found). Extra arguments go to meson setup, e.g. -Dcuda=disabled.
set -euo pipefail
top=$(cd "$(dirname "$0")/.." && pwd)
cd "$top"
[ -f build/build.ninja ] || meson setup build "$@" >/dev/null
ninja -C build
