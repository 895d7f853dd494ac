#!/usr/bin/env python3
"""Bends a binary STL downwards like a loaded cantilever clamped at x = 0:
z -= depth * (x / length)^2, every triangle in place (so that the result has
the same vertices, in the same order, as the input).

  python3 tools/bend_stl.py datasets/meshes/book_60x40x20.stl \
      datasets/meshes/book_60x40x20_bent.stl 60 2
"""
import struct
import sys

source, target, length, depth = sys.argv[1], sys.argv[2], float(sys.argv[3]), float(sys.argv[4])
data = open(source, "rb").read()
count = struct.unpack_from("<I", data, 80)[0]
out = bytearray(data[:84])
for t in range(count):
    base = 84 + 50 * t
    values = list(struct.unpack_from("<12fH", data, base))
    for v in range(3):
        x = values[3 + 3 * v]
        values[3 + 3 * v + 2] -= depth * (x / length) ** 2
    out += struct.pack("<12fH", *values)
open(target, "wb").write(bytes(out))
