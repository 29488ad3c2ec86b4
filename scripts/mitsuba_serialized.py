"""Writes scenes/mitsuba/meshes/params.serialized, the mesh file of scenes/mitsuba/params.xml,
in Mitsuba's serialized format, version 4 (`src/shapes/serialized.cpp`): per mesh the magic
0x041C and the version, then a zlib stream of the flags (0x1000: single precision; no
normals, texture coordinates or colours), the null-terminated name, the vertex and triangle
counts (u64), the positions (f32 x, y, z) and the triangles (u32); after the last mesh the
table of the meshes' offsets (u64) and their count (u32), all little-endian.

    python3 scripts/mitsuba_serialized.py

Mesh 0, "wedge": a triangular prism (8 triangles), outward-facing (each triangle's
(v1 − v0) × (v2 − v0) points out), its base on y = 0 inside [-0.5, 0.5]², 0.8 high.
Mesh 1, "lamp": the unit square [-0.5, 0.5]² of y = 0 as two triangles whose normals point
up (+y); params.xml hangs it under the ceiling with flip_normals, so that it emits down.
"""
import os
import struct
import zlib

WEDGE_VERTICES = [
    (-0.5, 0.0, -0.5), (0.5, 0.0, -0.5), (0.0, 0.8, -0.5),  # back triangle, z = -0.5
    (-0.5, 0.0, 0.5), (0.5, 0.0, 0.5), (0.0, 0.8, 0.5),  # front triangle, z = 0.5
]
WEDGE_TRIANGLES = [
    (0, 2, 1), (3, 4, 5),  # back (−z), front (+z)
    (0, 1, 4), (0, 4, 3),  # bottom (−y)
    (1, 2, 5), (1, 5, 4),  # right slope
    (2, 0, 3), (2, 3, 5),  # left slope
]
LAMP_VERTICES = [(-0.5, 0.0, -0.5), (0.5, 0.0, -0.5), (0.5, 0.0, 0.5), (-0.5, 0.0, 0.5)]
LAMP_TRIANGLES = [(0, 2, 1), (0, 3, 2)]


def cross(a, b):
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


def check_outward(vertices, triangles):
    centre = [sum(v[i] for v in vertices) / len(vertices) for i in range(3)]
    for t in triangles:
        a, b, c = (vertices[i] for i in t)
        n = cross([b[i] - a[i] for i in range(3)], [c[i] - a[i] for i in range(3)])
        out = [sum(v[i] for v in (a, b, c)) / 3 - centre[i] for i in range(3)]
        assert sum(n[i] * out[i] for i in range(3)) > 0, t


def mesh(name, vertices, triangles):
    body = struct.pack("<I", 0x1000) + name.encode() + b"\0"
    body += struct.pack("<QQ", len(vertices), len(triangles))
    body += b"".join(struct.pack("<3f", *v) for v in vertices)
    body += b"".join(struct.pack("<3I", *t) for t in triangles)
    return struct.pack("<HH", 0x041C, 4) + zlib.compress(body, 9)


check_outward(WEDGE_VERTICES, WEDGE_TRIANGLES)
check_outward(LAMP_VERTICES + [(0.0, -1.0, 0.0)], LAMP_TRIANGLES)
out = bytearray()
offsets = []
for m in (mesh("wedge", WEDGE_VERTICES, WEDGE_TRIANGLES), mesh("lamp", LAMP_VERTICES, LAMP_TRIANGLES)):
    offsets.append(len(out))
    out += m
out += b"".join(struct.pack("<Q", o) for o in offsets) + struct.pack("<I", len(offsets))
path = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "scenes", "mitsuba", "meshes", "params.serialized")
with open(path, "wb") as f:
    f.write(out)
print(f"{path}: {len(out)} bytes")
