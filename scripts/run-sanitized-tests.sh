#!/usr/bin/env bash
# Builds the CPU code with AddressSanitizer and UndefinedBehaviorSanitizer
# into build-asan/ and runs the CPU suite there (CUDA off: the sanitizers
# watch host code; the GPU code has compute-sanitizer on the GPU machine).
# GST_REGISTRY_FORK=no scans plugins in the test process itself: the forked
# gst-plugin-scanner is no sanitized program and would be the one to crash on
# loading the sanitized plugin. Any sanitizer report fails the run.
# Prints a closing "N passed, N failed, N skipped" line.
set -uo pipefail
top=$(cd "$(dirname "$0")/.." && pwd)
cd "$top"
"$top/scripts/get-test-data.sh" >/dev/null || exit 1
if [ ! -f build-asan/build.ninja ]; then
  meson setup build-asan -Dcuda=disabled -Db_sanitize=address,undefined -Db_lundef=false -Dbuildtype=debugoptimized \
    >/dev/null || exit 1
fi
ninja -C build-asan || exit 1
export GST_REGISTRY_FORK=no
# The plugin registry is made once, here, with leak checks off, so that no
# test process scans it: a scan loads every installed plugin (libav, gsm,
# OpenNI2, fontconfig through pango, ...) into the scanning process, and
# their one-time allocations, not ours, would be reported as leaks by
# whichever test happened to scan first. Same paths as the tests' own
# environment (tests/elements/meson.build), so they find it current.
# LD_PRELOAD: gst-inspect is no sanitized program; the sanitized plugin needs
# the ASan runtime loaded first.
GST_REGISTRY_1_0=$top/build-asan/test-registry.bin GST_PLUGIN_PATH_1_0=$top/build-asan/gst \
  ASAN_OPTIONS=detect_leaks=0 LD_PRELOAD=$(gcc -print-file-name=libasan.so) \
  gst-inspect-1.0 pseudo3dpack >/dev/null || { echo "sanitizers: the sanitized plugin does not load" >&2; exit 1; }
# fast_unwind_on_malloc=0: full stacks through GLib (built without frame
# pointers), so the suppressions can see where an allocation came from.
export ASAN_OPTIONS=detect_leaks=1:strict_string_checks=1:detect_stack_use_after_return=1:fast_unwind_on_malloc=0
export LSAN_OPTIONS=suppressions=$top/tests/sanitizers/lsan.supp:print_suppressions=0
export UBSAN_OPTIONS=halt_on_error=1:print_stacktrace=1
meson test -C build-asan --suite cpu --print-errorlogs --num-processes 2 --timeout-multiplier 4 "$@"
rc=$?
python3 "$top/scripts/junit_summary.py" "$top/build-asan/meson-logs/testlog.junit.xml" "sanitizers"
exit $rc
