#!/usr/bin/env bash
# Media player with 3D conversion as playbin's video filter.
#   pipelines/player.sh /path/to/movie.mp4 [layout]
set -euo pipefail
. "$(dirname "$0")/env.sh"
file=$(realpath "${1:?media file}")
gst-launch-1.0 playbin uri="file://$file" video-filter="pseudo3dconvert layout=${2:-anaglyph}"
