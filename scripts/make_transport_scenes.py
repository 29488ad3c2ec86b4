"""Writes the light-transport test scenes (scenes/transport/*.xml), made before any tuning of
light tracing (issue 51) or of `pg`'s selection probabilities and roulette/splitting (issue 53)
and kept fixed. Deterministic; run by hand:

    python3 scripts/make_transport_scenes.py

Issue 51 item 4 (light paths matter):
* lamp_in_glass.xml: a small emitting sphere inside a hollow rough-glass shade (two
  `roughdielectric` spheres) hanging in a closed room; every shadow ray from the room to the
  lamp is blocked by the shade.
* caustic.xml: a smooth glass sphere on a diffuse floor, a back wall, and one small spherical
  light up and behind it; the caustic lies on the floor in front of the sphere.
* frosted_window.xml: a closed room whose only light is a lamp outside, behind a frosted
  (`roughdielectric`) window pane set in one wall.
Issue 53 item 3:
* plate.xml: two rooms joined by a narrow vertical slit; in the first a spot light aimed at a
  glossy aluminium plate (`roughconductor`) that reflects its beam through the slit onto the
  floor of the second, where the camera is; the first room's walls are dark (0.15) so that
  the second room is lit almost only off the plate.
* dark_window.xml: a room of albedo 0.1-0.2 whose only light is a bright window patch in the
  back wall, seen past dark slats and pillars.
* pinhole.xml: a closed room with a small square hole in its front wall, a bright constant sky
  and a sunlit-green ground and a red tower outside; the hole projects them, upside down,
  onto the back wall the camera looks at.
* mixed.xml: a room of diffuse, rough-plastic, smooth-plastic and rough-metal objects lit by
  four small spherical lamps of different colours and one spot.
"""
import os

here = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "scenes", "transport")

HEADER = """<?xml version="1.0" encoding="utf-8"?>
<!-- {what}
     Made before any tuning, kept fixed. Written by scripts/make_transport_scenes.py (do not
     edit). {depth_note} -->
<scene version="3.0.0">
    <default name="spp" value="64"/>
    <default name="res" value="128"/>
    <integrator type="path">
        <integer name="max_depth" value="{max_depth}"/>
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


def header(what, fov, origin, target, max_depth=6, depth_note=""):
    return HEADER.format(what=what, fov=fov, origin=origin, target=target,
                         max_depth=max_depth, depth_note=depth_note)


def fmt(v):
    return ", ".join(f"{x:g}" for x in v)


def diffuse(c, twosided=True):
    inner = f'<bsdf type="diffuse"><rgb name="reflectance" value="{fmt(c)}"/></bsdf>'
    return f'<bsdf type="twosided">{inner}</bsdf>' if twosided else inner


def black():
    return '<bsdf type="diffuse"><rgb name="reflectance" value="0"/></bsdf>'


def rect(cx, cy, cz, hx, hy, axis, bsdf, emitter=""):
    """An axis-aligned rectangle centred at (cx, cy, cz), half-sizes hx, hy in its plane.
    axis: the normal, one of +x -x +y -y +z -z. In-plane axes: for +-z (x, y); for +-x (z, y);
    for +-y (x, z)."""
    rot = {"+z": "", "-z": '<rotate y="1" angle="180"/>',
           "+x": '<rotate y="1" angle="90"/>', "-x": '<rotate y="1" angle="-90"/>',
           "+y": '<rotate x="1" angle="-90"/>', "-y": '<rotate x="1" angle="90"/>'}[axis]
    return f"""    <shape type="rectangle">
        <transform name="to_world">
            <scale x="{hx:g}" y="{hy:g}"/>
            {rot}
            <translate x="{cx:g}" y="{cy:g}" z="{cz:g}"/>
        </transform>
        {bsdf}{emitter}
    </shape>
"""


def cube(c, h, bsdf, ry=0.0):
    return f"""    <shape type="cube">
        <transform name="to_world">
            <scale x="{h[0]:g}" y="{h[1]:g}" z="{h[2]:g}"/>
            <rotate y="1" angle="{ry:g}"/>
            <translate x="{c[0]:g}" y="{c[1]:g}" z="{c[2]:g}"/>
        </transform>
        {bsdf}
    </shape>
"""


def sphere(c, r, bsdf, emitter="", flip=False):
    f = '\n        <boolean name="flip_normals" value="true"/>' if flip else ""
    return f"""    <shape type="sphere">
        <point name="center" x="{c[0]:g}" y="{c[1]:g}" z="{c[2]:g}"/>
        <float name="radius" value="{r:g}"/>{f}
        {bsdf}{emitter}
    </shape>
