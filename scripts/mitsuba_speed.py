"""Times genpath's `pt` against Mitsuba 3 on the same Mitsuba XML scenes, in one run: the
benchmark of the speed issue, for people to rerun (never run by the build, the tests or CI).

    pip install mitsuba==3.9.1 numpy; apt-get install libllvm19   # for llvm_ad_rgb (numpy: reading its pixels back)
    cargo build --release
    python3 scripts/mitsuba_speed.py [NAME ...] [--spp 256] [--res 128] [--threads 2]
                                     [--runs 5] [--variant llvm_ad_rgb] [--genpath PATH]

NAME is a scene of scenes/mitsuba (default: every one with a sensor). Both renderers read the
same file with `$spp` (and `$res`, where the scene has it) set alike. Mitsuba: the render
call until its pixels are read back, warm (one untimed render first compiles its kernels),
the median of --runs. genpath:
the whole process, `genpath render NAME.xml --method pt --threads T` (loading, BVH build,
rendering and writing the EXR), the median of --runs. Prints both and their ratio (genpath
over Mitsuba: below 1, genpath is faster).
"""
import argparse
import glob
import os
import statistics
import subprocess
import tempfile
import time

import drjit as dr
import mitsuba as mi

here = os.path.dirname(os.path.abspath(__file__))
scenes = os.path.join(here, "..", "scenes", "mitsuba")
parser = argparse.ArgumentParser()
parser.add_argument("names", nargs="*")
parser.add_argument("--spp", type=int, default=256)
parser.add_argument("--res", type=int, default=128)
parser.add_argument("--threads", type=int, default=2)
parser.add_argument("--runs", type=int, default=5)
parser.add_argument("--variant", default="llvm_ad_rgb")
parser.add_argument("--genpath", default=os.path.join(here, "..", "target", "release", "genpath"))
args = parser.parse_args()
if not os.access(args.genpath, os.X_OK):
    parser.error(f"{args.genpath} is not an executable genpath (cargo build --release)")

mi.set_variant(args.variant)
dr.set_thread_count(args.threads)
names = args.names or [
    os.path.basename(p)[:-4]
    for p in sorted(glob.glob(os.path.join(scenes, "*.xml")))
    if "<sensor" in open(p).read()
]


def median_seconds(run):
    times = []
    for _ in range(args.runs):
        start = time.perf_counter()
        run()
        times.append(time.perf_counter() - start)
    return statistics.median(times)


print(f"{args.spp} spp, {args.threads} threads, median of {args.runs}; Mitsuba {mi.__version__} {args.variant}")
print(f"{'scene':<14} {'genpath s':>10} {'Mitsuba s':>10} {'ratio':>7}")
with tempfile.TemporaryDirectory() as tmp:
    for name in names:
        path = os.path.join(scenes, name + ".xml")
        # Only the parameters the scene declares: Mitsuba refuses others.
        text = open(path).read()
        params = {"spp": args.spp}
        if 'name="res"' in text:
            params["res"] = args.res
        scene = mi.load_file(path, **params)
        mi.render(scene, seed=0)  # compiles the kernels
        def mitsuba_render():
            # Reading the pixels waits for every kernel: dr.eval and dr.sync_thread alone
            # returned after about half the work here (box.xml, 256 spp: 1.0 s against 2.2 s).
            mi.render(scene, seed=1).numpy()

        mitsuba_s = median_seconds(mitsuba_render)
        command = [args.genpath, "render", path, "--method", "pt", "--threads", str(args.threads),
                   "--quiet", "-o", os.path.join(tmp, name + ".exr")]
        for key, value in params.items():
            command += ["-D", f"{key}={value}"]
        genpath_s = median_seconds(lambda: subprocess.run(command, check=True))
        print(f"{name:<14} {genpath_s:>10.3f} {mitsuba_s:>10.3f} {genpath_s / mitsuba_s:>7.2f}")
