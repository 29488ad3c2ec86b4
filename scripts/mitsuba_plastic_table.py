"""Prints the table of Mitsuba 3's own smooth `plastic` values that tests/brdf_sampler/
plastic.rs checks genpath's lobe choice and diffuse lobe against. Run by hand, never by the
build or CI:

    pip install mitsuba==3.9.1
    python3 scripts/mitsuba_plastic_table.py > tests/brdf_sampler/plastic_mitsuba.txt

Variant `scalar_rgb`. For each material (`material` lines: name, eta = int_ior / ext_ior as
Mitsuba computes it in single precision, nonlinear, diffuse_reflectance and
specular_reflectance), at direction pairs in Mitsuba's local shading frame (`si.wi`,
genpath's `wo`, then Mitsuba's `wo`, genpath's `wi`; unit vectors in single precision,
printed exactly): the BSDF value without the cosine (`bsdf.eval(ctx, si, wo) / cos θ_o`,
RGB, the diffuse lobe: the delta reflection has no value), `bsdf.pdf(ctx, si, wo)` (the
diffuse lobe's density times its probability), and from `bsdf.sample(ctx, si, 0, ·)` (the
delta reflection, which `sample1` = 0 chooses whenever it can be chosen) its probability
(`bs.pdf`, Mitsuba's `prob_specular`) and its weight (RGB, `specular_reflectance · F /
prob_specular`).
"""
import math
import struct

import drjit as dr
import mitsuba as mi

mi.set_variant("scalar_rgb")

# name, plugin parameters
MATERIALS = [
    ("default", {}),
    (
        "tinted",
        {
            "int_ior": 1.9,
            "ext_ior": 1.0,
            "diffuse_reflectance": {"type": "rgb", "value": [0.7, 0.3, 0.1]},
            "specular_reflectance": {"type": "rgb", "value": [0.9, 0.8, 0.5]},
        },
    ),
    (
        "nonlinear",
        {
            "int_ior": "water",
            "ext_ior": "air",
            "nonlinear": True,
            "diffuse_reflectance": {"type": "rgb", "value": [0.9, 0.5, 0.2]},
        },
    ),
    ("low_contrast", {"int_ior": 1.3, "ext_ior": 1.2, "diffuse_reflectance": {"type": "rgb", "value": [0.2, 0.2, 0.2]}}),
]

# (θ, φ) of si.wi and of wo.
PAIRS = [
    ((0.05, 0.3), (0.2, 3.6)),  # near normal
    ((0.7, 0.3), (1.1, 2.0)),
    ((1.2, 2.0), (0.4, 5.2)),
    ((1.5, 1.0), (1.45, 4.0)),  # grazing both
    ((0.9, 0.5), (math.pi - 0.9, 3.7)),  # wo below the surface: zero
]


def direction(theta, phi):
    return dr.normalize(
        mi.Vector3f(math.sin(theta) * math.cos(phi), math.sin(theta) * math.sin(phi), math.cos(theta))
    )


def single(x):
    """`x` rounded to single precision."""
    return struct.unpack("f", struct.pack("f", x))[0]


def f32(x):
    """The single-precision value, printed exactly (as the shortest double that is it)."""
    return repr(single(x))


ctx = mi.BSDFContext()
print("# Mitsuba 3.9.1 scalar_rgb plastic: scripts/mitsuba_plastic_table.py")
print("# material NAME ETA NONLINEAR D_R D_G D_B S_R S_G S_B")
print("# NAME WI_X WI_Y WI_Z WO_X WO_Y WO_Z F_R F_G F_B PDF P_SPECULAR W_R W_G W_B")
for name, params in MATERIALS:
    bsdf = mi.load_dict({"type": "plastic", **params})
    eta = float(mi.traverse(bsdf)["eta"])
    diffuse = params.get("diffuse_reflectance", {"value": [0.5, 0.5, 0.5]})["value"]
    specular = params.get("specular_reflectance", {"value": [1.0, 1.0, 1.0]})["value"]
    print(
        "material",
        name,
        f32(eta),
        str(params.get("nonlinear", False)).lower(),
        *[f32(c) for c in diffuse],
        *[f32(c) for c in specular],
    )
    for a, b in PAIRS:
        si = mi.SurfaceInteraction3f()
        si.wi = direction(*a)
        wo = direction(*b)
        value = bsdf.eval(ctx, si, wo)
        pdf = bsdf.pdf(ctx, si, wo)
        cos_o = abs(float(wo[2]))
        f = [float(value[i]) / cos_o for i in range(3)]
        bs, weight = bsdf.sample(ctx, si, 0.0, mi.Point2f(0.5, 0.5))
        assert bs.sampled_type == int(mi.BSDFFlags.DeltaReflection)
        print(
            name,
            *[repr(float(si.wi[i])) for i in range(3)],
            *[repr(float(wo[i])) for i in range(3)],
            *["%.9e" % v for v in f],
            "%.9e" % float(pdf),
            "%.9e" % float(bs.pdf),
            *["%.9e" % float(weight[i]) for i in range(3)],
        )