"""


def area(le):
    return f'\n        <emitter type="area"><rgb name="radiance" value="{fmt(le)}"/></emitter>'


def box_room(x0, x1, y0, y1, z0, z1, colours, skip=()):
    """Six twosided diffuse walls of the box [x0,x1]x[y0,y1]x[z0,z1], normals inward; colours:
    a dict from wall name (x0 x1 y0 y1 z0 z1) to albedo; `skip`: walls left out (built by the
    caller, e.g. with a hole)."""
    cx, cy, cz = (x0 + x1) / 2, (y0 + y1) / 2, (z0 + z1) / 2
    hx, hy, hz = (x1 - x0) / 2, (y1 - y0) / 2, (z1 - z0) / 2
    walls = {"y0": (cx, y0, cz, hx, hz, "+y"), "y1": (cx, y1, cz, hx, hz, "-y"),
             "z0": (cx, cy, z0, hx, hy, "+z"), "z1": (cx, cy, z1, hx, hy, "-z"),
             "x0": (x0, cy, cz, hz, hy, "+x"), "x1": (x1, cy, cz, hz, hy, "-x")}
    out = ""
    for name, (px, py, pz, a, b, axis) in walls.items():
        if name not in skip:
            out += rect(px, py, pz, a, b, axis, diffuse(colours[name]))
    return out


def wall_with_hole_z(z, x0, x1, y0, y1, hole, axis, bsdf):
    """A wall in the plane z from [x0,x1]x[y0,y1] with the rectangular hole
    hole = (hx0, hx1, hy0, hy1), made of four rectangles."""
    hx0, hx1, hy0, hy1 = hole
    parts = [(x0, x1, y0, hy0), (x0, x1, hy1, y1), (x0, hx0, hy0, hy1), (hx1, x1, hy0, hy1)]
    out = ""
    for a0, a1, b0, b1 in parts:
        out += rect((a0 + a1) / 2, (b0 + b1) / 2, z, (a1 - a0) / 2, (b1 - b0) / 2, axis, bsdf)
    return out


def wall_with_hole_x(x, z0, z1, y0, y1, hole, axis, bsdf):
    """As wall_with_hole_z, in the plane x, hole = (hz0, hz1, hy0, hy1)."""
    hz0, hz1, hy0, hy1 = hole
    parts = [(z0, z1, y0, hy0), (z0, z1, hy1, y1), (z0, hz0, hy0, hy1), (hz1, z1, hy0, hy1)]
    out = ""
    for a0, a1, b0, b1 in parts:
        out += rect(x, (b0 + b1) / 2, (a0 + a1) / 2, (a1 - a0) / 2, (b1 - b0) / 2, axis, bsdf)
    return out


def roughglass(alpha, dist="ggx"):
    return f"""<bsdf type="roughdielectric">
            <string name="distribution" value="{dist}"/>
            <float name="alpha" value="{alpha:g}"/>
            <string name="int_ior" value="bk7"/>
            <string name="ext_ior" value="air"/>
        </bsdf>"""


WHITE = (0.65, 0.65, 0.62)


def lamp_in_glass():
    out = header(
        "A small lamp (an emitting sphere, r 0.03) inside a hollow rough-glass shade (GGX alpha\n"
        "     0.25, bk7, outer r 0.22, inner r 0.2) hanging in a closed room with a table, a box and\n"
        "     a coloured wall: every shadow ray from the room is blocked by the shade. Issue 51\n"
        "     item 4(a): a lamp inside a rough-glass shade lighting a room.",
        fov=60, origin="1.6, 1.3, 2.3", target="-0.3, 0.8, -0.8", max_depth=8,
        depth_note="max_depth 8, not 6: the shade's two surfaces add two vertices to every path\n"
                   "     of the lamp's light (and more inside the shell).")
    cols = {k: WHITE for k in ("x0", "x1", "y0", "y1", "z0", "z1")}
    cols["x0"] = (0.6, 0.15, 0.1)
    cols["z0"] = (0.55, 0.6, 0.65)
    out += box_room(-2, 2, 0, 2.6, -2, 2.5, cols)
    # a table under the lamp and a box
    out += cube((0, 0.72, -0.5), (0.6, 0.03, 0.4), diffuse((0.45, 0.3, 0.15)))
    for dx in (-0.55, 0.55):
        for dz in (-0.85, -0.15):
            out += cube((dx, 0.35, dz), (0.03, 0.35, 0.03), diffuse((0.45, 0.3, 0.15)))
    out += cube((1.2, 0.3, -1.2), (0.3, 0.3, 0.3), diffuse((0.2, 0.35, 0.6)), ry=30)
    # the shade: a hollow shell of rough glass around the lamp
    c = (0.0, 1.7, -0.5)
    out += sphere(c, 0.22, roughglass(0.25))
    out += sphere(c, 0.2, roughglass(0.25), flip=True)
    out += sphere(c, 0.03, black(), area((2400, 2100, 1600)))
    out += "</scene>\n"
    return out


def caustic():
    out = header(
        "A smooth glass sphere (bk7, r 0.3) on a diffuse floor, a back wall, lit only by one\n"
        "     small spherical light (r 0.03) up and behind it; the caustic lies on the floor in\n"
        "     front of the sphere, seen directly. Issue 51 item 4(b): a caustic seen directly.",
        fov=45, origin="0.2, 1.6, 2.6", target="0.05, 0.15, 0.1")
    out += rect(0, 0, 0, 3, 3, "+y", diffuse((0.6, 0.6, 0.58)))
    out += rect(0, 1.5, -1.5, 3, 1.5, "+z", diffuse((0.5, 0.55, 0.6)))
    out += cube((-0.9, 0.2, -0.6), (0.2, 0.2, 0.2), diffuse((0.6, 0.2, 0.1)), ry=20)
    out += sphere((0, 0.3, 0), 0.3, """<bsdf type="dielectric">
            <string name="int_ior" value="bk7"/>
            <string name="ext_ior" value="air"/>
        </bsdf>""")
    out += sphere((-0.55, 1.2, -1.1), 0.03, black(), area((4000, 3700, 3200)))
    out += "</scene>\n"
    return out


def frosted_window():
    out = header(
        "A closed room whose only light is a lamp (an emitting sphere, r 0.1) outside it, 0.6\n"
        "     behind a frosted window pane (a 0.02-thick GGX roughdielectric slab, alpha 0.3, bk7)\n"
        "     that fills a 0.8 x 0.8 opening in the left wall. Issue 51 item 4(c): a light behind\n"
        "     a frosted window.",
        fov=60, origin="1.7, 1.2, 1.8", target="-0.5, 0.9, -0.6")
    cols = {k: WHITE for k in ("x0", "x1", "y0", "y1", "z0", "z1")}
    cols["z0"] = (0.5, 0.6, 0.5)
    out += box_room(-2, 2, 0, 2.5, -2, 2, cols, skip=("x0",))
    out += wall_with_hole_x(-2, -2, 2, 0, 2.5, (-1.0, -0.2, 0.9, 1.7), "+x", diffuse(WHITE))
    out += f"""    <shape type="cube">
        <transform name="to_world">
            <scale x="0.01" y="0.4" z="0.4"/>
            <translate x="-2" y="1.3" z="-0.6"/>
        </transform>
        {roughglass(0.3)}
    </shape>
