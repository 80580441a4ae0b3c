#!/usr/bin/env bash
# From a fresh Debian 12 checkout to 3D files you can open: installs the
# packages (setup-debian.sh asks for sudo itself when not root), fetches the
# sample data, builds into build/, then converts the samples into out/:
#   aloe-anaglyph.png  red-cyan anaglyph of data/aloeL.jpg
#   aloe-sbs-half.png  half side-by-side of data/aloeL.jpg
#   aloe-depth.png     the estimated depth map of data/aloeL.jpg (white = near)
#   vtest-sbs.mp4      data/vtest.avi as half side-by-side H.264 with frame packing
set -euo pipefail
top=$(cd "$(dirname "$0")/.." && pwd)
cd "$top"

scripts/setup-debian.sh
scripts/get-test-data.sh
scripts/build.sh

mkdir -p out
echo "converting the samples into out/ ..."
pipelines/image-to-anaglyph.sh data/aloeL.jpg out/aloe-anaglyph.png
pipelines/image-to-sbs.sh data/aloeL.jpg out/aloe-sbs-half.png
build/tools/pseudo3d-depthmap data/aloeL.jpg out/aloe-depth.png
pipelines/video-to-sbs.sh data/vtest.avi out/vtest-sbs.mp4

echo "3D files written:"
for f in aloe-anaglyph.png aloe-sbs-half.png aloe-depth.png vtest-sbs.mp4; do
  [ -s "out/$f" ] || { echo "quickstart: out/$f is missing or empty" >&2; exit 1; }
  echo "  $top/out/$f"
done
