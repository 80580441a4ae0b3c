#!/usr/bin/env bash
# Puts the real test data into data/: the Middlebury "Aloe" stereo pair with
# ground-truth disparity (aloeL.jpg, aloeR.jpg, aloeGT.png: disparity in
# pixels of the left view, 0 = unknown) and vtest.avi, all from Debian's
# opencv-doc package (installed by setup-debian.sh; downloaded and unpacked
# here if it is not installed). Then makes vtest-audio.mkv, vtest.avi's video
# (copied, not re-encoded) with an AAC sound track of the same length (a tick
# a second, so A/V sync can be checked by ear): the quickstart's film.
set -euo pipefail
top=$(cd "$(dirname "$0")/.." && pwd)
dest=$top/data
files=(aloeL.jpg aloeR.jpg aloeGT.png vtest.avi)
src=/usr/share/doc/opencv-doc/examples/data
mkdir -p "$dest"
if [ ! -f "$src/aloeL.jpg" ]; then
  tmp=$(mktemp -d)
  (cd "$tmp" && apt-get download opencv-doc >/dev/null && dpkg -x opencv-doc_*.deb root)
  src=$tmp/root/usr/share/doc/opencv-doc/examples/data
fi
for f in "${files[@]}"; do
  [ -f "$dest/$f" ] || cp "$src/$f" "$dest/$f"
done
# vtest.avi: 795 frames at 10 frames/s = 79.5 s = 795 buffers of 4800 samples at 48 kHz.
if [ ! -s "$dest/vtest-audio.mkv" ]; then
  tmp_mkv="$dest/.vtest-audio.mkv.part"
  gst-launch-1.0 -q filesrc location="$dest/vtest.avi" ! avidemux ! queue ! matroskamux name=mux ! \
    filesink location="$tmp_mkv" \
    audiotestsrc wave=ticks num-buffers=795 samplesperbuffer=4800 volume=0.5 ! \
    audio/x-raw,rate=48000,channels=2 ! audioconvert ! avenc_aac ! aacparse ! queue ! mux. &&
    mv "$tmp_mkv" "$dest/vtest-audio.mkv"
fi
echo "test data in $dest: ${files[*]} vtest-audio.mkv"
