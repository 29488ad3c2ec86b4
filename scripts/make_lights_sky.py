#!/usr/bin/env python3
"""Writes scenes/mitsuba/lights_sky.exr, the environment map of lights.xml (OpenEXR, float32
RGB, 64 × 32, by scripts/exr_write.py: nothing beyond Python's standard library): a sky
brighter towards the horizon over a darker ground, and a sun, a Gaussian blob of radius
about 3° whose peak is 60 times the sky's, at elevation 35°.

Run from anywhere: python3 scripts/make_lights_sky.py
"""
import math
import os

from exr_write import write_exr

ROOT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "scenes")
W, H = 64, 32


def direction(x, y):
    """Mitsuba's direction of texel (x, y): u at the texel's centre, v = y / (H - 1)."""
    phi = 2 * math.pi * (x + 0.5) / W
    theta = math.pi * y / (H - 1)
    return (math.sin(phi) * math.sin(theta), math.cos(theta), -math.cos(phi) * math.sin(theta))


def sky():
    elevation, azimuth = math.radians(35), math.radians(120)
    sun = (math.cos(elevation) * math.sin(azimuth), math.sin(elevation),
           -math.cos(elevation) * math.cos(azimuth))
    rows = []
    for y in range(H):
        row = []
        for x in range(W):
            d = direction(x, y)
            if d[1] >= 0:
                t = 1 - d[1]
                c = [0.25 + 0.45 * t, 0.4 + 0.4 * t, 0.8 + 0.15 * t]
            else:
                c = [0.12, 0.1, 0.08]
            cos_a = sum(a * b for a, b in zip(d, sun))
            angle = math.acos(max(-1.0, min(1.0, cos_a)))
            blob = 60.0 * math.exp(-((angle / math.radians(3.0)) ** 2))
            row.append((c[0] + blob, c[1] + 0.95 * blob, c[2] + 0.8 * blob))
        rows.append(row)
    return rows


def main():
    write_exr(os.path.join(ROOT, "mitsuba", "lights_sky.exr"), W, H, sky())


if __name__ == "__main__":
    main()
