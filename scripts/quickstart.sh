#!/usr/bin/env bash
# From a fresh Debian 12 checkout to 3D files you can open: installs the
# packages (setup-debian.sh asks for sudo itself when not root), fetches the
# sample data, builds the plugin and the tools into build/ (the test suites
# are left for scripts/run-tests.sh; arguments are meson options for the
# build, e.g. -Dgpu_arch=86 or -Dcuda=disabled), then converts the samples
# into out/ with pseudo3d-convert:
#   vtest-sbs.mp4      data/vtest-audio.mkv (a street scene with a ticking
#                      sound track) as half side-by-side H.264 for a 3D TV,
#                      audio copied, 3D layout signalled in the stream
#   aloe-sbs.jpg       data/aloeL.jpg as a side-by-side photo (EXIF kept)
#   aloe-depth.png     the depth map it was rendered from (16-bit, white = near)
#   aloe.mpo           the same pair as an MPO for 3D TVs, cameras and viewers
#   aloe-anaglyph.png  a red-cyan anaglyph of the photo
set -euo pipefail
top=$(cd "$(dirname "$0")/.." && pwd)
cd "$top"

scripts/setup-debian.sh
scripts/get-test-data.sh
scripts/build.sh -Dtests=disabled "$@"

mkdir -p out
convert=build/tools/convert/pseudo3d-convert
echo "converting the samples into out/ ..."
"$convert" data/vtest-audio.mkv out/vtest-sbs.mp4 --force
"$convert" data/aloeL.jpg out/aloe-sbs.jpg --depth-out out/aloe-depth.png --force
"$convert" data/aloeL.jpg out/aloe.mpo --force
"$convert" data/aloeL.jpg out/aloe-anaglyph.png --layout anaglyph --force

echo "3D files written:"
for f in vtest-sbs.mp4 aloe-sbs.jpg aloe-depth.png aloe.mpo aloe-anaglyph.png; do
  [ -s "out/$f" ] || { echo "quickstart: out/$f is missing or empty" >&2; exit 1; }
  echo "  $top/out/$f"
done