"""
    out += cube((0.3, 0.4, -0.8), (0.4, 0.4, 0.4), diffuse((0.6, 0.45, 0.2)), ry=20)
    out += cube((-1.2, 0.6, 1.0), (0.25, 0.6, 0.25), diffuse((0.2, 0.3, 0.55)), ry=-10)
    out += sphere((-2.6, 1.5, -0.6), 0.1, black(), area((700, 650, 560)))
    out += "</scene>\n"
    return out


def plate():
    # room A (the lamp's): x in [-2, 0]; room B (the camera's): x in [0, 2]; y in [0, 2],
    # z in [-1, 1]; the shared wall x = 0 has a slit at z in [-0.05, 0.05], y in [0.35, 1.65].
    out = header(
        "Two rooms joined by a narrow slit (0.1 x 1.3) in their shared wall. In the first (dark\n"
        "     walls, albedo 0.15) a spot light aimed at a glossy aluminium plate (roughconductor,\n"
        "     GGX alpha 0.12) that reflects the beam through the slit onto the floor of the\n"
        "     second, where the camera is: the camera's room is lit only off the plate (and the\n"
        "     little light the first room's dark walls send through the slit). Issue 53 item\n"
        "     3(a): a long dim path to a small bright indirect source.",
        fov=60, origin="1.85, 1.5, 0.9", target="0.4, 0.3, -0.3")
    dark = (0.15, 0.15, 0.15)
    colsA = {k: dark for k in ("x0", "y0", "y1", "z0", "z1")}
    colsB = {k: (0.6, 0.6, 0.58) for k in ("x1", "y0", "y1", "z0", "z1")}
    colsB["z0"] = (0.3, 0.45, 0.6)
    out += box_room(-2, 0, 0, 2, -1, 1, colsA, skip=("x1",))
    out += box_room(0, 2, 0, 2, -1, 1, colsB, skip=("x0",))
    # the shared wall, twosided: dark on room A's side would need two shapes; both sides 0.5
    out += wall_with_hole_x(0, -1, 1, 0, 2, (-0.05, 0.05, 0.35, 1.65), "-x",
                            diffuse((0.5, 0.5, 0.5)))
    out += cube((1.3, 0.25, -0.6), (0.25, 0.25, 0.25), diffuse((0.6, 0.3, 0.15)), ry=15)
    # plate at P, reflecting the spot at S towards the slit's centre G
    P = (-0.8, 1.6, 0.0)
    S = (-1.85, 0.5, 0.6)
    G = (0.0, 1.0, 0.0)

    def unit(v):
        n = sum(x * x for x in v) ** 0.5
        return tuple(x / n for x in v)
    a = unit(tuple(s - p for s, p in zip(S, P)))
    b = unit(tuple(g - p for g, p in zip(G, P)))
    n = unit(tuple(x + y for x, y in zip(a, b)))
    T = tuple(round(p + x, 5) for p, x in zip(P, n))
    out += f"""    <shape type="rectangle">
        <transform name="to_world">
            <scale value="0.25"/>
            <lookat origin="{fmt(P)}" target="{fmt(T)}" up="0, 0, 1"/>
        </transform>
        <bsdf type="roughconductor">
            <string name="material" value="Al"/>
            <string name="distribution" value="ggx"/>
            <float name="alpha" value="0.12"/>
        </bsdf>
    </shape>
    <emitter type="spot">
        <transform name="to_world">
            <lookat origin="{fmt(S)}" target="{fmt(P)}" up="0, 1, 0"/>
        </transform>
        <rgb name="intensity" value="2400, 2200, 1800"/>
        <float name="cutoff_angle" value="9"/>
        <float name="beam_width" value="6"/>
    </emitter>
