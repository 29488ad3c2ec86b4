"""Writes the textures of scenes/mitsuba/maps.xml (Mitsuba's `normalmap` and `bumpmap`),
8-bit RGB PNGs written byte by byte so that they need nothing but the standard library. Run
by hand, never by the build or CI:

    python3 scripts/make_maps.py

Writes scenes/mitsuba/maps/normals.png (16 × 16: the normals of a field of bumps,
(n + 1) / 2, every blue above 1/2), normals_gflip.png (the same with its green channel
flipped, the agreement test's must-reject twin: the bumps lit from the wrong side) and
heights.png (16 × 16 grey: a height field for the bump map, its luminance).
"""
import math
import os

from png_write import write_png

HERE = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "scenes", "mitsuba", "maps")
N = 16


def png(name, pixels):
    """An 8-bit RGB PNG of N × N `pixels` (row 0 at the top)."""
    write_png(os.path.join(HERE, name), N, N, pixels)


def byte(c):
    return max(0, min(255, round(255 * c)))


def normals(flip_green):
    """Bumps h = sin(2πx/8) sin(2πy/16) (texel units, steepest slope about 45°), and a
    slope in y that breaks the up-down symmetry."""
    px = []
    for y in range(N):
        for x in range(N):
            u, v = (x + 0.5) / N, (y + 0.5) / N
            dhdx = 0.9 * math.cos(4 * math.pi * u) * math.sin(2 * math.pi * v)
            dhdy = 0.6 * math.sin(4 * math.pi * u) * math.cos(2 * math.pi * v) + 0.35
            n = (-dhdx, -dhdy, 1.0)
            length = math.sqrt(sum(c * c for c in n))
            n = [c / length for c in n]
            if flip_green:
                n[1] = -n[1]
            px.append(tuple(byte((c + 1) / 2) for c in n))
    return px


def heights():
    px = []
    for y in range(N):
        for x in range(N):
            u, v = (x + 0.5) / N, (y + 0.5) / N
            h = 0.5 + 0.3 * math.sin(2 * math.pi * u) * math.cos(4 * math.pi * v) + 0.15 * math.sin(6 * math.pi * (u + v))
            g = byte(h)
            px.append((g, g, g))
    return px


os.makedirs(HERE, exist_ok=True)
png("normals.png", normals(False))
png("normals_gflip.png", normals(True))
png("heights.png", heights())
