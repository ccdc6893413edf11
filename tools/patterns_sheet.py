#!/usr/bin/env python3
"""Renders docs/patterns.png, the contact sheet of `require "patterns"`.

luster renders examples/scenes/patterns.xml (every pattern and four warps on
tiles with their names, examples/shaders/patterns_sheet.lua); the sheet is
grey, so this stores it as an 8-bit greyscale PNG, a third of the RGB file.
Only the Python standard library is needed.

    cargo build --release
    python3 tools/patterns_sheet.py            # writes docs/patterns.png
"""

import argparse
import pathlib
import struct
import subprocess
import sys
import tempfile
import zlib

ROOT = pathlib.Path(__file__).resolve().parent.parent


def chunks(data):
    pos = 8
    while pos < len(data):
        (length,) = struct.unpack(">I", data[pos : pos + 4])
        kind = data[pos + 4 : pos + 8]
        yield kind, data[pos + 8 : pos + 8 + length]
        pos += 12 + length


def paeth(a, b, c):
    p = a + b - c
    pa, pb, pc = abs(p - a), abs(p - b), abs(p - c)
    if pa <= pb and pa <= pc:
        return a
    return b if pb <= pc else c


def read_rgb(path):
    """The rows of an 8-bit RGB or RGBA PNG, unfiltered, and its size."""
    data = path.read_bytes()
    if data[:8] != b"\x89PNG\r\n\x1a\n":
        sys.exit(f"{path}: not a PNG file")
    idat = b""
    for kind, body in chunks(data):
        if kind == b"IHDR":
            width, height, depth, colour, _, _, interlace = struct.unpack(">IIBBBBB", body)
            if depth != 8 or colour not in (2, 6) or interlace:
                sys.exit(f"{path}: expected an 8-bit RGB(A) PNG without interlacing")
        elif kind == b"IDAT":
            idat += body
    bpp = 3 if colour == 2 else 4
    raw = zlib.decompress(idat)
    stride = width * bpp
    rows, prev = [], bytearray(stride)
    for y in range(height):
        f = raw[y * (stride + 1)]
        line = bytearray(raw[y * (stride + 1) + 1 : (y + 1) * (stride + 1)])
        for i in range(stride):
            a = line[i - bpp] if i >= bpp else 0
            b = prev[i]
            c = prev[i - bpp] if i >= bpp else 0
            if f == 1:
                line[i] = (line[i] + a) & 255
            elif f == 2:
                line[i] = (line[i] + b) & 255
            elif f == 3:
                line[i] = (line[i] + (a + b) // 2) & 255
            elif f == 4:
                line[i] = (line[i] + paeth(a, b, c)) & 255
        rows.append(line)
        prev = line
    return width, height, bpp, rows


def write_grey(path, width, height, rows):
    """An 8-bit greyscale PNG; each row takes the filter that leaves the
    smallest sum of magnitudes (libpng's heuristic)."""
    out, prev = bytearray(), bytearray(width)
    for line in rows:
        best = None
        for f in range(5):
            enc = bytearray(width)
            for i in range(width):
                a = line[i - 1] if i else 0
                b = prev[i]
                c = prev[i - 1] if i else 0
                pred = (0, a, b, (a + b) // 2, paeth(a, b, c))[f]
                enc[i] = (line[i] - pred) & 255
            cost = sum(v if v < 128 else 256 - v for v in enc)
            if best is None or cost < best[0]:
                best = (cost, f, enc)
        out.append(best[1])
        out += best[2]
        prev = line

    def chunk(kind, body):
        return struct.pack(">I", len(body)) + kind + body + struct.pack(">I", zlib.crc32(kind + body))

    png = b"\x89PNG\r\n\x1a\n"
    png += chunk(b"IHDR", struct.pack(">IIBBBBB", width, height, 8, 0, 0, 0, 0))
    png += chunk(b"IDAT", zlib.compress(bytes(out), 9))
    png += chunk(b"IEND", b"")
    path.write_bytes(png)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--luster", default=str(ROOT / "target/release/luster"), help="the luster binary")
    parser.add_argument("--out", default=str(ROOT / "docs/patterns.png"), help="the sheet to write")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        scene = ROOT / "examples/scenes/patterns.xml"
        subprocess.run([args.luster, "render", str(scene), "-o", tmp], check=True)
        width, height, bpp, rows = read_rgb(pathlib.Path(tmp) / "patterns.png")
    grey = []
    for line in rows:
        g = line[0::bpp]
        if g != line[1::bpp] or g != line[2::bpp]:
            sys.exit("the sheet is not grey: was the scene or its shader changed?")
        grey.append(g)
    write_grey(pathlib.Path(args.out), width, height, grey)
    print(f"{args.out}: {width}x{height}, {pathlib.Path(args.out).stat().st_size // 1024} KiB")


if __name__ == "__main__":
    main()
