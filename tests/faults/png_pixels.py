#!/usr/bin/env python3
"""png_pixels.py A.png B.png: exit 0 when the two PNGs have the same header (IHDR) and the same
pixels (the decompressed IDAT stream), 1 otherwise. POV-Ray stamps every PNG with its render
time (a tIME chunk), so two renders of the same frame differ in bytes, never in pixels."""
import struct
import sys
import zlib


def pixels(path):
    data, at, head, idat = open(path, 'rb').read(), 8, b'', b''
    while at + 8 <= len(data):
        n, kind = struct.unpack('>I4s', data[at:at + 8])
        if kind == b'IHDR':
            head = data[at + 8:at + 8 + n]
        elif kind == b'IDAT':
            idat += data[at + 8:at + 8 + n]
        at += 12 + n
    return head, zlib.decompress(idat)


try:
    sys.exit(0 if pixels(sys.argv[1]) == pixels(sys.argv[2]) else 1)
except (OSError, zlib.error, struct.error):
    sys.exit(1)
