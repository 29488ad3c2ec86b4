#!/usr/bin/env python3
"""One method's relMSE over another's at equal time, per scene, from `genpath sweep --time` CSVs.

    python3 scripts/pair_ratios.py METHOD BASE CSV...

For each CSV (one scene's sweep with several paired seeds, named after the scene), the mean relMSE of METHOD and of
BASE over the seeds, and the geometric mean of the per-seed ratios METHOD / BASE with its
bootstrap 95 % upper bound (as scripts/ratios.py computes them: 10 000 resamples of the
seeds, fixed random seed). Pairs with a NaN, infinite or negative pixel are left out and
named on stderr. Prints a Markdown table.
"""
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from ratios import geo_and_bound, paired, rows  # noqa: E402


def main(method, base, paths):
    print(f"| scene | `{base}` relMSE | `{method}` relMSE | ratio (geometric mean) | 95 % bound | pairs |")
    print("| --- | --- | --- | --- | --- | --- |")
    for path in paths:
        logs = paired(path, method, base)
        g, ub = geo_and_bound(list(logs.values()))
        mean = {}
        for m in (base, method):
            values = [float(r["relmse"]) for r in rows(path) if r["method"] == m]
            mean[m] = sum(values) / len(values) if values else float("nan")
        scene = os.path.basename(path).removesuffix(".csv")
        fmt = lambda x: "–" if x is None else f"{x:.3f}"
        print(f"| {scene} | {mean[base]:.4g} | {mean[method]:.4g} | {fmt(g)} | {fmt(ub)} | {len(logs)} |")


if __name__ == "__main__":
    if len(sys.argv) < 4:
        sys.exit(__doc__)
    main(sys.argv[1], sys.argv[2], sys.argv[3:])
