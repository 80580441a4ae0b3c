#!/usr/bin/env bash
# Installs what pseudo3d needs on Debian 12 (run as root, or with sudo):
# build tools, GStreamer 1.22 with base/good/bad/ugly plugins and libgstcuda,
# OpenCV, GoogleTest, opencv-doc (the Middlebury Aloe pair and vtest.avi
# used by the tests), ffmpeg and mkvtoolnix (the tests read the files the
# project writes back with ffprobe and mkvinfo, as ffmpeg-based players and
# Matroska tools do). The CUDA toolkit (nvcc) is optional: with it the GPU
# path is built too.
set -euo pipefail
packages=(
  meson ninja-build pkg-config g++ git
  libglib2.0-dev libgstreamer1.0-dev libgstreamer-plugins-base1.0-dev libgstreamer-plugins-bad1.0-dev
  gstreamer1.0-tools gstreamer1.0-plugins-base gstreamer1.0-plugins-good gstreamer1.0-plugins-bad
  gstreamer1.0-plugins-ugly gstreamer1.0-libav
  libopencv-dev libgtest-dev opencv-doc python3-matplotlib python3-numpy
  ffmpeg mkvtoolnix
)
missing=()
for p in "${packages[@]}"; do dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "ok installed" || missing+=("$p"); done
if [ ${#missing[@]} -gt 0 ]; then
  SUDO=""; [ "$(id -u)" -ne 0 ] && SUDO=sudo
  $SUDO apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}"
fi
echo "setup-debian: all packages present"
