"""genpath's `pt` against Mitsuba 3 at equal samples on the Mitsuba XML test scenes: each
renderer's relMSE against the scene's committed Mitsuba reference (scenes/mitsuba/NAME.ref.exr),
at the agreement test's samples and size, over paired seeds. The table of the Mitsuba-XML
issue's target (genpath's relMSE at most 1.1 × Mitsuba's, no bad pixels); for people to rerun,
never run by the build, the tests or CI.

    pip install mitsuba==3.9.1; apt-get install libllvm19     # for llvm_ad_rgb
    cargo build --release
    python3 scripts/mitsuba_agreement.py [NAME ...] [--seeds 2-9] [--variant llvm_ad_rgb]
                                         [--threads 2] [--genpath PATH]

NAME is a scene with a reference (default: every scenes/mitsuba/*.ref.exr). Both renderers
read the same file with `$spp` (and `$res`, where the scene has it) set to the test's; both
images are measured by `genpath compare` against the reference (one metric for both). Prints
per scene the two relMSEs summed over the seeds, their ratio (genpath over Mitsuba: below 1,
genpath is less noisy), the range of the per-seed ratios and genpath's bad-pixel fraction.
"""
import argparse
import glob
import os
import re
import subprocess
import tempfile

import drjit as dr
import mitsuba as mi

here = os.path.dirname(os.path.abspath(__file__))
scenes = os.path.join(here, "..", "scenes", "mitsuba")
# The agreement tests' samples per pixel (tests/mitsuba.rs); 256 for the others.
TEST_SPP = {"textures": 64, "maps": 64, "mask": 64}

parser = argparse.ArgumentParser()
parser.add_argument("names", nargs="*")
parser.add_argument("--seeds", default="2-9", help="FIRST-LAST, inclusive")
parser.add_argument("--threads", type=int, default=2)
parser.add_argument("--variant", default="llvm_ad_rgb")
parser.add_argument("--genpath", default=os.path.join(here, "..", "target", "release", "genpath"))
args = parser.parse_args()
if not os.access(args.genpath, os.X_OK):
    parser.error(f"{args.genpath} is not an executable genpath (cargo build --release)")
first, last = (int(s) for s in args.seeds.split("-"))
seeds = range(first, last + 1)

mi.set_variant(args.variant)
dr.set_thread_count(args.threads)
names = args.names or [
    os.path.basename(p)[: -len(".ref.exr")]
    for p in sorted(glob.glob(os.path.join(scenes, "*.ref.exr")))
]


def compare(image, reference):
    """(relMSE, bad fraction) of `image` against `reference`, as `genpath compare` prints them."""
    out = subprocess.run([args.genpath, "compare", image, reference], check=True,
                         capture_output=True, text=True).stdout
    relmse = float(re.search(r"relMSE (\S+)", out).group(1))
    bad = float(re.search(r"bad pixels (\S+)%", out).group(1)) / 100
    return relmse, bad


print(f"seeds {first}-{last}, Mitsuba {mi.__version__} {args.variant}, {args.threads} threads")
print(f"{'scene':<12} {'spp':>4} {'genpath':>10} {'Mitsuba':>10} {'ratio':>6} {'per seed':>12} {'bad':>5}")
with tempfile.TemporaryDirectory() as tmp:
    for name in names:
        path = os.path.join(scenes, name + ".xml")
        reference = os.path.join(scenes, name + ".ref.exr")
        text = open(path).read()
        params = {"spp": TEST_SPP.get(name, 256)}
        if 'name="res"' in text:
            params["res"] = mi.Bitmap(reference).size()[0]
        scene = mi.load_file(path, **params)
        sums, ratios, worst_bad = [0.0, 0.0], [], 0.0
        for seed in seeds:
            ours = os.path.join(tmp, f"{name}-genpath-{seed}.exr")
            command = [args.genpath, "render", path, "--method", "pt", "--seed", str(seed),
                       "--threads", str(args.threads), "--quiet", "-o", ours]
            for key, value in params.items():
                command += ["-D", f"{key}={value}"]
            subprocess.run(command, check=True)
            theirs = os.path.join(tmp, f"{name}-mitsuba-{seed}.exr")
            mi.Bitmap(mi.render(scene, seed=seed)).write(theirs)
            (a, bad), (b, _) = compare(ours, reference), compare(theirs, reference)
            sums[0] += a
            sums[1] += b
            ratios.append(a / b)
            worst_bad = max(worst_bad, bad)
        print(f"{name:<12} {params['spp']:>4} {sums[0] / len(seeds):>10.3e} {sums[1] / len(seeds):>10.3e}"
              f" {sums[0] / sums[1]:>6.2f} {min(ratios):>5.2f}-{max(ratios):<5.2f} {worst_bad:>5.3f}",
              flush=True)
