#!/usr/bin/env python3
"""Compares two folders of frame_NNNN.png written by `himal bench --path ...
--images DIR` (e.g. `--occlusion hiz` against `off`): per frame, the pixels
that differ and the largest channel difference; then how many frames differ
at all. Plain Python (zlib), 8-bit RGB/RGBA PNGs without interlacing.

    python3 tools/compare_frames.py out/off out/hiz
"""
import os
import struct
import sys
import zlib


def read_png(path):
    with open(path, "rb") as f:
        data = f.read()
    if data[:8] != b"\x89PNG\r\n\x1a\n":
        raise ValueError(f"{path}: not a PNG")
    pos, idat, header = 8, b"", None
    while pos < len(data):
        (length,) = struct.unpack(">I", data[pos : pos + 4])
        kind = data[pos + 4 : pos + 8]
        body = data[pos + 8 : pos + 8 + length]
        if kind == b"IHDR":
            header = struct.unpack(">IIBBBBB", body)
        elif kind == b"IDAT":
            idat += body
        pos += 12 + length
    width, height, depth, color, _, _, interlace = header
    if depth != 8 or color not in (2, 6) or interlace:
        raise ValueError(f"{path}: only 8-bit RGB/RGBA, not interlaced")
    bpp = 3 if color == 2 else 4
    raw = zlib.decompress(idat)
    stride = width * bpp
    rows, prev = [], bytearray(stride)
    for y in range(height):
        kind = raw[y * (stride + 1)]
        line = bytearray(raw[y * (stride + 1) + 1 : (y + 1) * (stride + 1)])
        for i in range(stride):
            a = line[i - bpp] if i >= bpp else 0
            b = prev[i]
            c = prev[i - bpp] if i >= bpp else 0
            if kind == 1:
                line[i] = (line[i] + a) & 255
            elif kind == 2:
                line[i] = (line[i] + b) & 255
            elif kind == 3:
                line[i] = (line[i] + (a + b) // 2) & 255
            elif kind == 4:
                p = a + b - c
                pa, pb, pc = abs(p - a), abs(p - b), abs(p - c)
                pred = a if pa <= pb and pa <= pc else (b if pb <= pc else c)
                line[i] = (line[i] + pred) & 255
        rows.append(line)
        prev = line
    return width, height, bpp, rows


def main():
    a_dir, b_dir = sys.argv[1], sys.argv[2]
    names = sorted(n for n in os.listdir(a_dir) if n.startswith("frame_") and n.endswith(".png"))
    differing, total_pixels, total_diff = 0, 0, 0
    for name in names:
        wa, ha, bpp, ra = read_png(os.path.join(a_dir, name))
        wb, hb, bppb, rb = read_png(os.path.join(b_dir, name))
        if (wa, ha, bpp) != (wb, hb, bppb):
            raise ValueError(f"{name}: sizes differ")
        pixels, largest = 0, 0
        for la, lb in zip(ra, rb):
            for x in range(wa):
                d = max(abs(la[x * bpp + k] - lb[x * bpp + k]) for k in range(3))
                if d:
                    pixels += 1
                    largest = max(largest, d)
        total_pixels += wa * ha
        total_diff += pixels
        differing += pixels > 0
        print(f"{name}: {pixels} pixels differ ({100.0 * pixels / (wa * ha):.3f} %), largest {largest}/255")
    print(
        f"{differing} of {len(names)} frames differ; {total_diff} of {total_pixels} pixels "
        f"({100.0 * total_diff / max(total_pixels, 1):.4f} %)"
    )


if __name__ == "__main__":
    main()
