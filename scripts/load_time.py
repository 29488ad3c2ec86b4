"""Load time of a large Mitsuba scene (issue 25): writes a binary little-endian PLY of a
height-field grid of about N triangles (default 1 000 000) and an XML scene that uses it
into DIR (default a temporary directory), renders it with genpath at 1 spp and 16², and
prints the render JSON's `times_s.load` and `accel_build`. Nothing is committed as data.

    python3 scripts/load_time.py [--triangles N] [--dir DIR] [--genpath target/release/genpath]
"""
import argparse
import json
import math
import os
import struct
import subprocess
import tempfile

parser = argparse.ArgumentParser()
parser.add_argument("--triangles", type=int, default=1_000_000)
parser.add_argument("--dir")
here = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..")
parser.add_argument("--genpath", default=os.path.join(here, "target", "release", "genpath"))
args = parser.parse_args()

side = math.ceil(math.sqrt(args.triangles / 2))  # cells per side; 2 triangles per cell
out = args.dir or tempfile.mkdtemp(prefix="genpath-load-")
ply = os.path.join(out, "grid.ply")
n = side + 1
with open(ply, "wb") as f:
    f.write(
        (
            "ply\nformat binary_little_endian 1.0\n"
            f"element vertex {n * n}\nproperty float x\nproperty float y\nproperty float z\n"
            f"element face {2 * side * side}\nproperty list uchar int vertex_indices\nend_header\n"
        ).encode()
    )
    row = bytearray()
    for j in range(n):
        row.clear()
        for i in range(n):
            x, y = 2 * i / side - 1, 2 * j / side - 1
            row += struct.pack("<fff", x, y, 0.05 * math.sin(9 * x) * math.cos(7 * y))
        f.write(row)
    tri = struct.Struct("<Biii")
    for j in range(side):
        buf = bytearray()
        for i in range(side):
            a = j * n + i
            buf += tri.pack(3, a, a + 1, a + n + 1)
            buf += tri.pack(3, a, a + n + 1, a + n)
        f.write(buf)
xml = os.path.join(out, "grid.xml")
with open(xml, "w") as f:
    f.write(
        """<scene version="3.0.0">
    <sensor type="perspective">
        <float name="fov" value="40"/>
        <transform name="to_world"><lookat origin="0, 0, 3" target="0, 0, 0" up="0, 1, 0"/></transform>
        <film type="hdrfilm"><integer name="width" value="16"/><integer name="height" value="16"/>
            <rfilter type="box"/></film>
    </sensor>
    <shape type="ply"><string name="filename" value="grid.ply"/><boolean name="face_normals" value="true"/></shape>
    <emitter type="constant"><rgb name="radiance" value="1"/></emitter>
</scene>
"""
    )
image = os.path.join(out, "grid.exr")
subprocess.run([args.genpath, "render", xml, "--method", "pt", "--spp", "1", "-o", image], check=True)
with open(image + ".json") as f:
    times = json.load(f)["times_s"]
print(f"{2 * side * side} triangles ({os.path.getsize(ply) / 1e6:.0f} MB PLY): "
      f"load {times['load']:.3f} s, accel_build {times['accel_build']:.3f} s")
