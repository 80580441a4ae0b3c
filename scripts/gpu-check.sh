#!/usr/bin/env bash
# GPU build, tests, sanitizers and benchmark in one go.
#
#   scripts/gpu-check.sh prepare        (here, no GPU needed) builds build-gpu/
#       for sm_90, bundles GStreamer + the project's binaries + test data into
#       .gpu/payload.tar.gz with scripts/make-gst-runtime.sh.
#   scripts/gpu-check.sh run [OUTDIR [tests|sanitize|pipelines|convert|profile|all]]   (on the GPU machine, from the repo
#       root, with .gpu carried) unpacks, runs the GPU suites, compute-sanitizer
#       memcheck on the kernel suite and on element cases, racecheck on the
#       kernels that use shared memory (large sizes filtered out: the
#       sanitizers are ~100x slower), pseudo3d-bench, and prints a table;
#       "convert" runs scripts/bench-convert.sh (pseudo3d-convert --benchmark
#       on a 4K H.264 clip: convert-to-fakesink against decode-only);
#       "profile" takes Nsight Compute's per-instruction counts of one
#       frame's kernels (P3D_PROFILE_SIZE, default 3840x2160; the first
#       P3D_PROFILE_LAUNCHES launches, default 12) and summarises them with
#       scripts/sass_profile.py (profile.txt; sass.csv and details.csv
#       beside it).
#       Full logs and results land in OUTDIR (default gpu-results/).
#
# With the device tool:  run(command="scripts/gpu-check.sh run $OUT", carry=[".gpu"])
set -uo pipefail
top=$(cd "$(dirname "$0")/.." && pwd)
cd "$top"

