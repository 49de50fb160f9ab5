#!/usr/bin/python3
"""Writes a large synthetic survey for the lidar memory and time measurements (bench/results/lidar.md): NX x NY
copies of a LAS 1.4 file (e.g. the settlements `hashfusion lidar --input synthetic:1` writes) side by side, each
shifted by the input's extent rounded up to whole metres. Only the point coordinates and the header's counts and
bounds change.

    scripts/lidar_replicate_las.py IN.las OUT.las NX NY
"""
import struct
import sys

import numpy as np


def main():
    src, dst, nx, ny = sys.argv[1], sys.argv[2], int(sys.argv[3]), int(sys.argv[4])
    data = open(src, "rb").read()
    if data[:4] != b"LASF" or data[25] != 4:
        sys.exit(f"{src}: expected a LAS 1.4 file")
    offset = struct.unpack_from("<I", data, 96)[0]
    fmt, rec = data[104], struct.unpack_from("<H", data, 105)[0]
    scale = struct.unpack_from("<3d", data, 131)
    off = struct.unpack_from("<3d", data, 155)
    max_x, min_x, max_y, min_y, max_z, min_z = struct.unpack_from("<6d", data, 179)
    count = struct.unpack_from("<Q", data, 247)[0]
    points = np.frombuffer(data, dtype=np.uint8, count=count * rec, offset=offset).reshape(count, rec)
    xy = points[:, :8].copy().view("<i4").reshape(count, 2)
    step_x, step_y = np.ceil(max_x - min_x + 1), np.ceil(max_y - min_y + 1)
    header = bytearray(data[:offset])
    struct.pack_into("<I", header, 107, 0)  # legacy count: 0 for formats 6-10
    struct.pack_into("<6d", header, 179, min_x + nx * step_x, min_x, min_y + ny * step_y, min_y, max_z, min_z)
    struct.pack_into("<Q", header, 247, count * nx * ny)
    struct.pack_into("<15Q", header, 255, *([0] * 15))
    with open(dst, "wb") as out:
        out.write(header)
        copy = points.copy()
        for j in range(ny):
            for i in range(nx):
                shifted = xy + np.array([round(i * step_x / scale[0]), round(j * step_y / scale[1])], dtype=np.int64)
                copy[:, :8] = shifted.astype("<i4").view(np.uint8).reshape(count, 8)
                out.write(copy.tobytes())
    print(f"{dst}: {count * nx * ny} points of format {fmt}, {nx} x {ny} copies of {src}")


if __name__ == "__main__":
    main()
