#!/usr/bin/env bash
# Still image -> half side-by-side PNG (the frame keeps the input's size;
# each view is squeezed to half width, as 3D TVs expect).
#   pipelines/image-to-sbs.sh in.jpg out.png [extra pseudo3dconvert properties]
set -euo pipefail
. "$(dirname "$0")/env.sh"
in=${1:?input image}; out=${2:?output png}; shift 2
gst-launch-1.0 -q filesrc location="$in" ! decodebin ! videoconvert ! video/x-raw,format=RGBA ! \
  pseudo3dconvert layout=side-by-side-half "$@" ! videoconvert ! pngenc ! filesink location="$out"
