#!/usr/bin/env python3
"""PNG checks for the shell tests, in plain Python (no imaging library on a bare Debian).

    pngcheck.py varied PNG            exit 0 when the middle row holds more than 8 distinct byte
                                      values (the image shows something, not one flat colour)
    pngcheck.py size PNG W H          exit 0 when the image is W x H pixels
    pngcheck.py same A.png B.png      exit 0 when the two images' header and pixels are equal
                                      (text chunks, such as POV-Ray's render time, aside)
"""
import struct
import sys
import zlib


def chunks(path):
    """The image header and the decompressed scanlines (each still led by its filter byte)."""
    data = open(path, "rb").read()
    if data[:8] != b"\x89PNG\r\n\x1a\n":
        sys.exit(f"pngcheck: {path}: not a PNG")
    pos, head, idat = 8, b"", b""
    while pos < len(data):
        n, kind = struct.unpack(">I4s", data[pos:pos + 8])
        body = data[pos + 8:pos + 8 + n]
        if kind == b"IHDR":
            head = body
        elif kind == b"IDAT":
            idat += body
        pos += 12 + n
    return head, zlib.decompress(idat)


def main():
    what, args = sys.argv[1], sys.argv[2:]
    if what == "varied":
        head, raw = chunks(args[0])
        width, height = struct.unpack(">II", head[:8])
        row = len(raw) // height
        values = set(raw[1 + (height // 2) * row:(height // 2 + 1) * row])
        print(f"pngcheck: {args[0]}: {width} x {height}, {len(values)} distinct byte values on the middle row")
        sys.exit(0 if len(values) > 8 else 1)
    if what == "size":
        width, height = struct.unpack(">II", chunks(args[0])[0][:8])
        sys.exit(0 if (width, height) == (int(args[1]), int(args[2])) else 1)
    if what == "same":
        sys.exit(0 if chunks(args[0]) == chunks(args[1]) else 1)
    sys.exit(f"pngcheck: unknown check {what} (varied, size, same)")


if __name__ == "__main__":
    main()
