"""genpath's `lt` against Mitsuba 3's light tracer (`ptracer`) at equal samples per pixel on
Mitsuba XML scenes: for each scene, both render SPP samples per pixel; printed are each one's
seconds, relMSE against the scene's reference (by `genpath compare`, genpath's own
definition) and efficiency 1 / (relMSE × seconds). A tool for people, never run by the build,
the tests or CI.

    pip install mitsuba==3.9.1; apt-get install libllvm19
    python3 scripts/lt_vs_ptracer.py scenes/transport/lamp_in_glass.xml ... [--spp 64]
        [--seeds 401,402] [--genpath target/release/genpath]

genpath's seconds are the whole process (`genpath render`: loading, building the
accelerator, rendering, writing); Mitsuba's are its warm render call (an untimed render at
the same samples compiles its kernels first) until the pixels are read back: what issue 51
item 5 asks. The reference is SCENE with `.ref.exr` for `.xml`. Both on all cores by default.
"""
import argparse
import os
import re
import subprocess
import tempfile
import time

import drjit as dr
import mitsuba as mi

here = os.path.dirname(os.path.abspath(__file__))
parser = argparse.ArgumentParser()
parser.add_argument("scenes", nargs="+")
parser.add_argument("--spp", type=int, default=64)
parser.add_argument("--seeds", default="401")
parser.add_argument("--variant", default="llvm_ad_rgb")
parser.add_argument("--genpath", default=os.path.join(here, "..", "target", "release", "genpath"))
args = parser.parse_args()
mi.set_variant(args.variant)


def relmse(image, reference):
    out = subprocess.run([args.genpath, "compare", image, reference], capture_output=True, text=True, check=True)
    return float(re.search(r"relMSE (\S+)", out.stdout).group(1))


print("| scene | seed | method | spp | seconds | relMSE | efficiency |")
print("| --- | ---: | --- | ---: | ---: | ---: | ---: |")
with tempfile.TemporaryDirectory() as tmp:
    for scene_path in args.scenes:
        name = os.path.basename(scene_path)[:-4]
        reference = scene_path[:-4] + ".ref.exr"
        depth = int(re.search(r'name="max_depth" value="(-?\d+)"', open(scene_path).read()).group(1))
        scene = mi.load_file(scene_path, spp=args.spp)
        integrator = mi.load_dict({"type": "ptracer", "max_depth": depth})
        mi.render(scene, integrator=integrator, seed=1)  # compiles the kernels
        for seed in map(int, args.seeds.split(",")):
            start = time.perf_counter()
            image = mi.render(scene, integrator=integrator, seed=seed)
            dr.eval(image)
            array = image.numpy()
            seconds = time.perf_counter() - start
            out = os.path.join(tmp, f"{name}-mi.exr")
            mi.Bitmap(array).convert(mi.Bitmap.PixelFormat.RGB, mi.Struct.Type.Float32, False).write(out)
            r = relmse(out, reference)
            print(f"| {name} | {seed} | Mitsuba `ptracer` | {args.spp} | {seconds:.2f} | {r:.4g} | {1 / (r * seconds):.3g} |")
            out = os.path.join(tmp, f"{name}-lt.exr")
            start = time.perf_counter()
            subprocess.run([args.genpath, "render", scene_path, "--method", "lt", "--spp", str(args.spp),
                            "--seed", str(seed), "--quiet", "-o", out], check=True)
            seconds = time.perf_counter() - start
            r = relmse(out, reference)
            print(f"| {name} | {seed} | genpath `lt` | {args.spp} | {seconds:.2f} | {r:.4g} | {1 / (r * seconds):.3g} |")
