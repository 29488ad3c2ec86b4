"""Mitsuba 3's light tracer (`ptracer`) on Mitsuba XML test scenes, the references of
tests/lt.rs's agreement of genpath's `lt` with Mitsuba's. Run by hand, never by the build or CI
(pip install mitsuba==3.9.1; apt-get install libllvm19):

    python3 scripts/mitsuba_ptracer_references.py [NAME ...] [--spp N] [--res N]

Writes scenes/mitsuba/<name>.ptracer.exr (float32 RGB) for each named scene (default: box and
lights), rendered with the llvm_ad_rgb variant by `ptracer` with the scene's own `max_depth`
(its `path` integrator's; `hide_emitters` as the scene says), in passes of 256 spp (seeds
1000 + pass) averaged, at 16384 spp (64 × the test's 256) and 32 × 32 pixels (the test's
size). Beside it, <name>.ptracer.json: per 8 × 8 block and channel (blocks row by row, r, g,
b), the variance of the reference's block mean estimated from the spread of its passes (a
light tracer's noise differs from genpath's where the camera sees a light: Mitsuba samples
the visible emitters, genpath takes them along camera rays). Prints each render's time.
"""
import json
import argparse
import os
import re
import time

import mitsuba as mi
import numpy as np

BLOCK = 8

parser = argparse.ArgumentParser()
parser.add_argument("names", nargs="*", default=["box", "lights"])
parser.add_argument("--spp", type=int, default=16384)
parser.add_argument("--res", type=int, default=32)
args = parser.parse_args()
mi.set_variant("llvm_ad_rgb")
here = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "scenes", "mitsuba")

for name in args.names:
    path = os.path.join(here, name + ".xml")
    text = open(path).read()
    depth = int(re.search(r'name="max_depth" value="(-?\d+)"', text).group(1))
    hide = re.search(r'name="hide_emitters" value="true"', text) is not None
    start = time.time()
    per_pass = min(args.spp, 256)
    scene = mi.load_file(path, spp=per_pass, res=args.res)
    integrator = mi.load_dict({"type": "ptracer", "max_depth": depth, "hide_emitters": hide})
    passes = args.spp // per_pass
    image = None
    blocks = []
    for i in range(passes):
        img = mi.render(scene, integrator=integrator, seed=1000 + i)
        image = img if image is None else image + img
        a = np.array(img)[:, :, :3]
        b = a.reshape(args.res // BLOCK, BLOCK, args.res // BLOCK, BLOCK, 3).mean(axis=(1, 3))
        blocks.append(b.reshape(-1))
    image = image / passes
    blocks = np.array(blocks)
    variance = blocks.var(axis=0, ddof=1) / passes
    with open(path[:-4] + ".ptracer.json", "w") as f:
        json.dump({"spp": args.spp, "passes": passes, "block": BLOCK, "block_variance": variance.tolist()}, f)
    out = path[:-4] + ".ptracer.exr"
    mi.Bitmap(image).convert(mi.Bitmap.PixelFormat.RGB, mi.Struct.Type.Float32, False).write(out)
    print(f"{name}.xml: ptracer, max_depth {depth}, {args.spp} spp at {args.res}², in {time.time() - start:.1f} s -> {out}")
