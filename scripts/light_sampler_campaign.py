#!/usr/bin/env python3
"""`pt` with `--light-sampler uniform` against `bvh` at equal samples on every scene that ships.

    python3 scripts/light_sampler_campaign.py GENPATH OUTDIR [--spp N] [--seeds K] [--method M] [SCENE...]

For each scene, both light samplers render (with `pt`, or method M) seeds 1..K at N samples per pixel (TOML scenes at
128×128, Mitsuba scenes at their own size); relMSE is taken against the scene's `.ref.exr`
where it has one, else against a reference rendered once by `pt` with uniform picking at 32 × N
samples with seed 1000 (written to OUTDIR, reused). Prints a Markdown table: per scene the mean
relMSE of each sampler, their ratio (bvh / uniform, ratio of the means over the paired seeds)
and its bootstrap 95 % upper bound (10 000 resamples of the seeds, fixed random seed), and the
mean whole-process seconds of each. An image already in OUTDIR is reused (with the seconds
its render took, kept beside it), so that more seeds can be added to a run.
"""
import glob
import json
import os
import random
import subprocess
import sys
import time

args = sys.argv[1:]
if len(args) < 2:
    sys.exit(__doc__)
genpath, out = args[0], args[1]
spp, seeds, method, scenes = 32, 6, "pt", []
rest = args[2:]
while rest:
    a = rest.pop(0)
    if a == "--spp":
        spp = int(rest.pop(0))
    elif a == "--seeds":
        seeds = int(rest.pop(0))
    elif a == "--method":
        method = rest.pop(0)
    else:
        scenes.append(a)
if not scenes:
    scenes = sorted(glob.glob("scenes/*/scene.toml")) + sorted(
        f for f in glob.glob("scenes/*/*.xml") if os.path.exists(f[:-4] + ".ref.exr"))
os.makedirs(out, exist_ok=True)


def render(scene, sampler, seed, n, path, method="pt"):
    if os.path.exists(path + ".wall"):
        with open(path + ".wall") as f:
            return float(f.read())
    size = [] if scene.endswith(".xml") else ["--width", "128", "--height", "128"]
    cmd = [genpath, "render", scene, "--method", method, "--spp", str(n), "--seed", str(seed),
           "--light-sampler", sampler, "-q", "-o", path] + size
    t = time.time()
    subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL)
    wall = time.time() - t
    with open(path + ".wall", "w") as f:
        f.write(f"{wall}\n")
    return wall


def relmse(image, ref):
    r = subprocess.run([genpath, "compare", image, ref], check=True, capture_output=True, text=True)
    return float(r.stdout.split()[1])


def bound(pairs):
    rng = random.Random(7)
    ratios = []
    for _ in range(10000):
        s = [rng.choice(pairs) for _ in pairs]
        ratios.append(sum(b for _, b in s) / sum(u for u, _ in s))
    ratios.sort()
    return ratios[int(0.95 * len(ratios))]


print(f"`{method}`, {spp} spp, seeds 1–{seeds}\n")
print(f"| scene | uniform relMSE | bvh relMSE | bvh / uniform | 95 % bound | s uniform | s bvh |")
print("| --- | --- | --- | --- | --- | --- | --- |")
for scene in scenes:
    name = scene.replace("scenes/", "").replace("/scene.toml", "").replace(".xml", "")
    tag = name.replace("/", "-")
    ref = scene[:-4] + ".ref.exr" if scene.endswith(".xml") else f"{out}/{tag}.ref.exr"
    if not os.path.exists(ref):
        render(scene, "uniform", 1000, 32 * spp, ref)
    pairs, secs = [], {"uniform": 0.0, "bvh": 0.0}
    for seed in range(1, seeds + 1):
        e = {}
        for sampler in ("uniform", "bvh"):
            img = f"{out}/{tag}-{method}-{sampler}-{seed}.exr"
            secs[sampler] += render(scene, sampler, seed, spp, img, method) / seeds
            e[sampler] = relmse(img, ref)
        pairs.append((e["uniform"], e["bvh"]))
    mu = sum(u for u, _ in pairs) / seeds
    mb = sum(b for _, b in pairs) / seeds
    print(f"| {name} | {mu:.4g} | {mb:.4g} | {mb / mu:.3f} | {bound(pairs):.3f} | "
          f"{secs['uniform']:.2f} | {secs['bvh']:.2f} |", flush=True)
