#!/usr/bin/env bash
# Measures error against run time on real data and writes the report:
#   docs/quality.jsonl           raw measurements (tools/dev/quality/, one file per study)
#   docs/quality.md              tables and what they say
#   docs/img/quality-vs-time.png PSNR vs time of view synthesis, filter error vs time
# Builds pseudo3d-quality in build/ (BUILDDIR=... for another folder) and
# fetches the test data first. Extra arguments go to pseudo3d-quality
# (e.g. --quick for a smoke test, --runs 9, --threads 1 for timings that a
# shared machine disturbs less).
set -euo pipefail
top=$(cd "$(dirname "$0")/.." && pwd)
cd "$top"
builddir=${BUILDDIR:-build}
# Debian's interpreter has python3-matplotlib (setup-debian.sh installs it);
# another python3 first in PATH may not.
py=python3
[ -x /usr/bin/python3 ] && py=/usr/bin/python3
if ! "$py" -c 'import matplotlib' 2>/dev/null; then
  echo "quality-report: $py has no matplotlib (apt-get install python3-matplotlib)" >&2
  exit 1
fi

scripts/get-test-data.sh >/dev/null
[ -f "$builddir/build.ninja" ] || meson setup "$builddir" >/dev/null
ninja -C "$builddir" tools/dev/quality/pseudo3d-quality >/dev/null

mkdir -p docs/img
"$builddir/tools/dev/quality/pseudo3d-quality" --data data --out docs/quality.jsonl "$@"
"$py" scripts/plot_quality.py docs/quality.jsonl docs/img/quality-vs-time.png docs/quality.md
