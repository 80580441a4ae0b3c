#!/usr/bin/env bash
# Video file -> half side-by-side H.264 MP4 with its sound track, the 3D
# layout signalled in the stream: the gst-launch equivalent of
#   pseudo3d-convert in.mkv out.mp4
# for people who build their own pipelines. (The converter also copies the
# sound instead of re-encoding it, handles files without sound, subtitles,
# --start/--duration, the GPU decoders, progress, and never leaves a partial
# file.)
#   pipelines/video-to-sbs.sh in.(mkv|mp4|avi) out.mp4 [extra pseudo3dconvert properties]
#   AUDIO=no pipelines/video-to-sbs.sh silent.avi out.mp4   (a file without sound)
#
# What matters in the line:
# - the sound goes through an unbounded queue (max-size-* 0): the video
#   branch holds seconds of frames before the muxer sees any (decoder, the 3D
#   stages, x264's look-ahead), so a bounded queue on the sound fills, blocks
#   the demuxer, and the video waits for it forever (a deadlock);
# - the caps after "d." pick the right decodebin pad for each branch;
# - format=I420 keeps x264 in the High profile players decode (from RGB it
#   would choose High 4:4:4), and pseudo3dconvert's pack stage writes that
#   I420 itself (no videoconvert after it); frame-packing=auto writes the layout into the
#   stream's frame-packing SEI; pass=qual quantizer=20 is x264's CRF 20;
# - pseudo3dsignal writes the eye order into that SEI and keeps mp4mux from
#   writing its own (wrong) stereo box; -e finishes the file on Ctrl-C.
set -euo pipefail
. "$(dirname "$0")/env.sh"
in=${1:?input video}; out=${2:?output mp4}; shift 2
audio=()
if [ "${AUDIO:-yes}" != no ]; then
  audio=(d. ! audio/x-raw ! queue max-size-buffers=0 max-size-bytes=0 max-size-time=0 ! audioconvert ! audioresample !
         avenc_aac ! m.)
fi
gst-launch-1.0 -e filesrc location="$in" ! decodebin name=d \
  d. ! video/x-raw ! queue max-size-buffers=8 max-size-bytes=0 max-size-time=0 ! videoconvert ! \
  pseudo3dconvert layout=side-by-side-half "$@" ! queue max-size-buffers=4 max-size-bytes=0 max-size-time=0 ! \
  video/x-raw,format=I420 ! x264enc pass=qual quantizer=20 frame-packing=auto ! \
  progressreport update-freq=10 ! h264parse ! pseudo3dsignal ! mp4mux name=m ! filesink location="$out" \
  "${audio[@]}"
