"""Writes the light-sampling test scenes (scenes/lights/*.xml), made before any tuning of the
light sampler and kept fixed (issue 47). Deterministic; run by hand:

    python3 scripts/make_light_scenes.py

* dome.xml: a room-less courtyard under a large dim emitting dome (an inward-facing sphere of
  radius 100, radiance 0.02) lit mostly by three small bright lamps (spheres of radius 0.04,
  radiance 300–600) and a spot; a floor, two boxes and a wall. Nearly all of the light on
  the floor comes from the lamps, nearly all the emitting area is the dome.
* many.xml: a long hall lit by 1024 small one-sided ceiling panels (0.06 × 0.06) in a 32 × 32
  grid whose radiance varies from panel to panel (a fixed pseudo-random pattern), over a
  floor with pillars; the camera looks down the hall, so that each point is lit mostly by
  the few panels near it.
"""
import os
import random

here = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "scenes", "lights")

HEADER = """<?xml version="1.0" encoding="utf-8"?>
<!-- {what} Written by scripts/make_light_scenes.py (do not edit). -->
<scene version="3.0.0">
    <default name="spp" value="64"/>
    <default name="res" value="128"/>
    <integrator type="path">
        <integer name="max_depth" value="6"/>
    </integrator>
    <sensor type="perspective">
        <float name="fov" value="{fov}"/>
        <transform name="to_world">
            <lookat origin="{origin}" target="{target}" up="0, 1, 0"/>
        </transform>
        <sampler type="independent">
            <integer name="sample_count" value="$spp"/>
        </sampler>
        <film type="hdrfilm">
            <integer name="width" value="$res"/>
            <integer name="height" value="$res"/>
            <rfilter type="box"/>
        </film>
    </sensor>
"""


def diffuse(r, g, b):
    return f'<bsdf type="diffuse"><rgb name="reflectance" value="{r}, {g}, {b}"/></bsdf>'


def box(sx, sy, sz, ry, x, y, z, colour):
    return f"""    <shape type="cube">
        <transform name="to_world">
            <scale x="{sx}" y="{sy}" z="{sz}"/>
            <rotate y="1" angle="{ry}"/>
            <translate x="{x}" y="{y}" z="{z}"/>
        </transform>
        {diffuse(*colour)}
    </shape>
"""


def floor(half, y=0.0, colour=(0.6, 0.6, 0.55)):
    return f"""    <shape type="rectangle">
        <transform name="to_world">
            <scale value="{half}"/>
            <rotate x="1" angle="-90"/>
            <translate y="{y}"/>
        </transform>
        {diffuse(*colour)}
    </shape>
"""


def dome():
    out = HEADER.format(
        what="A large dim emitting dome and small bright lamps (light-sampling test scene).",
        fov=45,
        origin="0, 2.2, 5.5",
        target="0, 0.4, 0",
    )
    out += floor(20)
    out += box(0.4, 0.4, 0.4, 25, -0.9, 0.4, 0.0, (0.7, 0.2, 0.1))
    out += box(0.3, 1.0, 0.3, -15, 0.8, 1.0, -0.6, (0.2, 0.3, 0.7))
    # a wall behind
    out += """    <shape type="rectangle">
        <transform name="to_world">
            <scale x="4" y="2"/>
            <translate y="2" z="-2.5"/>
        </transform>
        """ + diffuse(0.5, 0.5, 0.5) + """
    </shape>
"""
    # the dome: inward-facing, dim
    out += """    <shape type="sphere">
        <float name="radius" value="100"/>
        <boolean name="flip_normals" value="true"/>
        """ + diffuse(0, 0, 0) + """
        <emitter type="area"><rgb name="radiance" value="0.02, 0.025, 0.03"/></emitter>
    </shape>
"""
    for (x, y, z), le in [((-1.6, 1.3, 1.0), (600, 520, 400)),
                          ((1.7, 0.9, 0.8), (300, 350, 450)),
                          ((0.2, 2.4, -1.5), (500, 500, 500))]:
        out += f"""    <shape type="sphere">
        <point name="center" x="{x}" y="{y}" z="{z}"/>
        <float name="radius" value="0.04"/>
        {diffuse(0, 0, 0)}
        <emitter type="area"><rgb name="radiance" value="{le[0]}, {le[1]}, {le[2]}"/></emitter>
    </shape>
"""
    out += """    <emitter type="spot">
        <transform name="to_world">
            <lookat origin="2.5, 3, 2" target="-0.5, 0, -0.5" up="0, 1, 0"/>
        </transform>
        <rgb name="intensity" value="8, 7.6, 6"/>
        <float name="cutoff_angle" value="25"/>
        <float name="beam_width" value="15"/>
    </emitter>
</scene>
"""
    return out


def many():
    out = HEADER.format(
        what="A hall lit by 1024 small ceiling panels of varied radiance (light-sampling test scene).",
        fov=55,
        origin="0, 1.2, 7.5",
        target="0, 0.9, -4",
    )
    out += floor(8, colour=(0.55, 0.55, 0.5))
    # side walls and a back wall
    for x, angle in [(-3, 90), (3, -90)]:
        out += f"""    <shape type="rectangle">
        <transform name="to_world">
            <scale x="8" y="1.5"/>
            <rotate y="1" angle="{angle}"/>
            <translate x="{x}" y="1.5"/>
        </transform>
        {diffuse(0.5, 0.45, 0.4)}
    </shape>
"""
    for i in range(5):
        z = -6 + 3 * i
        for x in (-1.6, 1.6):
            out += box(0.15, 1.4, 0.15, 0, x, 1.4, z, (0.6, 0.6, 0.6))
    rng = random.Random(47)
    for i in range(32):
        for j in range(32):
            x = -2.8 + 5.6 * (i + 0.5) / 32
            z = -7.5 + 15.0 * (j + 0.5) / 32
            level = rng.choice([0.2, 1.0, 1.0, 3.0, 10.0])
            tint = rng.choice([(1.0, 0.9, 0.7), (0.8, 0.9, 1.0), (1.0, 1.0, 1.0)])
            le = [round(20 * level * t, 3) for t in tint]
            out += f"""    <shape type="rectangle">
        <transform name="to_world">
            <scale value="0.03"/>
            <rotate x="1" angle="90"/>
            <translate x="{x:.4f}" y="2.9" z="{z:.4f}"/>
        </transform>
        {diffuse(0, 0, 0)}
        <emitter type="area"><rgb name="radiance" value="{le[0]}, {le[1]}, {le[2]}"/></emitter>
    </shape>
"""
    out += "</scene>\n"
    return out


os.makedirs(here, exist_ok=True)
for name, text in [("dome", dome()), ("many", many())]:
    with open(os.path.join(here, name + ".xml"), "w") as f:
        f.write(text)
    print(name, len(text.splitlines()), "lines")
