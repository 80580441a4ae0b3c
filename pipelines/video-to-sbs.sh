#!/usr/bin/env bash
# Video file -> half side-by-side H.264 MP4 with frame packing signalled
# (x264enc frame-packing=auto writes the SEI from the multiview caps).
#   pipelines/video-to-sbs.sh in.(avi|mp4|mkv) out.mp4 [extra pseudo3dconvert properties]
set -euo pipefail
. "$(dirname "$0")/env.sh"
in=${1:?input video}; out=${2:?output mp4}; shift 2
gst-launch-1.0 -q filesrc location="$in" ! decodebin ! videoconvert ! video/x-raw,format=I420 ! \
  pseudo3dconvert layout=side-by-side-half "$@" ! videoconvert ! video/x-raw,format=I420 ! \
  x264enc speed-preset=veryfast frame-packing=auto ! h264parse ! mp4mux ! filesink location="$out"
