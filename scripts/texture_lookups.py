"""Writes the small textures of genpath's texture tests and scenes/mitsuba/textures.xml, and
the table of Mitsuba 3.9.1's own lookups in them that tests/textures.rs compares genpath's
with. Run by hand, never by the build or CI:

    pip install mitsuba==3.9.1
    python3 scripts/texture_lookups.py

Writes scenes/mitsuba/textures/{grid,small,grey,one}.png (8-bit, written here byte by byte,
so that they need nothing but the standard library), float.exr (through Mitsuba's Bitmap),
and lookups.tsv: for every texture file, filter_type, wrap_mode, raw and to_uv (none, or
`st`: scale (2, 3) then translate (0.25, 0.1)), Mitsuba's `bitmap` evaluated (`eval`, the
`scalar_rgb` variant) at a fixed set of texture coordinates inside and outside [0, 1]² (none
of which lands, after `to_uv`, on a texel boundary, where the last bit of rounding decides
the texel); and
the `checkerboard` (colours (0.9, 0.5, 0.1) and (0.05, 0.2, 0.7)) at the same points.
"""
import os
import struct
import zlib

import mitsuba as mi

mi.set_variant("scalar_rgb")
HERE = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "scenes", "mitsuba", "textures")


def png(name, w, h, pixels, grey=False):
    """An 8-bit RGB (or grey) PNG of `pixels` (row 0 at the top), without dependencies."""
    raw = b""
    for y in range(h):
        row = [pixels[y * w + x] for x in range(w)]
        raw += b"\0" + bytes(v for p in row for v in ([p] if grey else p))

    def chunk(kind, data):
        body = kind + data
        return struct.pack(">I", len(data)) + body + struct.pack(">I", zlib.crc32(body) & 0xFFFFFFFF)

    header = struct.pack(">IIBBBBB", w, h, 8, 0 if grey else 2, 0, 0, 0)
    data = b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", header) + chunk(b"IDAT", zlib.compress(raw, 9)) + chunk(b"IEND", b"")
    with open(os.path.join(HERE, name), "wb") as f:
        f.write(data)


def grid():
    """8 × 8: a colour ramp in u and v, with a dark diagonal so that flips show."""
    px = []
    for y in range(8):
        for x in range(8):
            if x == y:
                px.append((20, 20, 20))
            else:
                px.append((40 + 30 * x, 40 + 25 * y, 200 - 20 * x))
    return px


os.makedirs(HERE, exist_ok=True)
png("grid.png", 8, 8, grid())
png("small.png", 3, 2, [(0, 0, 0), (255, 128, 64), (10, 200, 30), (90, 90, 250), (255, 255, 255), (128, 0, 0)])
png("grey.png", 2, 2, [0, 100, 200, 255], grey=True)
png("one.png", 1, 1, [(200, 100, 50)])
floats = [0.0, 0.5, 2.0, 0.25, 1.0, 0.125, 3.0, 0.0, 0.75, 0.1, 0.2, 0.3, 1.5, 0.9, 0.05, 0.6, 0.4, 0.0]
mi.Bitmap(mi.TensorXf(floats, shape=(2, 3, 3))).write(os.path.join(HERE, "float.exr"))

UVS = [(0.0, 0.0), (0.1, 0.2), (0.5, 0.5), (0.37, 0.81), (0.999, 0.001), (1.0, 1.0),
       (-0.3, 0.4), (1.2, -0.7), (2.6, 1.45), (-1.55, -2.23), (0.26, 0.74), (0.74, 0.26)]
ST = mi.ScalarTransform4f().translate([0.25, 0.1, 0.0]) @ mi.ScalarTransform4f().scale([2.0, 3.0, 1.0])


def lookup(texture, u, v):
    si = mi.SurfaceInteraction3f()
    si.uv = mi.Point2f(u, v)
    return texture.eval(si)


rows = []
for name in ["grid.png", "small.png", "grey.png", "one.png", "float.exr"]:
    for filt in ["nearest", "bilinear"]:
        for wrap in ["repeat", "mirror", "clamp"]:
            for raw in [False, True]:
                for to_uv in ["none", "st"]:
                    d = {"type": "bitmap", "filename": os.path.join(HERE, name),
                         "filter_type": filt, "wrap_mode": wrap, "raw": raw}
                    if to_uv == "st":
                        d["to_uv"] = ST
                    t = mi.load_dict(d)
                    for u, v in UVS:
                        c = lookup(t, u, v)
                        rows.append([name, filt, wrap, str(int(raw)), to_uv, u, v, c[0], c[1], c[2]])
for to_uv in ["none", "st"]:
    d = {"type": "checkerboard", "color0": {"type": "rgb", "value": [0.9, 0.5, 0.1]},
         "color1": {"type": "rgb", "value": [0.05, 0.2, 0.7]}}
    if to_uv == "st":
        d["to_uv"] = ST
    t = mi.load_dict(d)
    for u, v in UVS:
        c = lookup(t, u, v)
        rows.append(["checkerboard", "-", "-", "0", to_uv, u, v, c[0], c[1], c[2]])
with open(os.path.join(HERE, "lookups.tsv"), "w") as f:
    f.write("# Mitsuba %s bitmap/checkerboard lookups (scripts/texture_lookups.py)\n" % mi.__version__)
    f.write("file\tfilter\twrap\traw\tto_uv\tu\tv\tr\tg\tb\n")
    for r in rows:
        f.write("\t".join(str(x) if isinstance(x, str) else "%.9g" % x for x in r) + "\n")
print(len(rows), "lookups")
