"""A minimal PNG writer (8-bit RGB, one zlib stream), so that the scripts that make the
textures of scenes/ need nothing beyond Python's standard library.

    from png_write import write_png
    write_png(path, width, height, pixels)   # pixels[y * width + x] = (r, g, b), row 0 at the top
"""
import struct
import zlib


def write_png(path, width, height, pixels):
    raw = b"".join(
        b"\0" + bytes(v for x in range(width) for v in pixels[y * width + x]) for y in range(height)
    )

    def chunk(kind, data):
        body = kind + data
        return struct.pack(">I", len(data)) + body + struct.pack(">I", zlib.crc32(body) & 0xFFFFFFFF)

    header = struct.pack(">IIBBBBB", width, height, 8, 2, 0, 0, 0)
    data = b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", header) + chunk(b"IDAT", zlib.compress(raw, 9)) + chunk(b"IEND", b"")
    with open(path, "wb") as f:
        f.write(data)
