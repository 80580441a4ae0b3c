#!/usr/bin/env python3
"""Where a kernel's instructions go, from Nsight Compute's per-instruction counts.

    scripts/sass_profile.py SASS_CSV PIXELS [--kernel NAME] [--hot N]

SASS_CSV is `ncu --import REPORT --page source --csv --print-source sass`
of a report taken with `--section SourceCounters` (scripts/gpu-check.sh run
OUTDIR profile writes it). PIXELS is the frame's pixel count (3840x2160:
8294400). For the first profiled launch of every kernel it prints the
instructions executed, per warp and per pixel ("a pixel" = one thread
instruction per pixel when a warp covers 32 pixels: the figure the
benchmarks' notes quote), the opcodes' shares, and with --hot N the N
SASS lines executed most often. The stages are instruction bound
(docs/benchmarks.md), so this says where a cut can pay.
"""
import argparse
import collections
import csv
import sys


def sections(rows):
    """The report's kernels in order: (name, header, rows) for each launch."""
    out, cur = [], None
    for r in rows:
        if not r:
            continue
        if r[0] == "Kernel Name":
            cur = {"name": r[1], "header": None, "rows": []}
            out.append(cur)
        elif r[0] == "Address" and cur is not None:
            cur["header"] = r
        elif cur is not None and cur["header"] is not None:
            cur["rows"].append(r)
    return [s for s in out if s["header"]]


def opcode(sass):
    words = sass.split()
    if words and words[0].startswith("@"):  # a predicate guard
        words = words[1:]
    return words[0].split(".")[0] if words else ""


def short_name(name):
    """The kernel's name and template arguments, without its parameters and namespaces."""
    depth = 0
    for i, ch in enumerate(name):
        depth += {"<": 1, ">": -1}.get(ch, 0)
        if ch == "(" and depth == 0:
            name = name[:i]
            break
    if name.startswith("void "):
        name = name[5:]
    return name.replace("p3d::<unnamed>::", "").replace("p3d::", "")


def summarise(s, pixels, hot):
    h = s["header"]
    src, executed = h.index("Source"), h.index("Instructions Executed")
    counts = [(int(r[executed] or 0), r[src]) for r in s["rows"]]
    total = sum(n for n, _ in counts)
    warps_per_frame = pixels / 32.0
    print(f"{short_name(s['name'])}: {total} warp instructions, {total / warps_per_frame:.1f} a pixel")
    ops = collections.Counter()
    for n, text in counts:
        ops[opcode(text)] += n
    shares = ", ".join(f"{op} {100.0 * n / total:.1f} %" for op, n in ops.most_common(8)) if total else "-"
    print(f"  opcodes: {shares}")
    for n, text in sorted(counts, key=lambda c: -c[0])[:hot]:
        print(f"  {n:10d}  {n / warps_per_frame:6.2f} a pixel  {text}")


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("csv")
    ap.add_argument("pixels", type=int)
    ap.add_argument("--kernel", default="", help="only kernels whose name contains this")
    ap.add_argument("--hot", type=int, default=0)
    a = ap.parse_args()
    if a.pixels <= 0:
        sys.exit("PIXELS must be positive")
    with open(a.csv, newline="") as f:
        found = sections(list(csv.reader(f)))
    if not found:
        sys.exit(f"{a.csv}: no SourceCounters kernel sections (was the report taken with --section SourceCounters?)")
    seen = set()
    for s in found:
        if a.kernel not in s["name"] or s["name"] in seen:
            continue
        seen.add(s["name"])
        summarise(s, a.pixels, a.hot)
    if not seen:
        sys.exit(f"{a.csv}: no kernel matches {a.kernel!r}")


if __name__ == "__main__":
    main()
