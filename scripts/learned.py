#!/usr/bin/env python3
"""What the GA learned, from the JSON that `genpath render --method ga-pt` (or `ga`) writes.

    python3 scripts/learned.py IMAGE.exr.json...

Prints a Markdown table, a row per render: its GA pixels and how many improved on `srt`;
the mean share of the evolved mixtures' weight (over the GA pixels) on the defensive `srt`
generator and the other BRDF-led ones, on anchor cones and on patches (each generator counted
by its first step's sampler: the guide's first vertex); the median (and range) over the GA
pixels of `V_srt / V_best`, the variance of `srt` over the evolved mixture's on the pixel's
test paths (1: nothing learned); the median number of test paths carrying light; and the
spatial guide's training trial of the GA's guides (ratio of the guided arm's relative
variance times cost over the spatial guide's alone; above 1.15 the guides are dropped).
"""
import json
import os
import statistics
import sys


def first_sampler(generator):
    kind = generator["steps"][0]["sampler"]["type"] if generator["steps"] else "brdf"
    return {"brdf": "brdf", "anchor": "anchor", "patch": "patch"}.get(kind, "brdf")


def row(path):
    with open(path) as f:
        d = json.load(f)
    pixels = d["ga"]["pixels"]
    if not pixels:
        return None
    shares = {"brdf": [], "anchor": [], "patch": []}
    ratios = []
    for p in pixels:
        mixture = p["mixture"]
        share = dict.fromkeys(shares, 0.0)
        for w, g in zip(mixture["weights"], mixture["generators"]):
            share[first_sampler(g)] += w
        for k, v in share.items():
            shares[k].append(v)
        if p["v_best"] > 0:
            ratios.append(p["v_srt"] / p["v_best"])
    improved = sum(not p["kept_srt"] for p in pixels)
    light = statistics.median(p["light_paths"] for p in pixels)
    trial = (d.get("spatial") or {}).get("guides_trial")
    trial_text = "–"
    if trial:
        outcome = "kept" if trial["kept"] else "dropped"
        trial_text = f"{trial['ratio']:.2f} at pass {trial['pass']}: {outcome}"
    scene = os.path.basename(path).split(".")[0]
    mean = lambda xs: sum(xs) / len(xs)
    ratio_text = "–"
    if ratios:
        ratio_text = (
            f"{statistics.median(ratios):.2f} [{min(ratios):.2f}–{max(ratios):.2f}]"
        )
    return (
        f"| {scene} | {len(pixels)} | {improved} | {mean(shares['brdf']):.2f} | "
        f"{mean(shares['anchor']):.2f} | {mean(shares['patch']):.2f} | {ratio_text} | "
        f"{light:.0f} | {trial_text} |"
    )


def main(paths):
    if not paths:
        sys.exit(__doc__)
    print(
        "| render | GA pixels | improved on `srt` | weight: BRDF | anchors | patches | "
        "`V_srt / V_best` median [range] | light paths (median) | training trial |"
    )
    print("| --- | --- | --- | --- | --- | --- | --- | --- | --- |")
    for path in paths:
        r = row(path)
        if r:
            print(r)


if __name__ == "__main__":
    main(sys.argv[1:])
