#!/usr/bin/env python3
"""Converts a raw little-endian RGB565 image (the firmware's output) to an 8-bit RGB PNG.

    rgb565_to_png.py IN.rgb565 OUT.png WIDTH HEIGHT

Each 5- or 6-bit channel is widened by bit replication (the usual RGB565 -> RGB888
expansion, as embedded-graphics' `Rgb888::from(Rgb565)` does). Standard library only.
"""

import struct
import sys
import zlib


def chunk(kind, data):
    return (struct.pack(">I", len(data)) + kind + data
            + struct.pack(">I", zlib.crc32(kind + data) & 0xFFFFFFFF))


def main():
    if len(sys.argv) != 5:
        sys.exit(__doc__)
    src, dst, width, height = sys.argv[1], sys.argv[2], int(sys.argv[3]), int(sys.argv[4])
    data = open(src, "rb").read()
    if len(data) != 2 * width * height:
        sys.exit(f"{src}: {len(data)} bytes, expected {2 * width * height} for {width}x{height}")
    rows = bytearray()
    for y in range(height):
        rows.append(0)  # filter: none
        for (v,) in struct.iter_unpack("<H", data[2 * width * y:2 * width * (y + 1)]):
            r, g, b = v >> 11, (v >> 5) & 0x3F, v & 0x1F
            rows += bytes(((r << 3) | (r >> 2), (g << 2) | (g >> 4), (b << 3) | (b >> 2)))
    png = (b"\x89PNG\r\n\x1a\n"
           + chunk(b"IHDR", struct.pack(">IIBBBBB", width, height, 8, 2, 0, 0, 0))
           + chunk(b"IDAT", zlib.compress(bytes(rows), 9))
           + chunk(b"IEND", b""))
    with open(dst, "wb") as f:
        f.write(png)


if __name__ == "__main__":
    main()
