#!/usr/bin/env python3
"""Ratios of relMSE at equal time, from the CSVs `genpath sweep --time` writes.

    python3 scripts/ratios.py SCENE...            # reads reports/SCENE-2s-reps.csv and reports/SCENE.csv
    python3 scripts/ratios.py --dir reports/lt --pairs lt:pt,lt:pg SCENE...

For each scene, `ga-pt`'s and `pt`'s relMSE over `pg`'s: at 2 s the
geometric mean of the per-seed ratios over the paired seeds of SCENE-2s-reps.csv, with a
bootstrap 95 % upper bound (10 000 resamples of the seeds, fixed random seed), and at 8 and
30 s the single seed of SCENE.csv. Prints a Markdown table. A ratio counts only where both
renders are free of NaN, infinite and negative pixels (the CSV's `bad_fraction`, which relMSE
leaves out): a pair with any such pixel is left out and named on stderr.
"""
import csv
import math
import random
import sys
from collections import defaultdict

def rows(path):
    with open(path) as f:
        return list(csv.DictReader(f))


def paired(path, method, base):
    """log(relMSE_method / relMSE_base) per (seed, budget) where both rendered."""
    by = defaultdict(dict)
    for r in rows(path):
        if float(r.get("bad_fraction") or 0) > 0:
            # Older CSVs have no such column: their images were not checked.
            print(f"{path}: {r['method']} seed {r['seed']} budget {r['budget']}: "
                  f"bad_fraction {r['bad_fraction']}, left out", file=sys.stderr)
            continue
        by[(r["seed"], r["budget"])][r["method"]] = float(r["relmse"])
    return {k: math.log(v[method] / v[base]) for k, v in by.items() if method in v and base in v}


def geo_and_bound(logs):
    if not logs:
        return None, None
    mean = sum(logs) / len(logs)
    rng = random.Random(1)
    means = sorted(
        sum(rng.choice(logs) for _ in logs) / len(logs) for _ in range(10000)
    )
    return math.exp(mean), math.exp(means[int(0.975 * len(means))])


def main(scenes, pairs=(("ga-pt", "pg"), ("pt", "pg")), folder="reports"):
    print("| scene | method | over | 2 s (six seeds) | 95 % bound | 8 s | 30 s |")
    print("| --- | --- | --- | --- | --- | --- | --- |")
    for scene in scenes:
        for method, base in pairs:
            reps = paired(f"{folder}/{scene}-2s-reps.csv", method, base)
            g, ub = geo_and_bound(list(reps.values()))
            single = paired(f"{folder}/{scene}.csv", method, base)
            at = {b: math.exp(v) for (_, b), v in single.items()}
            fmt = lambda x: "–" if x is None else f"{x:.2f}" if x >= 0.1 else f"{x:.2g}"
            print(
                f"| {scene} | `{method}` | `{base}` | {fmt(g)} | {fmt(ub)} | "
                f"{fmt(at.get('8'))} | {fmt(at.get('30'))} |"
            )


if __name__ == "__main__":
    import argparse
    parser = argparse.ArgumentParser()
    parser.add_argument("scenes", nargs="*", default=["gap", "shelf", "window", "corridor"])
    parser.add_argument("--pairs", default="ga-pt:pg,pt:pg", help="method:over, comma-separated")
    parser.add_argument("--dir", default="reports")
    a = parser.parse_args()
    main(a.scenes, [tuple(p.split(":")) for p in a.pairs.split(",")], a.dir)
