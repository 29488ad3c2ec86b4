"""Prints the table of Mitsuba 3's own `roughdielectric` values that tests/brdf_sampler/
roughdielectric.rs checks genpath's `eval` and `pdf` against. Run by hand, never by the build
or CI:

    pip install mitsuba==3.9.1
    python3 scripts/mitsuba_roughdielectric_table.py > tests/brdf_sampler/roughdielectric_mitsuba.txt

Variant `scalar_rgb`. For each material (`material` lines: name, distribution, alpha_u,
alpha_v, sample_visible, eta = int_ior / ext_ior as Mitsuba computes it in single precision,
specular_reflectance and specular_transmittance), at direction pairs in Mitsuba's local
shading frame (`si.wi`, genpath's `wo`, then Mitsuba's `wo`, genpath's `wi`; both unit
vectors in single precision, printed exactly), the BSDF value without the cosine
(`bsdf.eval(ctx, si, wo) / |cos θ_o|`, RGB) and `bsdf.pdf(ctx, si, wo)` in radiance mode.
The pairs cover reflection and transmission from outside (`si.wi` above the surface) and
from inside (below it: the relative index inverted), grazing and near-normal incidence, total
internal reflection, and configurations where the BSDF is zero.
"""
import math
import struct

import drjit as dr
import mitsuba as mi

mi.set_variant("scalar_rgb")

# name, plugin parameters
MATERIALS = [
    ("ggx", {"distribution": "ggx", "alpha": 0.2, "int_ior": 1.5, "ext_ior": 1.0}),
    (
        "beckmann_tinted",
        {
            "distribution": "beckmann",
            "alpha": 0.3,
            "int_ior": "bk7",
            "ext_ior": "air",
            "specular_reflectance": {"type": "rgb", "value": [0.9, 0.8, 0.7]},
            "specular_transmittance": {"type": "rgb", "value": [0.6, 0.7, 0.8]},
        },
    ),
    (
        "ggx_anisotropic",
        {"distribution": "ggx", "alpha_u": 0.1, "alpha_v": 0.4, "int_ior": "water", "ext_ior": 1.0},
    ),
    (
        "beckmann_all_normals",
        {"distribution": "beckmann", "alpha": 0.25, "int_ior": 1.7, "ext_ior": 1.0, "sample_visible": False},
    ),
    (
        "ggx_all_normals_low_contrast",
        {"distribution": "ggx", "alpha": 0.5, "int_ior": 1.5, "ext_ior": 1.2, "sample_visible": False},
    ),
]

# (θ, φ) of si.wi and of wo; θ > π/2 lies below the surface.
PI = math.pi
PAIRS = [
    ((0.5, 0.3), (0.7, 3.6)),  # outside, reflection
    ((0.5, 0.3), (PI - 0.35, 3.3)),  # outside, transmission
    ((1.45, 2.0), (PI - 0.9, 5.0)),  # grazing, transmission
    ((1.45, 2.0), (1.3, 5.2)),  # grazing, reflection
    ((0.05, 0.0), (PI - 0.1, 0.7)),  # near normal, transmission
    ((PI - 0.4, 1.0), (0.6, 4.0)),  # inside, transmission out
    ((PI - 0.4, 1.0), (PI - 0.5, 4.2)),  # inside, reflection
    ((PI - 1.0, 0.5), (PI - 1.1, 3.5)),  # inside beyond the critical angle, reflection
    ((PI - 1.0, 0.5), (0.9, 3.7)),  # inside beyond the critical angle, transmission
    ((0.5, 0.3), (PI - 0.5, 0.3)),  # outside, wo = si.wi mirrored in the surface (no facet refracts there: zero)
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
print("# Mitsuba 3.9.1 scalar_rgb roughdielectric: scripts/mitsuba_roughdielectric_table.py")
print("# material NAME DISTRIBUTION ALPHA_U ALPHA_V SAMPLE_VISIBLE ETA R_R R_G R_B T_R T_G T_B")
print("# NAME WI_X WI_Y WI_Z WO_X WO_Y WO_Z F_R F_G F_B PDF")
for name, params in MATERIALS:
    bsdf = mi.load_dict({"type": "roughdielectric", **params})
    ior = {"bk7": 1.5046, "air": 1.000277, "water": 1.3330}
    int_ior = ior.get(params["int_ior"], params["int_ior"])
    ext_ior = ior.get(params["ext_ior"], params["ext_ior"])
    eta = single(single(int_ior) / single(ext_ior))
    assert abs(float(mi.traverse(bsdf)["eta"]) - float(eta)) == 0.0
    au = params.get("alpha_u", params.get("alpha"))
    av = params.get("alpha_v", params.get("alpha"))
    refl = params.get("specular_reflectance", {"value": [1.0, 1.0, 1.0]})["value"]
    trans = params.get("specular_transmittance", {"value": [1.0, 1.0, 1.0]})["value"]
    print(
        "material",
        name,
        params["distribution"],
        f32(au),
        f32(av),
        str(params.get("sample_visible", True)).lower(),
        f32(eta),
        *[f32(c) for c in refl],
        *[f32(c) for c in trans],
    )
    for a, b in PAIRS:
        si = mi.SurfaceInteraction3f()
        si.wi = direction(*a)
        wo = direction(*b)
        value = bsdf.eval(ctx, si, wo)
        pdf = bsdf.pdf(ctx, si, wo)
        cos_o = abs(float(wo[2]))
        f = [float(value[i]) / cos_o for i in range(3)]
        print(
            name,
            *[repr(float(si.wi[i])) for i in range(3)],
            *[repr(float(wo[i])) for i in range(3)],
            *["%.9e" % v for v in f],
            "%.9e" % float(pdf),
        )
