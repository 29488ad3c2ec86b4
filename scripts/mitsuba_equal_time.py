"""Mitsuba 3's path tracer at equal time on a Mitsuba XML scene, to read beside
`genpath sweep --time` on the same file: for each budget in seconds, Mitsuba renders as many
samples per pixel as fit (its time per sample and per render call calibrated by two warm
renders), and this prints
its seconds, relMSE against the reference (by `genpath compare`, genpath's own definition)
and efficiency 1 / (relMSE × seconds), the columns `sweep` writes. A tool for people, never
run by the build, the tests or CI.

    pip install mitsuba==3.9.1 numpy; apt-get install libllvm19   # for llvm_ad_rgb (numpy: reading its pixels back)
    cargo build --release
    python3 scripts/mitsuba_equal_time.py scenes/mitsuba/sunroom.xml \
        --ref reports/refs/sunroom_ref.exr --budgets 2,8 [--seeds 401,402] [--threads 2] [--res N]

Mitsuba's seconds are its render call until the pixels are read back, warm (an untimed
render at the same samples compiles its kernels first); genpath's in `sweep` count the
whole render, its learning included. Both at the scene's own size.
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
parser.add_argument("scene")
parser.add_argument("--ref", required=True)
parser.add_argument("--budgets", default="2,8")
parser.add_argument("--seeds", default="401")
parser.add_argument("--threads", type=int, default=2)
parser.add_argument("--variant", default="llvm_ad_rgb")
parser.add_argument("--res", type=int, help="the scene's $res, where it has one")
parser.add_argument("--calibrate", type=int, default=16, help="samples of the timing render")
parser.add_argument("--genpath", default=os.path.join(here, "..", "target", "release", "genpath"))
args = parser.parse_args()
if not os.access(args.genpath, os.X_OK):
    parser.error(f"{args.genpath} is not an executable genpath (cargo build --release)")
mi.set_variant(args.variant)
dr.set_thread_count(args.threads)


def timed_render(spp, seed):
    """Mitsuba's image at `spp` and its seconds, warm."""
    params = {"spp": spp}
    if args.res is not None:
        params["res"] = args.res
    scene = mi.load_file(args.scene, **params)
    mi.render(scene, seed=seed + 7919).numpy()  # compiles the kernels
    start = time.perf_counter()
    image = mi.render(scene, seed=seed)
    image.numpy()  # waits for every kernel
    return image, time.perf_counter() - start


def relmse(image, tmp):
    out = os.path.join(tmp, "mitsuba.exr")
    mi.Bitmap(image).convert(mi.Bitmap.PixelFormat.RGB, mi.Struct.Type.Float32, False).write(out)
    text = subprocess.run([args.genpath, "compare", out, args.ref], check=True,
                          capture_output=True, text=True).stdout
    return float(re.search(r"relMSE (\S+)", text).group(1))


# Two timings give the time per sample and the render call's fixed cost (which one timing at
# few samples would count as samples' time, leaving short budgets unfilled).
_, short = timed_render(args.calibrate, 1)
_, long = timed_render(4 * args.calibrate, 1)
per_sample = max((long - short) / (3 * args.calibrate), 1e-9)
fixed = max(short - per_sample * args.calibrate, 0.0)
print(f"Mitsuba {mi.__version__} {args.variant}, {args.threads} threads: "
      f"{per_sample * 1e3:.2f} ms per sample per pixel, {fixed * 1e3:.0f} ms per render call")
print("| budget | seed | spp | seconds | relMSE | efficiency |")
print("|---|---|---|---|---|---|")
with tempfile.TemporaryDirectory() as tmp:
    for budget in [float(b) for b in args.budgets.split(",")]:
        for seed in [int(s) for s in args.seeds.split(",")]:
            spp = max(1, int((budget - fixed) / per_sample))
            image, seconds = timed_render(spp, seed)
            r = relmse(image, tmp)
            print(f"| {budget:g} | {seed} | {spp} | {seconds:.2f} | {r:.4e} | {1 / (r * seconds):.4f} |")
