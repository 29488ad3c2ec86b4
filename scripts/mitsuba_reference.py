"""Renders the Mitsuba references of the XML agreement test (tests/mitsuba.rs) with Mitsuba 3
itself. Run by hand, never by the build or CI:

    pip install mitsuba==3.9.1
    python3 scripts/mitsuba_reference.py [SPP] [RES]    # defaults 16384 spp (64 × the test's), 64²

Writes scenes/mitsuba/<name>.ref.exr (float32 RGB) for every scenes/mitsuba/*.xml, rendered
with the `scalar_rgb` variant (the box filter and independent sampler the scenes name), and
prints each render's time.
"""
import glob
import os
import sys
import time

import mitsuba as mi

mi.set_variant("scalar_rgb")
spp = int(sys.argv[1]) if len(sys.argv) > 1 else 16384
res = int(sys.argv[2]) if len(sys.argv) > 2 else 64
here = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "scenes", "mitsuba")
for path in sorted(glob.glob(os.path.join(here, "*.xml"))):
    scene = mi.load_file(path, spp=spp, res=res)
    start = time.time()
    image = mi.render(scene, seed=1)
    seconds = time.time() - start
    out = path[:-4] + ".ref.exr"
    mi.Bitmap(image).convert(mi.Bitmap.PixelFormat.RGB, mi.Struct.Type.Float32, False).write(out)
    print(f"{os.path.basename(path)}: {spp} spp at {res}² in {seconds:.1f} s -> {out}")
