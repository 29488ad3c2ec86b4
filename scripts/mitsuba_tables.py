"""Writes src/scene/xml/tables.rs: the data genpath's Mitsuba XML loader takes from Mitsuba 3.

Run by hand (not by the build or CI), with Mitsuba 3 installed (`pip install mitsuba==3.9.1`):

    python3 scripts/mitsuba_tables.py > src/scene/xml/tables.rs

* the CIE 1931 2° colour-matching functions and the CIE D65 illuminant at Mitsuba's 95
  samples (360–830 nm, 5 nm), as Mitsuba integrates wavelength:value spectra in its RGB
  variants;
* the RGB (η, k) of every conductor preset of Mitsuba's `conductor` plugin (`material`),
  converted by Mitsuba's own `spectrum_list_to_srgb(…, bounded=False, d65=False)` from its
  data/ior/*.spd files, as Mitsuba's RGB variants do.
"""
import glob
import os

import mitsuba as mi

mi.set_variant("scalar_rgb")
mi.set_log_level(mi.LogLevel.Error)  # its clamping warnings go to stdout

SAMPLES = 95
wavelengths = [360.0 + 5.0 * i for i in range(SAMPLES)]


def row(values):
    return ", ".join(repr(float(v)) for v in values)


print("//! Data taken from Mitsuba 3 by `scripts/mitsuba_tables.py` (generated; do not edit).")
print(f"//! Mitsuba {mi.MI_VERSION}.")
print()
print("/// CIE 1931 2° x̄, ȳ, z̄ at 360 + 5·i nm, i < 95.")
for name, k in (("CIE_X", 0), ("CIE_Y", 1), ("CIE_Z", 2)):
    vals = [mi.cie1931_xyz(w)[k] for w in wavelengths]
    print(f"pub const {name}: [f64; 95] = [{row(vals)}];")
print("/// CIE D65 relative spectral power at the same wavelengths, normalised as Mitsuba's")
print("/// `cie_d65` (unit luminance).")
print(f"pub const D65: [f64; 95] = [{row([mi.cie_d65(w) for w in wavelengths])}];")

ior_dir = os.path.join(os.path.dirname(mi.__file__), "data", "ior")
names = sorted(
    os.path.basename(p)[: -len(".eta.spd")] for p in glob.glob(os.path.join(ior_dir, "*.eta.spd"))
)


def spd(path):
    wl, v = [], []
    for line in open(path):
        line = line.split("#")[0].strip()
        if line:
            a, b = line.split()[:2]
            wl.append(float(a))
            v.append(float(b))
    return wl, v


print("/// Mitsuba's conductor presets: (name, RGB η, RGB k).")
print("pub const CONDUCTORS: &[(&str, [f64; 3], [f64; 3])] = &[")
for name in names:
    rgb = []
    for part in ("eta", "k"):
        wl, v = spd(os.path.join(ior_dir, f"{name}.{part}.spd"))
        c = mi.spectrum_list_to_srgb(wl, v, bounded=False, d65=False)
        rgb.append([c[0], c[1], c[2]])
    print(f'    ("{name}", [{row(rgb[0])}], [{row(rgb[1])}]),')
print("];")
