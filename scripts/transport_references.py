"""Mitsuba 3 references of the light-transport test scenes (scenes/transport/*.xml), by hand,
never by the build or CI (pip install mitsuba==3.9.1; apt-get install libllvm19):

    python3 scripts/transport_references.py [names...] [--spp N] [--method path|ptracer|auto]
    python3 scripts/transport_references.py --preview [names...]   # 64 spp of both, PNGs in /tmp

Renders scenes/transport/<name>.ref.exr with the llvm_ad_rgb variant in passes of 256 spp
(seeds 1000 + pass) averaged, as scripts/mitsuba_light_scenes.py does, with the integrator and
spp of the table below (`path`: the scene's own integrator; `ptracer`: Mitsuba's light tracer
with the scene's max_depth). Mitsuba's light tracer cannot see through a delta BSDF seen
directly by the camera, so for a scene with smooth glass (caustic) `ptracer` is used only where
no primary ray of the pixel meets a delta BSDF (64 jittered primary rays per pixel tell) and
`path` everywhere else, each with the same number of passes ("composite").
Noise: the passes are split into two halves (even and odd passes); the script prints the
relMSE (genpath's: per channel (a - r)^2 / (r^2 + 0.01), averaged) between the halves, the
reference being their average; halves/2 is one half's expected relMSE against the truth and
halves/4 the whole reference's. Writes the halves to /tmp/transport-ref/<name>-{a,b}.exr.
"""
import argparse
import os
import time

import mitsuba as mi
import numpy as np

# name: (method, spp)
PLAN = {
    "lamp_in_glass": ("ptracer", 12288),
    "caustic": ("composite", 24576),
    "frosted_window": ("ptracer", 24576),
    "plate": ("ptracer", 24576),
    "dark_window": ("path", 8192),
    "pinhole": ("path", 16384),
    "mixed": ("path", 6144),
}

parser = argparse.ArgumentParser()
parser.add_argument("names", nargs="*", default=list(PLAN))
parser.add_argument("--spp", type=int, default=0, help="override the table's spp")
parser.add_argument("--method", default="", help="override the table's method")
parser.add_argument("--res", type=int, default=128)
parser.add_argument("--preview", action="store_true")
parser.add_argument("--out", default="")
args = parser.parse_args()
mi.set_variant("llvm_ad_rgb")
here = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "scenes", "transport")
tmp = "/tmp/transport-ref"
os.makedirs(tmp, exist_ok=True)


def depth_of(path):
    import re
    text = open(path).read()
    return int(re.search(r'name="max_depth" value="(\d+)"', text).group(1))


def delta_fraction(scene, res, n=64):
    """Per pixel, the fraction of n jittered primary rays whose first hit has a delta lobe."""
    sensor = scene.sensors()[0]
    rng = np.random.default_rng(7)
    ys, xs = np.mgrid[0:res, 0:res]
    xs = np.repeat(xs.ravel(), n).astype(np.float64)
    ys = np.repeat(ys.ravel(), n).astype(np.float64)
    px = (xs + rng.random(xs.size)) / res
    py = (ys + rng.random(ys.size)) / res
    ray, _ = sensor.sample_ray(0.0, 0.5, mi.Point2f(px, py), mi.Point2f(0.5, 0.5))
    si = scene.ray_intersect(ray)
    flags = si.bsdf().flags()
    has = mi.has_flag(flags, mi.BSDFFlags.Delta) & si.is_valid()
    return np.array(has, dtype=np.float64).reshape(res, res, n).mean(axis=2)


def render_passes(scene, integrator, passes, seed0=1000):
    a = b = None
    for k in range(passes):
        img = np.array(mi.render(scene, seed=seed0 + k, integrator=integrator), dtype=np.float64)
        if k % 2 == 0:
            a = img if a is None else a + img
        else:
            b = img if b is None else b + img
    na, nb = (passes + 1) // 2, passes // 2
    return a / na, (b / nb if nb else None)


for name in args.names:
    path = os.path.join(here, name + ".xml")
    method, spp = PLAN[name]
    method = args.method or method
    spp = args.spp or spp
    depth = depth_of(path)
    ptracer = mi.load_dict({"type": "ptracer", "max_depth": depth})
    if args.preview:
        scene = mi.load_file(path, spp=64, res=args.res)
        for m, integ in [("path", None), ("ptracer", ptracer)]:
            t = time.time()
            img = np.array(mi.render(scene, seed=1, integrator=integ))
            dt = time.time() - t
            mi.util.write_bitmap(os.path.join(tmp, f"{name}-{m}-64.png"), img)
            mi.Bitmap(img).write(os.path.join(tmp, f"{name}-{m}-64.exr"))
            print(f"{name} {m} 64 spp {dt:.1f} s mean {img.mean():.3f}")
        continue
    start = time.time()
    scene = mi.load_file(path, spp=256, res=args.res)
    passes = spp // 256
    if method == "composite":
        frac = delta_fraction(scene, args.res)[..., None]
        pa, pb = render_passes(scene, None, passes)
        la, lb = render_passes(scene, ptracer, passes)
        use_path = frac > 0
        ha, hb = np.where(use_path, pa, la), np.where(use_path, pb, lb)
        print(f"{name}: {int(use_path.sum())} of {args.res ** 2} pixels from path")
    else:
        ha, hb = render_passes(scene, ptracer if method == "ptracer" else None, passes)
    ref = (ha + hb) / 2
    secs = time.time() - start
    out = args.out or os.path.join(here, name + ".ref.exr")
    mi.Bitmap(ref.astype(np.float32)).write(out)
    mi.Bitmap(ha.astype(np.float32)).write(os.path.join(tmp, f"{name}-a.exr"))
    mi.Bitmap(hb.astype(np.float32)).write(os.path.join(tmp, f"{name}-b.exr"))
    mi.util.write_bitmap(os.path.join(tmp, f"{name}-ref.png"), ref.astype(np.float32))
    h = float(np.mean((ha - hb) ** 2 / (ref * ref + 0.01)))  # half a against half b
    print(f"{name}: {method} {spp} spp in {secs:.1f} s; mean {ref.mean():.4f}; "
          f"relMSE(halves) {h:.3e}, one half {h / 2:.3e}, reference {h / 4:.3e}")
