"""A minimal OpenEXR writer (uncompressed scanlines, float32 R, G, B), so that the scripts
that make the environment maps of scenes/ need nothing beyond Python's standard library.

    from exr_write import write_exr
    write_exr(path, width, height, pixels)   # pixels[y][x] = (r, g, b), row 0 at the top
"""
import struct


def _attribute(name, kind, value):
    return name.encode() + b"\0" + kind.encode() + b"\0" + struct.pack("<i", len(value)) + value


def write_exr(path, width, height, pixels):
    channels = b"".join(
        c.encode() + b"\0" + struct.pack("<iB3xii", 2, 0, 1, 1) for c in "BGR"
    ) + b"\0"
    window = struct.pack("<iiii", 0, 0, width - 1, height - 1)
    header = (
        struct.pack("<ii", 20000630, 2)
        + _attribute("channels", "chlist", channels)
        + _attribute("compression", "compression", b"\0")
        + _attribute("dataWindow", "box2i", window)
        + _attribute("displayWindow", "box2i", window)
        + _attribute("lineOrder", "lineOrder", b"\0")
        + _attribute("pixelAspectRatio", "float", struct.pack("<f", 1.0))
        + _attribute("screenWindowCenter", "v2f", struct.pack("<ff", 0.0, 0.0))
        + _attribute("screenWindowWidth", "float", struct.pack("<f", 1.0))
        + b"\0"
    )
    line_bytes = 3 * 4 * width
    first = len(header) + 8 * height
    offsets = b"".join(struct.pack("<Q", first + y * (8 + line_bytes)) for y in range(height))
    lines = []
    for y in range(height):
        row = pixels[y]
        data = b"".join(
            struct.pack("<%df" % width, *(row[x][c] for x in range(width))) for c in (2, 1, 0)
        )
        lines.append(struct.pack("<ii", y, line_bytes) + data)
    with open(path, "wb") as f:
        f.write(header + offsets + b"".join(lines))
