#!/usr/bin/env python3
"""Sums a `perf report` of genpath by phase of the path tracer.

    perf record -F 4000 -g -o pt.data target/release/genpath render scenes/cbox/scene.toml \\
        --method pt --spp 256 --max-bounces 5 -o /tmp/pt.exr --quiet
    perf report -i pt.data --no-children --sort dso,symbol --stdio | python3 scripts/profile_phases.py

Each self-time line (`PCT% DSO [.] SYMBOL`) goes to the first phase whose test it passes;
prints a Markdown table of the phases' shares. Debian's libembree3 has no symbols: its time
is one phase, the traversal.
"""
import re
import sys

PHASES = [
    ("Embree traversal (libembree3)", lambda dso, sym: "embree" in dso),
    ("Embree calls (our intersect/occluded wrappers)", lambda dso, sym: "EmbreeAccel" in sym),
    ("BSDF eval, pdf and sampling", lambda dso, sym: "bsdf::" in sym or "VertexBsdf" in sym or "specular" in sym),
    ("light sampling and next-event estimation", lambda dso, sym: any(
        k in sym for k in ("LightPoint", "sample_seen_from", "LightCandidate", "next_event", "Emitters", "pick_light"))),
    ("the path loop (MIS weights, Russian roulette, inlined)", lambda dso, sym: any(
        k in sym for k in ("radiance_guided", "emission_weight", "scatters"))),
    ("libm (sincos, powf)", lambda dso, sym: "libm" in dso),
    ("camera rays", lambda dso, sym: "Camera" in sym),
    ("surface points (hit to shading frame)", lambda dso, sym: "surface_point" in sym or "shading" in sym),
    ("tiles, random streams, closures", lambda dso, sym: any(
        k in sym for k in ("render_tile", "call_mut", "sample_rng", "Rng"))),
    ("other", lambda dso, sym: True),
]


def main():
    shares = {name: 0.0 for name, _ in PHASES}
    for line in sys.stdin:
        m = re.match(r"\s+([0-9.]+)%\s+(\S+)\s+\[.\]\s+(.*)", line)
        if not m:
            continue
        pct, dso, sym = float(m.group(1)), m.group(2), m.group(3)
        for name, test in PHASES:
            if test(dso, sym):
                shares[name] += pct
                break
    print("| phase | share of samples |")
    print("| --- | --- |")
    for name, _ in PHASES:
        print(f"| {name} | {shares[name]:.1f} % |")


if __name__ == "__main__":
    main()