</scene>
"""
    return out


def dark_window():
    out = header(
        "A room of albedo 0.1-0.2 whose only light is a bright window patch (an emitting\n"
        "     rectangle, 0.9 x 0.7) in the back wall, seen past dark slats (0.1) hung across the\n"
        "     room and two pillars: most paths find nothing, a few carry everything. Issue 53\n"
        "     item 3(b): a bright window seen past dark occluders.",
        fov=55, origin="0.4, 1.1, 2.8", target="0, 1.1, -2")
    cols = {"x0": (0.15, 0.12, 0.1), "x1": (0.12, 0.14, 0.16), "y0": (0.2, 0.18, 0.15),
            "y1": (0.15, 0.15, 0.15), "z0": (0.12, 0.12, 0.12), "z1": (0.15, 0.15, 0.15)}
    out += box_room(-1.5, 1.5, 0, 2.4, -2, 3, cols)
    out += rect(0.2, 1.3, -1.99, 0.45, 0.35, "+z", black(), area((40, 38, 34)))
    for i in range(6):
        out += cube((0.0, 0.85 + 0.16 * i, -1.0), (1.2, 0.025, 0.06), diffuse((0.1, 0.1, 0.1)))
    for x in (-0.45, 0.75):
        out += cube((x, 1.2, -0.4), (0.12, 1.2, 0.12), diffuse((0.15, 0.15, 0.13)))
    out += cube((-0.8, 0.3, 0.6), (0.35, 0.3, 0.35), diffuse((0.2, 0.15, 0.1)), ry=25)
    out += "</scene>\n"
    return out


def pinhole():
    out = header(
        "A closed room (3 x 2.4 x 2.4) with a 0.16 x 0.16 hole in its front wall; outside, a bright\n"
        "     constant sky, a green ground and a red tower. The hole projects them, upside down\n"
        "     (ground above the horizon line, sky below), onto the back wall the camera looks at;\n"
        "     the room is lit only through the hole. Issue 53 item 3(c): a pinhole projection.",
        fov=60, origin="0.8, 1.0, 1.08", target="-0.1, 1.1, -1.2")
    cols = {k: (0.7, 0.7, 0.7) for k in ("x0", "x1", "y0", "y1", "z0", "z1")}
    out += box_room(-1.5, 1.5, 0, 2.4, -1.2, 1.2, cols, skip=("z1",))
    out += wall_with_hole_z(1.2, -1.5, 1.5, 0, 2.4, (-0.08, 0.08, 1.12, 1.28), "-z",
                            diffuse((0.7, 0.7, 0.7)))
    # outside: ground and a tower
    out += rect(0, -0.001, 1.2, 5, 5, "+y", diffuse((0.2, 0.45, 0.15)))
    out += cube((1.2, 1.5, 4.0), (0.4, 1.5, 0.4), diffuse((0.7, 0.15, 0.1)))
    out += """    <emitter type="constant">
        <rgb name="radiance" value="300, 340, 400"/>
    </emitter>
