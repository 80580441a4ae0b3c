#!/usr/bin/env bash
# Builds and runs the test suites: the CPU suite always; the GPU suite runs
# where a CUDA device is usable and reports "skipped" (exit 77) elsewhere.
# Prints a closing "N passed, N failed, N skipped" line.
set -uo pipefail
top=$(cd "$(dirname "$0")/.." && pwd)
cd "$top"
"$top/scripts/get-test-data.sh" || exit 1
"$top/scripts/build.sh" || exit 1
meson test -C build --print-errorlogs --num-processes 2 "$@"
rc=$?
# Closing line over every test case (gtest cases as meson's JUnit log lists them).
python3 - "$top/build/meson-logs/testlog.junit.xml" <<'PY'
import sys
import xml.etree.ElementTree as ET
passed = failed = skipped = 0
for case in ET.parse(sys.argv[1]).getroot().iter("testcase"):
    kinds = {child.tag for child in case}
    if kinds & {"failure", "error"}:
        failed += 1
    elif "skipped" in kinds:
        skipped += 1
    else:
        passed += 1
print(f"{passed} passed, {failed} failed, {skipped} skipped")
PY
exit $rc
