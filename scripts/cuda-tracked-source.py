#!/usr/bin/env python3
"""Copies a .cu file into the build tree for meson.build's CUDA targets.

Meson 1.0 passes nvcc no dependency flags, so ninja never learns which
headers a .cu includes and would not recompile it after a header changes.
meson.build compiles this copy instead, made by a custom target whose
inputs are the .cu and the headers: a header change re-runs the copy and
the copy is compiled anew. A #line directive keeps compiler messages
pointing at the original file.

    cuda-tracked-source.py SOURCE.cu OUTPUT.cu [HEADER...]
"""
import os
import sys

source, output = sys.argv[1], sys.argv[2]
with open(source, encoding="utf-8") as f:
    text = f.read()
with open(output, "w", encoding="utf-8") as f:
    f.write('#line 1 "%s"\n' % os.path.abspath(source))
    f.write(text)
