#!/usr/bin/env bash
# What pseudo3d-convert adds to the pipeline it drives (issue 9, item 5): a
# 4K H.264 clip converted to half side-by-side with the encoder replaced by a
# fakesink, against decoding the same file alone, both measured in one
# `pseudo3d-convert --benchmark` run (decoding by NVDEC into CUDA memory
# where a GPU is usable). Then one real conversion of the clip (x264,
# ultrafast) timed end to end. Writes OUTDIR/convert.jsonl and prints a
# summary. The clip and the converted file go to P3D_BENCH_WORK (default
# OUTDIR).
#
#   scripts/bench-convert.sh [OUTDIR]
# Needs gst-launch-1.0 and pseudo3d-convert (P3D_CONVERT, default
# build/tools/convert/pseudo3d-convert) with the plugin found; on the GPU machine
# `scripts/gpu-check.sh run OUTDIR convert` sets that up.
set -uo pipefail
top=$(cd "$(dirname "$0")/.." && pwd)
out=${1:-convert-results}
mkdir -p "$out"
convert=${P3D_CONVERT:-$top/build/tools/convert/pseudo3d-convert}
frames=${P3D_BENCH_FRAMES:-600}
work=${P3D_BENCH_WORK:-$out}
mkdir -p "$work"
clip=$work/clip-4k.mp4
jsonl=$out/convert.jsonl

# 4:2:0 (as NVDEC decodes; from videotestsrc x264 would take 4:4:4).
if [ ! -s "$clip" ]; then
  gst-launch-1.0 -q videotestsrc num-buffers="$frames" pattern=ball ! \
    video/x-raw,format=I420,width=3840,height=2160,framerate=30/1 ! \
    x264enc speed-preset=ultrafast tune=zerolatency ! h264parse ! mp4mux ! filesink location="$clip" || exit 1
fi

: >"$jsonl"
"$convert" --benchmark "$clip" --layout side-by-side-half --benchmark-runs 3 --benchmark-out "$jsonl" \
  | tee "$out/convert-benchmark.txt"
rc=${PIPESTATUS[0]}

# One real conversion, encoder included (x264: no NVENC on H100/H200).
res=$work/clip-4k-sbs.mp4
t0=$(date +%s.%N)
"$convert" "$clip" "$res" --preset ultrafast --force --quiet
rc2=$?
t1=$(date +%s.%N)
python3 -c "import json,sys; w=float(sys.argv[2])-float(sys.argv[1]); n=int(sys.argv[3]); print(json.dumps({'bench':'pseudo3d-convert','mode':'convert-x264-ultrafast','frames':n,'wall_seconds':round(w,3),'fps':round(n/w,1),'exit_code':int(sys.argv[4])}))" \
  "$t0" "$t1" "$frames" "$rc2" | tee -a "$jsonl"
[ $rc -eq 0 ] && [ $rc2 -eq 0 ]
