#!/usr/bin/env bash
# H.264 file decoded on the GPU (nvh264dec) -> every stage on the GPU in
# device memory -> download -> x264 half side-by-side MKV, the layout and eye
# order signalled in the stream (pseudo3dsignal). Video only; with
# `pseudo3d-convert in.mp4 out.mkv` the same chain keeps the sound too.
#   pipelines/video-to-sbs-gpu.sh in.mp4 out.mkv
set -euo pipefail
. "$(dirname "$0")/env.sh"
in=${1:?input H.264 mp4}; out=${2:?output mkv}; shift 2
gst-launch-1.0 -q filesrc location="$in" ! qtdemux ! h264parse ! nvh264dec ! \
  "video/x-raw(memory:CUDAMemory)" ! pseudo3dconvert layout=side-by-side-half "$@" ! cudadownload ! \
  videoconvert ! video/x-raw,format=I420 ! x264enc speed-preset=veryfast frame-packing=auto ! h264parse ! pseudo3dsignal ! matroskamux ! \
  filesink location="$out"
