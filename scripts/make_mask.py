"""Writes the opacity texture of scenes/mitsuba/mask.xml (Mitsuba's `mask`): an 8-bit grey
PNG (three equal channels), written byte by byte so that it needs nothing but the standard
library. Run by hand, never by the build or CI:

    python3 scripts/make_mask.py

Writes scenes/mitsuba/masks/leaf.png (16 × 16): a leaf, opaque (255) inside an outline
pointed at both ends, clear (0) outside, with a half-grey rim (128, an opacity of 0.216
once sRGB-decoded) and a clear midrib, so that the opacity takes fractional values too.
"""
import math
import os

from png_write import write_png

HERE = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "scenes", "mitsuba", "masks")
N = 16


def png(name, pixels):
    """An 8-bit RGB PNG of N × N `pixels` (row 0 at the top)."""
    write_png(os.path.join(HERE, name), N, N, pixels)


def leaf():
    """Inside |x| < half-width(y), the half-width sin(π t)^0.8 · 0.42 along t = y."""
    px = []
    for y in range(N):
        for x in range(N):
            u, v = (x + 0.5) / N, (y + 0.5) / N
            w = 0.42 * math.sin(math.pi * v) ** 0.8
            d = abs(u - 0.5)
            if d < 0.04:
                g = 0
            elif d < w - 0.08:
                g = 255
            elif d < w:
                g = 128
            else:
                g = 0
            px.append((g, g, g))
    return px


os.makedirs(HERE, exist_ok=True)
png("leaf.png", leaf())
