#!/usr/bin/env bash
# Still image (JPEG or PNG) -> red-cyan Dubois anaglyph PNG.
#   pipelines/image-to-anaglyph.sh in.jpg out.png [extra pseudo3dconvert properties]
set -euo pipefail
. "$(dirname "$0")/env.sh"
in=${1:?input image}; out=${2:?output png}; shift 2
gst-launch-1.0 -q filesrc location="$in" ! decodebin ! videoconvert ! video/x-raw,format=RGBA ! \
  pseudo3dconvert layout=anaglyph glasses=red-cyan anaglyph-method=dubois "$@" ! \
  videoconvert ! pngenc ! filesink location="$out"
