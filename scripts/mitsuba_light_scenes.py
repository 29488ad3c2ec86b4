"""Mitsuba 3 renders of the light-sampling test scenes (scenes/lights/*.xml), by hand, never
by the build or CI (pip install mitsuba==3.9.1; apt-get install libllvm19):

    python3 scripts/mitsuba_light_scenes.py [--ref-spp 16384] [--spp 64] [--seeds 6]

Writes scenes/lights/<name>.ref.exr (llvm_ad_rgb, passes of 256 spp with seeds 1000 + pass,
averaged) and /tmp/mitsuba-lights/<name>-<spp>spp-s<seed>.exr (Mitsuba's own renders at the
test's samples, seeds 1..N, for the relMSE comparison at equal samples); prints times.
"""
import argparse
import os
import time

import mitsuba as mi
import numpy as np

parser = argparse.ArgumentParser()
parser.add_argument("names", nargs="*", default=["dome", "many"])
parser.add_argument("--ref-spp", type=int, default=16384)
parser.add_argument("--spp", type=int, default=64)
parser.add_argument("--seeds", type=int, default=6)
parser.add_argument("--res", type=int, default=128)
args = parser.parse_args()
mi.set_variant("llvm_ad_rgb")
here = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "scenes", "lights")
out = "/tmp/mitsuba-lights"
os.makedirs(out, exist_ok=True)
for name in args.names:
    path = os.path.join(here, name + ".xml")
    if args.ref_spp:
        start = time.time()
        scene = mi.load_file(path, spp=256, res=args.res)
        acc = None
        passes = args.ref_spp // 256
        for k in range(passes):
            img = np.array(mi.render(scene, seed=1000 + k))
            acc = img if acc is None else acc + img
        mi.Bitmap(acc / passes).write(os.path.join(here, name + ".ref.exr"))
        print(f"{name}: reference {args.ref_spp} spp in {time.time() - start:.1f} s")
    scene = mi.load_file(path, spp=args.spp, res=args.res)
    for seed in range(1, args.seeds + 1):
        start = time.time()
        img = mi.render(scene, seed=seed)
        np.array(img)
        mi.Bitmap(img).write(os.path.join(out, f"{name}-{args.spp}spp-s{seed}.exr"))
        print(f"{name}: {args.spp} spp seed {seed} in {time.time() - start:.2f} s")