prepare() {
  set -e
  # The test data first: the build turns it into the raw dumps the GPU suites read.
  scripts/get-test-data.sh >/dev/null
  [ -f build-gpu/build.ninja ] || meson setup build-gpu -Dbuildtype=release -Dgpu_arch=90 -Dcuda=enabled >/dev/null
  ninja -C build-gpu
  rm -rf .gpu && mkdir -p .gpu/payload/bin .gpu/payload/data
  local bins=(build-gpu/tests/gpu/test_gpu build-gpu/tests/gpu/test_gpu_elements
              build-gpu/tools/dev/bench/pseudo3d-bench build-gpu/tools/convert/pseudo3d-convert)
  "$top/scripts/make-gst-runtime.sh" .gpu/payload/gstrt build-gpu/gst/libgstpseudo3d.so "${bins[@]}" >/dev/null
  cp "${bins[@]}" build-gpu/gst/libgstpseudo3d.so .gpu/payload/bin/
  strip --strip-unneeded .gpu/payload/bin/* 2>/dev/null || true
  cp build-gpu/tests/raw-data/*.p3draw .gpu/payload/data/  # decoded here: no image codecs there
  tar czf .gpu/payload.tar.gz -C .gpu payload && rm -rf .gpu/payload
  echo "prepared .gpu/payload.tar.gz ($(du -h .gpu/payload.tar.gz | cut -f1))"
}

run() {
  local out=${1:-gpu-results} what=${2:-all}
  mkdir -p "$out"
  local work=/tmp/p3d-gpu
  rm -rf "$work" && mkdir -p "$work" && tar xzf .gpu/payload.tar.gz -C "$work"
  local p=$work/payload
  # shellcheck disable=SC1091
  source "$p/gstrt/env.sh"
  export GST_PLUGIN_PATH_1_0=$p/bin XDG_RUNTIME_DIR=/tmp P3D_DATA_DIR=$p/data P3D_OUT_DIR=$work/test-output
  export LD_LIBRARY_PATH=$p/gstrt/lib:${LD_LIBRARY_PATH:-}
  nvidia-smi --query-gpu=name,driver_version,memory.total --format=csv,noheader | tee "$out/gpu.txt"
  gst-inspect-1.0 pseudo3d >"$out/inspect.txt" 2>&1 || echo "plugin did not load" | tee -a "$out/summary.txt"

  local big='*Uhd*:*7680*:*3840*:*EightK*:*UltraHd*:*Large*:*8k*:*4k*:*8K*:*4K*'
  declare -A rc
  if [ "$what" = tests ] || [ "$what" = all ]; then
  "$p/bin/test_gpu" --gtest_output=xml:"$out/test_gpu.xml" >"$out/test_gpu.log" 2>&1; rc[kernels]=$?
  "$p/bin/test_gpu_elements" --gtest_output=xml:"$out/test_gpu_elements.xml" >"$out/test_gpu_elements.log" 2>&1; rc[elements]=$?
  "$p/bin/pseudo3d-bench" --out "$out/bench.jsonl" >"$out/bench.txt" 2>&1; rc[bench]=$?
  fi
  if [ "$what" = pipelines ]; then
    "$top/scripts/bench-pipelines.sh" "$out" >"$out/pipelines.txt" 2>&1; rc[pipelines]=$?
  fi
  if [ "$what" = convert ]; then
    P3D_CONVERT=$p/bin/pseudo3d-convert P3D_BENCH_WORK=$work/convert \
      "$top/scripts/bench-convert.sh" "$out" >"$out/convert.txt" 2>&1; rc[convert]=$?
  fi
  if [ "$what" = profile ]; then
    local size=${P3D_PROFILE_SIZE:-3840x2160}
    # The bench computes each input frame's stages once before it times
    # anything: the first dozen launches are one frame's depth, filter and
    # warp kernels.
    ncu --section SourceCounters --section SpeedOfLight --launch-count "${P3D_PROFILE_LAUNCHES:-12}" -o "$out/profile" \
      "$p/bin/pseudo3d-bench" --device gpu --size "$size" --iterations 2 --out "$work/profile-bench.jsonl" \
      >"$out/ncu.log" 2>&1; rc[profile]=$?
    ncu --import "$out/profile.ncu-rep" --page source --csv --print-source sass >"$out/sass.csv" 2>>"$out/ncu.log"
    ncu --import "$out/profile.ncu-rep" --page details --csv >"$out/details.csv" 2>>"$out/ncu.log"
    rm -f "$out/profile.ncu-rep"  # tens of MB; the CSVs hold what the summary reads
    "$top/scripts/sass_profile.py" "$out/sass.csv" "$(( ${size%x*} * ${size#*x} ))" --hot 5 >"$out/profile.txt" 2>&1 ||
      rc[profile]=1
  fi
  if [ "$what" != tests ] && [ "$what" != pipelines ] && [ "$what" != convert ] && [ "$what" != profile ]; then
  compute-sanitizer --tool memcheck --leak-check full --error-exitcode 3 "$p/bin/test_gpu" --gtest_filter="-$big" \
    >"$out/memcheck.log" 2>&1; rc[memcheck]=$?
  compute-sanitizer --tool memcheck --error-exitcode 3 "$p/bin/test_gpu_elements" --gtest_filter='*RGBA_333x177*:*BGRx_1001x7*:*GpuFaults*:*GpuContext*' \
    >"$out/memcheck-elements.log" 2>&1; rc[memcheck_elements]=$?
  # racecheck looks at shared memory only: the kernels that use it (depth,
  # bilateral, warp; pack and convert have none), on the small and odd
  # sizes: the sanitizer is ~100x slower, and the Aloe-sized cases and the
  # bilateral's stiff inputs would take it past the device tool's
  # 10-minute limit on a command.
  local shared='GpuDepth.*:GpuBilateral*:GpuWarp.*:GpuExtremeDepth.*Small*:GpuExtremeWarp.*Small*'
  compute-sanitizer --tool racecheck --error-exitcode 3 "$p/bin/test_gpu" --gtest_filter="$shared-$big:*Aloe*" \
    >"$out/racecheck.log" 2>&1; rc[racecheck]=$?
  fi

  {
    echo "== GPU: $(cat "$out/gpu.txt")"
    for k in "${!rc[@]}"; do printf '%-18s exit %s\n' "$k" "${rc[$k]}"; done
    grep -hE '^\[  (PASSED|FAILED) |^\[  FAILED  \]' "$out"/test_gpu*.log 2>/dev/null
    grep -hE 'ERROR SUMMARY|RACECHECK SUMMARY' "$out"/memcheck*.log "$out"/racecheck.log 2>/dev/null
    [ -f "$out/bench.txt" ] && { echo "== benchmark"; cat "$out/bench.txt"; }
    [ -f "$out/pipelines.txt" ] && { echo "== pipelines"; cat "$out/pipelines.txt"; }
    [ -f "$out/convert.txt" ] && { echo "== pseudo3d-convert"; cat "$out/convert.txt"; }
    [ -f "$out/profile.txt" ] && { echo "== instructions (Nsight Compute SourceCounters)"; cat "$out/profile.txt"; }
  } | tee "$out/summary.txt"
  local fail=0
  for k in "${!rc[@]}"; do [ "${rc[$k]}" -ne 0 ] && fail=1; done
  return $fail
}

case "${1:-}" in
  prepare) prepare ;;
  run) shift; run "$@" ;;
  *) echo "usage: $0 prepare | run [OUTDIR [tests|sanitize|pipelines|convert|profile|all]]" >&2; exit 2 ;;
esac
