#!/usr/bin/env bash
# End-to-end pipeline benchmarks: frames/s and added latency (GStreamer's
# latency tracer) of the whole chain in real pipelines, at 1080p and 4K, on
# the CPU, on the GPU staged through system memory, and on the GPU with
# CUDA memory between the stages; then a 4K H.264 clip decoded by nvh264dec,
# converted, encoded by x264 and muxed, with wall time against the clip's
# duration. Writes JSON lines to OUTDIR/pipelines.jsonl and prints a table.
#
#   scripts/bench-pipelines.sh [OUTDIR]    (gst-launch-1.0 and the plugin on
#                                           the path: scripts/gpu-check.sh run
#                                           OUTDIR pipelines sets that up)
# GPU rows are skipped where cudaupload is missing (no GPU).
set -uo pipefail
out=${1:-pipeline-results}
mkdir -p "$out"
jsonl=$out/pipelines.jsonl
frames=${P3D_BENCH_FRAMES:-300}
have_gpu=0
gst-inspect-1.0 cudaupload >/dev/null 2>&1 && have_gpu=1
stages="pseudo3ddepth processing=%P ! pseudo3dfilter processing=%P ! pseudo3dwarp processing=%P ! pseudo3dpack processing=%P layout=side-by-side-half"

# One frame repeated by imagefreeze: the source costs nothing per frame, so
# the wall time is the chain's (plus the sink's negligible work).
run_case() {  # name width height mode
  local name=$1 w=$2 h=$3 mode=$4 chain
  case $mode in
    cpu) chain=${stages//%P/cpu} ;;
    gpu-staged) chain=${stages//%P/gpu} ;;
    gpu-resident) chain="cudaupload ! video/x-raw(memory:CUDAMemory) ! ${stages//%P/gpu} ! cudadownload" ;;
  esac
  local n=$frames
  [ "$mode" = cpu ] && n=$(( w > 2000 ? 10 : 30 ))  # the CPU reference is slow
  local launch="videotestsrc num-buffers=1 pattern=smpte ! video/x-raw,format=NV12,width=$w,height=$h,framerate=30/1 ! imagefreeze num-buffers=$n is-live=false ! $chain ! fakesink sync=false"
  local log=$out/$name-$mode-${w}x$h.log
  local t0 t1
  t0=$(date +%s.%N)
  # shellcheck disable=SC2086
  GST_TRACERS="latency(flags=pipeline+element)" GST_DEBUG="GST_TRACER:7" GST_DEBUG_NO_COLOR=1 \
    gst-launch-1.0 -q $launch >"$log" 2>&1
  local rc=$?
  t1=$(date +%s.%N)
  python3 - "$log" "$name" "$mode" "$w" "$h" "$n" "$t0" "$t1" "$rc" >>"$jsonl" <<'PY'
import json, re, statistics, sys
log, name, mode, w, h, n, t0, t1, rc = sys.argv[1:]
wall = float(t1) - float(t0)
pipe, elem = [], {}
for line in open(log, errors="replace"):
    m = re.search(r"time=\(guint64\)(\d+)", line)
    if not m:
        continue
    t = int(m.group(1)) / 1e6
    if "element-latency" in line:
        e = re.search(r"element=\(string\)([\w-]+)", line)
        if e and e.group(1).startswith(("pseudo3d", "cudaupload", "cudadownload")):
            elem.setdefault(e.group(1), []).append(t)
    elif re.search(r"\blatency,", line):
        pipe.append(t)
med = lambda v: round(statistics.median(v), 3) if v else None
print(json.dumps({"bench": "pipeline", "case": name, "mode": mode, "width": int(w), "height": int(h),
                  "frames": int(n), "wall_s": round(wall, 3), "fps": round(int(n) / wall, 1) if wall > 0 else None,
                  "pipeline_latency_ms_median": med(pipe),
                  "element_latency_ms_median": {k: med(v) for k, v in sorted(elem.items())},
                  "exit_code": int(rc)}))
PY
}

: >"$jsonl"
for size in 1920x1080 3840x2160; do
  w=${size%x*}; h=${size#*x}
  run_case chain "$w" "$h" cpu
  if [ $have_gpu = 1 ]; then
    run_case chain "$w" "$h" gpu-staged
    run_case chain "$w" "$h" gpu-resident
  fi
done

# 4K H.264: make a 10 s clip, then decode on the GPU, convert, encode, mux.
if [ $have_gpu = 1 ] && gst-inspect-1.0 nvh264dec >/dev/null 2>&1; then
  clip=$out/clip-4k.mp4 res=$out/clip-4k-sbs.mp4
  # 4:2:0, as NVDEC decodes (x264 would take 4:4:4 from videotestsrc otherwise).
  gst-launch-1.0 -q videotestsrc num-buffers=300 pattern=ball ! video/x-raw,format=I420,width=3840,height=2160,framerate=30/1 ! \
    x264enc speed-preset=ultrafast tune=zerolatency ! h264parse ! mp4mux ! filesink location="$clip" >/dev/null 2>&1
  for enc in encode decode-only; do
    if [ $enc = encode ]; then
      tail="cudadownload ! videoconvert n-threads=8 ! video/x-raw,format=I420 ! x264enc speed-preset=ultrafast threads=12 frame-packing=auto ! h264parse ! mp4mux ! filesink location=$res"
    else
      tail="cudadownload ! fakesink sync=false"
    fi
    t0=$(date +%s.%N)
    # shellcheck disable=SC2086
    gst-launch-1.0 -q filesrc location="$clip" ! qtdemux ! h264parse ! nvh264dec ! \
      pseudo3dconvert layout=side-by-side-half ! $tail >"$out/file-4k-$enc.log" 2>&1
    rc=$?
    t1=$(date +%s.%N)
    [ $rc -ne 0 ] && tail -5 "$out/file-4k-$enc.log" >&2
    python3 -c "import json,sys; w=float(sys.argv[2])-float(sys.argv[1]); print(json.dumps({'bench':'file','case':'h264-4k-'+sys.argv[3],'clip_s':10.0,'frames':300,'wall_s':round(w,3),'fps':round(300/w,1),'realtime_factor':round(10.0/w,2),'exit_code':int(sys.argv[4])}))" \
      "$t0" "$t1" "$enc" "$rc" >>"$jsonl"
  done
fi

python3 - "$jsonl" <<'PY'
import json, sys
print(f"{'case':<22}{'mode':<14}{'size':<11}{'fps':>8}{'latency ms':>12}  per-element latency ms (median)")
for l in open(sys.argv[1]):
    r = json.loads(l)
    if r["bench"] == "pipeline":
        el = " ".join(f"{k.replace('pseudo3d','')}={v}" for k, v in r["element_latency_ms_median"].items())
        print(f"{r['case']:<22}{r['mode']:<14}{str(r['width'])+'x'+str(r['height']):<11}{r['fps']:>8}"
              f"{str(r['pipeline_latency_ms_median']):>12}  {el}  rc={r['exit_code']}")
    else:
        print(f"{r['case']:<22}{'nvh264dec':<14}{'3840x2160':<11}{r['fps']:>8}{'':>12}  wall {r['wall_s']} s for a "
              f"{r['clip_s']} s clip ({r['realtime_factor']}x real time) rc={r['exit_code']}")
PY
