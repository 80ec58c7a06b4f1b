#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""Writes the example textures of examples/textured_blobs.wrl (thesis figure 3-4: two metaballs with very different
textures): a checkerboard wrapped by a TexGenSphere and diagonal stripes projected by a TexGenPlane; and the blank
canvases flubber's suit, tie and face were painted on in the app (flubber_blank.png: its skin colour). Plain Python
(zlib), so the images can be made again anywhere: python3 scripts/make_example_textures.py examples/"""
import struct
import sys
import zlib


def write_png(path, width, height, pixel):
    rows = bytearray()
    for y in range(height):
        rows.append(0)  # filter: none
        for x in range(width):
            rows.extend(pixel(x, y))

    def chunk(kind, data):
        body = kind + data
        return struct.pack(">I", len(data)) + body + struct.pack(">I", zlib.crc32(body) & 0xFFFFFFFF)

    header = struct.pack(">IIBBBBB", width, height, 8, 2, 0, 0, 0)
    with open(path, "wb") as f:
        f.write(b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", header) + chunk(b"IDAT", zlib.compress(bytes(rows), 9)) +
                chunk(b"IEND", b""))


def checker(x, y):  # 16 x 8 squares on a 512 x 256 image: squares on the sphere
    return (235, 170, 40) if ((x // 32) + (y // 32)) % 2 == 0 else (250, 240, 215)


def stripes(x, y):  # blue and white diagonal stripes with a dark blue frame
    if min(x, y, 255 - x, 255 - y) < 8:
        return (20, 40, 110)
    return (40, 90, 200) if ((x + y) // 24) % 2 == 0 else (235, 240, 250)


if __name__ == "__main__":
    out = sys.argv[1] if len(sys.argv) > 1 else "examples/"
    write_png(out + "/textured_blobs_checker.png", 512, 256, checker)
    write_png(out + "/textured_blobs_stripes.png", 256, 256, stripes)
    write_png(out + "/flubber_blank.png", 256, 256, lambda x, y: (178, 231, 137))  # sRGB of linear 0.45 0.8 0.25
