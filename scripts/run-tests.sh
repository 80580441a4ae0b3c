#!/usr/bin/env bash
# Builds and runs the test suites: the CPU suite always; the GPU suite runs
# where a CUDA device is usable and reports "skipped" (exit 77) elsewhere.
# Prints a closing "N passed, N failed, N skipped" line.
set -uo pipefail
top=$(cd "$(dirname "$0")/.." && pwd)
cd "$top"
"$top/scripts/get-test-data.sh" || exit 1
"$top/scripts/build.sh" -Dtests=auto || exit 1  # a quick-start build/ has them off
meson test -C build --print-errorlogs --num-processes 2 "$@"
rc=$?
python3 "$top/scripts/junit_summary.py" "$top/build/meson-logs/testlog.junit.xml"
exit $rc
