#!/usr/bin/env bash
# Still image -> full side-by-side PNG (2W x H: left view, right view), the
# gst-launch equivalent of `pseudo3d-convert in.jpg out.png`. Add
# layout=side-by-side-half for a 3D TV's half side-by-side (W x H).
# GStreamer's JPEG decoding does not apply the EXIF orientation, so a
# portrait photo stored sideways stays sideways (and gets its depth gradient
# across); pseudo3d-convert turns it upright first and keeps the EXIF.
#   pipelines/image-to-sbs.sh in.jpg out.png [extra pseudo3dconvert properties]
set -euo pipefail
. "$(dirname "$0")/env.sh"
in=${1:?input image}; out=${2:?output png}; shift 2
gst-launch-1.0 -q filesrc location="$in" ! decodebin ! videoconvert ! video/x-raw,format=RGBA ! \
  pseudo3dconvert layout=side-by-side "$@" ! videoconvert ! pngenc ! filesink location="$out"