</scene>
"""
    return out


def mixed():
    out = header(
        "A room of mixed glossy and diffuse surfaces (rough aluminium and gold, rough and\n"
        "     smooth plastic, a glossy floor, diffuse walls) lit by four small spherical lamps\n"
        "     (r 0.03) of different colours and a spot. Issue 53 item 3(d): a mixed\n"
        "     glossy/diffuse interior with several small lights.",
        fov=60, origin="1.4, 1.4, 2.3", target="-0.2, 0.6, -0.6")
    cols = {k: WHITE for k in ("x0", "x1", "y1", "z0", "z1")}
    cols["x1"] = (0.2, 0.4, 0.3)
    out += box_room(-2, 2, 0, 2.5, -2, 2.5, cols, skip=("y0",))
    out += rect(0.25, 0, 0.25, 2, 2.25, "+y", """<bsdf type="roughplastic">
            <string name="distribution" value="ggx"/>
            <float name="alpha" value="0.08"/>
            <rgb name="diffuse_reflectance" value="0.35, 0.25, 0.18"/>
        </bsdf>""")
    out += cube((-1.0, 0.4, -1.0), (0.4, 0.4, 0.4), """<bsdf type="roughconductor">
            <string name="material" value="Al"/>
            <string name="distribution" value="ggx"/>
            <float name="alpha" value="0.15"/>
        </bsdf>""", ry=30)
    out += sphere((0.4, 0.35, -0.3), 0.35, """<bsdf type="plastic">
            <rgb name="diffuse_reflectance" value="0.1, 0.2, 0.6"/>
        </bsdf>""")
    out += sphere((-0.3, 0.25, 0.6), 0.25, """<bsdf type="roughconductor">
            <string name="material" value="Au"/>
            <string name="distribution" value="beckmann"/>
            <float name="alpha" value="0.25"/>
        </bsdf>""")
    out += cube((1.2, 0.6, -1.3), (0.3, 0.6, 0.3), diffuse((0.6, 0.55, 0.5)), ry=-20)
    # a glossy panel on the back wall
    out += rect(0.2, 1.4, -1.98, 0.8, 0.5, "+z", """<bsdf type="roughconductor">
            <string name="material" value="Cu"/>
            <string name="distribution" value="ggx"/>
            <float name="alpha" value="0.05"/>
        </bsdf>""")
    for c, le in [((-1.5, 1.9, 0.5), (1500, 1200, 800)), ((1.4, 2.1, 0.8), (600, 900, 1500)),
                  ((0.0, 0.9, -1.7), (1200, 1200, 1200)), ((1.6, 0.3, 1.6), (1500, 600, 400))]:
        out += sphere(c, 0.03, black(), area(le))
    out += """    <emitter type="spot">
        <transform name="to_world">
            <lookat origin="-1.8, 2.4, 2.2" target="0.4, 0.35, -0.3" up="0, 1, 0"/>
        </transform>
        <rgb name="intensity" value="12, 11, 9"/>
        <float name="cutoff_angle" value="15"/>
        <float name="beam_width" value="10"/>
    </emitter>
</scene>
"""
    return out


SCENES = [("lamp_in_glass", lamp_in_glass), ("caustic", caustic),
          ("frosted_window", frosted_window), ("plate", plate),
          ("dark_window", dark_window), ("pinhole", pinhole), ("mixed", mixed)]

if __name__ == "__main__":
    os.makedirs(here, exist_ok=True)
    for name, make in SCENES:
        text = make()
        with open(os.path.join(here, name + ".xml"), "w") as f:
            f.write(text)
        print(name, len(text.splitlines()), "lines")
