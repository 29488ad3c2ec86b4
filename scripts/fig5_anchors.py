#!/usr/bin/env python3
"""What the GA learned on fig5 (paper §6), from the JSON of a `--method ga` render.

Per image half (left / right), over the GA pixels that improved on srt: the share of the
evolved weight held by generators whose first step aims at the red wall (x = -1) or the blue
wall (x = +1), split into the wall's upper part (y >= 1.4, lit through the gap above the
occluder) and the rest; the mean absorption of those generators at the wall vertex (step 2);
and the mean first-step anchor height.

Usage: scripts/fig5_anchors.py fig5.exr.json
"""
import json
import sys


def classify(step):
    s = step["sampler"]
    if s["type"] != "anchor":
        return "brdf"
    x, y, _ = s["anchor"]
    wall = "red" if x < -0.999 else "blue" if x > 0.999 else None
    if wall is None:
        return "other anchor"
    return f"{wall} upper" if y >= 1.4 else f"{wall} lower"


def main(path):
    stats = json.load(open(path))
    width = stats["width"]
    kinds = ["red upper", "red lower", "blue upper", "blue lower", "other anchor", "brdf"]
    halves = {"left": [], "right": []}
    for p in stats["ga"]["pixels"]:
        if p["kept_srt"]:
            continue
        m = p["mixture"]
        evolved = sum(m["weights"][1:])
        share = dict.fromkeys(kinds, 0.0)
        absorb = {"red upper": [], "blue upper": []}
        heights = []
        for g, w in zip(m["generators"][1:], m["weights"][1:]):
            kind = classify(g["steps"][0])
            share[kind] += w / evolved
            if kind in absorb and len(g["steps"]) > 1:
                absorb[kind].append((w, g["steps"][1]["absorption"]))
            if g["steps"][0]["sampler"]["type"] == "anchor":
                heights.append((w, g["steps"][0]["sampler"]["anchor"][1]))
        halves["left" if p["x"] < width / 2 else "right"].append((share, absorb, heights))
    print("| half | GA pixels | " + " | ".join(kinds) + " | absorption at wall (red/blue upper) | mean anchor height |")
    print("|---" * (len(kinds) + 4) + "|")
    for half, rows in halves.items():
        n = len(rows)
        if n == 0:
            continue
        mean = {k: sum(r[0][k] for r in rows) / n for k in kinds}
        absorption = []
        for k in ("red upper", "blue upper"):
            pairs = [a for r in rows for a in r[1][k]]
            wsum = sum(w for w, _ in pairs)
            absorption.append(f"{sum(w * a for w, a in pairs) / wsum:.2f}" if wsum > 0 else "-")
        hp = [h for r in rows for h in r[2]]
        hw = sum(w for w, _ in hp)
        height = sum(w * h for w, h in hp) / hw if hw > 0 else float("nan")
        print(f"| {half} | {n} | " + " | ".join(f"{mean[k]:.2f}" for k in kinds)
              + f" | {absorption[0]} / {absorption[1]} | {height:.2f} |")


if __name__ == "__main__":
    main(sys.argv[1])
