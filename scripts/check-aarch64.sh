#!/usr/bin/env bash
# Builds common/ (the algorithms and CPU references, with their vector
# code) and its CPU tests (test_common) for aarch64 with Debian's cross
# compiler, and runs them under qemu-user: OpenCV's universal intrinsics
# take NEON there, so this is the check that the vector code is right on
# ARM, not only that it compiles.
#
# Only common/ and its tests: Debian 12's arm64 development packages of
# GStreamer and of OpenCV's image codecs are not co-installable with the
# amd64 ones the native build needs (installing them removes those), so
# the elements are not cross-built. The tests read the raw dumps of the
# test pictures that a native build writes (scripts/build.sh first):
# the raw reader replaces OpenCV's codecs, as in the GPU suites. The
# dumps need the pictures in data/ (scripts/get-test-data.sh).
# Usage: scripts/check-aarch64.sh [native build dir, default build]
set -euo pipefail
top=$(cd "$(dirname "$0")/.." && pwd)
cd "$top"
native=${1:-build}
raw="$native/tests/raw-data"
[ -f "$raw/aloeL.jpg.p3draw" ] || { echo "check-aarch64: no raw test data in $raw (scripts/get-test-data.sh, then build natively)" >&2; exit 1; }

# Cross compiler and qemu, and the arm64 libraries the tests link: these
# three development packages co-install with their amd64 counterparts.
SUDO=""; [ "$(id -u)" -ne 0 ] && SUDO=sudo
need=(g++-aarch64-linux-gnu qemu-user libopencv-core-dev:arm64 libopencv-imgproc-dev:arm64 libgtest-dev:arm64)
missing=()
for p in "${need[@]}"; do dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "ok installed" || missing+=("$p"); done
if [ ${#missing[@]} -gt 0 ]; then
  dpkg --print-foreign-architectures | grep -qx arm64 || $SUDO dpkg --add-architecture arm64
  $SUDO apt-get update -qq
  # --no-remove: stop rather than take away an amd64 package the native build needs.
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends --no-remove "${missing[@]}"
fi

out="$top/build-aarch64"
rm -rf "$out/obj"  # compiled afresh: no stale object of an edited header or a removed source
mkdir -p "$out/obj"
cxx=aarch64-linux-gnu-g++
flags=(-std=c++17 -O2 -ffp-contract=off -Wall -Wextra -pthread -DNDEBUG
       "-DP3D_DATA_DIR=\"$top/data\"" -I/usr/include/opencv4 -I/usr/include/aarch64-linux-gnu/opencv4
       -Icommon -Itools/support -Itests/support)
sources=(common/*.cpp tools/support/host_frame.cpp tools/support/metrics.cpp
         tests/support/test_data.cpp tests/support/stiff_frames.cpp tests/support/stereo_frames.cpp
         tests/support/image_read_raw_only.cpp tests/support/gtest_main.cpp tests/common/*.cpp)
# Compile in parallel, one object per source.
printf '%s\n' "${sources[@]}" | xargs -P "$(nproc)" -I{} sh -c \
  'o="$0/obj/$(echo "{}" | tr / _).o"; $1 $2 -c "{}" -o "$o"' "$out" "$cxx" "${flags[*]}"
$cxx -pthread -o "$out/test_common" "$out"/obj/*.o -lopencv_imgproc -lopencv_core -lgtest
aarch64-linux-gnu-readelf -h "$out/test_common" | grep -q "AArch64" || { echo "check-aarch64: not an aarch64 binary" >&2; exit 1; }
echo "check-aarch64: running test_common under qemu-aarch64"
# Left out: the one test whose death tests re-execute the binary (gtest's
# threadsafe style), which qemu-user cannot without binfmt_misc.
P3D_DATA_DIR="$(cd "$raw" && pwd)" qemu-aarch64 -L / "$out/test_common" --gtest_brief=1 \
  --gtest_filter='-AdaptiveWarpPack.BackgroundSmoothWithACopiedEye'
