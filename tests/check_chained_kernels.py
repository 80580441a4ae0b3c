#!/usr/bin/env python3
"""Every CUDA kernel of cuda/ starts with chained_kernel_start(), or is marked
as launched plainly.

launch_chained() (cuda/chained_launch.cuh) lets a kernel start while the one
before it is still running; only the kernel's own chained_kernel_start()
makes it wait for that one's results. The launcher cannot see whether a
kernel has it (it checks the PTX version only), so a kernel launched chained
without it would read stale data on Hopper and later, and only there. This
check makes the choice explicit for every kernel: its body's first
statement is chained_kernel_start(), or a comment within the three lines
above its __global__ says "plain launch" (and its launcher uses <<< >>>).

Usage: check_chained_kernels.py CUDA_DIR ; exit 0 when every kernel is
covered, 1 with the list of those that are not.
"""
import pathlib
import re
import sys


def kernels(text):
    """(name, first statement, the three lines above) of each __global__ function."""
    lines = text.splitlines()
    for m in re.finditer(r"__global__\b", text):
        head_end = text.index("{", m.end())
        name = re.findall(r"(\w+)\s*\(", text[m.end():head_end])
        body = text[head_end + 1:]
        first = body.lstrip().split(";", 1)[0].strip() + ";"
        line_no = text.count("\n", 0, m.start())
        above = "\n".join(lines[max(0, line_no - 3):line_no])
        # the kernel's name: the last identifier before its parameter list
        # that is not __launch_bounds__
        names = [n for n in name if n != "__launch_bounds__"]
        yield (names[0] if names else "?"), first, above


def main():
    cuda_dir = pathlib.Path(sys.argv[1])
    bad, seen = [], 0
    for path in sorted(cuda_dir.glob("*.cu")):
        for name, first, above in kernels(path.read_text()):
            seen += 1
            if first == "chained_kernel_start();" or "plain launch" in above:
                continue
            bad.append(f"{path.name}: {name}: first statement '{first}'")
    if seen == 0:
        print(f"no kernels found under {cuda_dir}")
        return 1
    if bad:
        print("kernels that neither start with chained_kernel_start() nor are marked 'plain launch':")
        print("\n".join(bad))
        return 1
    print(f"{seen} kernels checked")
    return 0


if __name__ == "__main__":
    sys.exit(main())
