#!/usr/bin/env bash
# Live source -> anaglyph on screen. SOURCE defaults to a test pattern; use
# SOURCE=v4l2src for a camera.
#   SOURCE=v4l2src pipelines/live-to-display.sh [extra pseudo3dconvert properties]
set -euo pipefail
. "$(dirname "$0")/env.sh"
source_el=${SOURCE:-"videotestsrc is-live=true pattern=ball"}
gst-launch-1.0 $source_el ! videoconvert ! video/x-raw,format=I420 ! \
  pseudo3dconvert layout=anaglyph "$@" ! videoconvert ! autovideosink sync=false
