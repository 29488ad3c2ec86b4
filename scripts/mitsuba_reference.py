"""Renders the Mitsuba references of the XML agreement tests (tests/mitsuba.rs) with Mitsuba 3
itself. Run by hand, never by the build or CI:

    pip install mitsuba==3.9.1
    python3 scripts/mitsuba_reference.py [NAME ...] [--spp N] [--res N] [--seed S] [--out FILE]

Writes scenes/mitsuba/<name>.ref.exr (float32 RGB) for each named scene (default: every
scenes/mitsuba/*.xml with a sensor), rendered with the `scalar_rgb` variant (the box filter and independent
sampler the scenes name) at the scene's reference samples and size: 64 × its test's samples
(box, smooth, rough, roughglass and plastic: 16384 spp at 64², glass, env, spheres, lights and spot: 16384 spp at 128², legacy and params:
16384 spp at their own 64 × 48; the tests' 256 spp). --spp, --res and --seed (default 1) override them, and --out (one scene) writes elsewhere:
e.g. Mitsuba's own render at the test's samples, to compare genpath's error with, or
sunroom.xml's reference for the GA's reports (reports/refs/sunroom_ref.exr: its .json says
how it was made).
--variant llvm_ad_rgb (with `apt-get install libllvm19`) is much faster; it renders in
passes of at most 256 spp (seeds seed·1000 + pass) and averages them, to bound its memory.
Prints each render's time.
"""
import argparse
import glob
import os
import time

import mitsuba as mi

# (spp, res) of each scene's reference: 64 × its test's samples, at the test's size.
REFERENCES = {
    "box": (16384, 64),
    "glass": (16384, 128),
    "env": (16384, 128),
    "spheres": (16384, 128),
    "lights": (16384, 128),
    "spot": (16384, 128),
    "smooth": (16384, 64),
    "rough": (16384, 64),
    "roughglass": (16384, 64),
    "plastic": (16384, 64),
    # 4096 spp: 16 × its test's samples (the reference's own variance enters the test).
    "textures": (4096, 64),
    "maps": (4096, 64),
    # 1024 × its test's samples: Mitsuba's `path` meets masks with opaque shadow rays and
    # is far noisier there than genpath's `pt` (see docs/scenes.md).
    "mask": (65536, 64),
    # 64 × 48, fixed in the files (their film is not square: no `res` parameter).
    "legacy": (16384, None),
    "params": (16384, None),
}

parser = argparse.ArgumentParser()
parser.add_argument("names", nargs="*")
parser.add_argument("--spp", type=int)
parser.add_argument("--res", type=int)
parser.add_argument("--seed", type=int, default=1)
parser.add_argument("--out")
parser.add_argument("--variant", default="scalar_rgb")
args = parser.parse_args()

mi.set_variant(args.variant)
here = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "scenes", "mitsuba")
# Every scene with a sensor (not legacy_room.xml, which legacy.xml includes).
names = args.names or [
    os.path.basename(p)[:-4]
    for p in sorted(glob.glob(os.path.join(here, "*.xml")))
    if "<sensor" in open(p).read()
]
if args.out and len(names) != 1:
    parser.error("--out takes one scene")
for name in names:
    path = os.path.join(here, name + ".xml")
    spp, res = REFERENCES.get(name, (16384, 64))
    spp, res = args.spp or spp, args.res or res
    start = time.time()
    size = {} if res is None else {"res": res}
    if args.variant.startswith("scalar"):
        scene = mi.load_file(path, spp=spp, **size)
        image = mi.render(scene, seed=args.seed)
    else:
        per_pass = min(spp, 256)
        if spp % per_pass:
            parser.error(f"{spp} spp is not a multiple of {per_pass}")
        scene = mi.load_file(path, spp=per_pass, **size)
        passes = spp // per_pass
        image = None
        for i in range(passes):
            img = mi.render(scene, seed=args.seed * 1000 + i)
            image = img if image is None else image + img
        image = image / passes
    seconds = time.time() - start
    out = args.out or path[:-4] + ".ref.exr"
    mi.Bitmap(image).convert(mi.Bitmap.PixelFormat.RGB, mi.Struct.Type.Float32, False).write(out)
    size = f"{res}²" if res else "its own size"
    print(f"{name}.xml: {spp} spp at {size}, seed {args.seed}, in {seconds:.1f} s -> {out}")
