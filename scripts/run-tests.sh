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
python3 - "$top/build/meson-logs/testlog.json" <<'PY'
import json, sys
counts = {"OK": 0, "FAIL": 0, "SKIP": 0, "TIMEOUT": 0, "ERROR": 0, "EXPECTEDFAIL": 0, "UNEXPECTEDPASS": 0}
for line in open(sys.argv[1]):
    r = json.loads(line)
    counts[r["result"]] = counts.get(r["result"], 0) + 1
failed = counts["FAIL"] + counts["TIMEOUT"] + counts["ERROR"] + counts["UNEXPECTEDPASS"]
print(f"{counts['OK']} passed, {failed} failed, {counts['SKIP']} skipped")
PY
exit $rc
