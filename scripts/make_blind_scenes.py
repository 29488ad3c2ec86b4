"""Writes the four scenes nobody tuned for (issue 24): scenes/{gap,shelf,window,corridor}/.

    python3 scripts/make_blind_scenes.py

Each scene is an OBJ of quads (metres, y up) with its MTL and scene.toml (256 x 256, max
bounces 5). Surfaces are two-sided Lambertian unless named otherwise; an emitter emits on the
side its quad's normal points to (counter-clockwise winding seen from that side). Once
committed with their references these scenes stay fixed: the GA is tuned on fig5, fig1, cbox
and glossy only, and reported on these.
"""
import os

ROOT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "scenes")


class Mesh:
    def __init__(self):
        self.v = []
        self.groups = []  # (name, material, [faces])

    def quad(self, name, material, a, b, c, d, facing=None):
        """A quad a-b-c-d; with `facing` (a vector), wound so its normal points along it."""
        if facing is not None:
            e1 = [b[i] - a[i] for i in range(3)]
            e2 = [c[i] - a[i] for i in range(3)]
            n = [e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2], e1[0] * e2[1] - e1[1] * e2[0]]
            if sum(n[i] * facing[i] for i in range(3)) < 0:
                a, b, c, d = d, c, b, a
        base = len(self.v) + 1
        self.v.extend([a, b, c, d])
        self.groups.append((name, material, [(base, base + 1, base + 2, base + 3)]))

    def box_x(self, name, material, x0, x1, y0, y1, z0, z1):
        """The four walls and two caps of an axis-aligned box."""
        p = lambda x, y, z: (x, y, z)
        self.quad(name, material, p(x0, y0, z0), p(x1, y0, z0), p(x1, y0, z1), p(x0, y0, z1))
        self.quad(name, material, p(x0, y1, z0), p(x1, y1, z0), p(x1, y1, z1), p(x0, y1, z1))
        self.quad(name, material, p(x0, y0, z0), p(x1, y0, z0), p(x1, y1, z0), p(x0, y1, z0))
        self.quad(name, material, p(x0, y0, z1), p(x1, y0, z1), p(x1, y1, z1), p(x0, y1, z1))
        self.quad(name, material, p(x0, y0, z0), p(x0, y0, z1), p(x0, y1, z1), p(x0, y1, z0))
        self.quad(name, material, p(x1, y0, z0), p(x1, y0, z1), p(x1, y1, z1), p(x1, y1, z0))

    def write(self, path, mtl, header):
        with open(path, "w") as f:
            f.write(header)
            f.write(f"mtllib {mtl}\n")
            for v in self.v:
                f.write("v {:.4f} {:.4f} {:.4f}\n".format(*v))
            for name, material, faces in self.groups:
                f.write(f"o {name}\nusemtl {material}\n")
                for face in faces:
                    f.write("f " + " ".join(str(i) for i in face) + "\n")


def wall_x(m, name, material, x, y0, y1, z0, z1):
    m.quad(name, material, (x, y0, z0), (x, y0, z1), (x, y1, z1), (x, y1, z0))


def wall_z(m, name, material, z, x0, x1, y0, y1):
    m.quad(name, material, (x0, y0, z), (x1, y0, z), (x1, y1, z), (x0, y1, z))


def floor_y(m, name, material, y, x0, x1, z0, z1):
    m.quad(name, material, (x0, y, z0), (x1, y, z0), (x1, y, z1), (x0, y, z1))


def scene_toml(name, mesh, origin, target, fov, comment):
    return f"""# {name}: {comment} See README.md.
mesh = "{mesh}"

[camera]
origin = {origin}
target = {target}
up = [0.0, 1.0, 0.0]
fov_x_deg = {fov}
width = 256
height = 256

[render]
max_bounces = 5
"""


MTL_DIFFUSE = """newmtl white
Kd 0.7 0.7 0.7

newmtl grey
Kd 0.5 0.5 0.5

newmtl red
Kd 0.6 0.15 0.1

newmtl blue
Kd 0.15 0.25 0.6
"""


def write_scene(name, mesh, mtl_text, toml_text, readme, header):
    d = os.path.join(ROOT, name)
    os.makedirs(d, exist_ok=True)
    mesh.write(os.path.join(d, f"{name}.obj"), f"{name}.mtl", header)
    with open(os.path.join(d, f"{name}.mtl"), "w") as f:
        f.write(mtl_text)
    with open(os.path.join(d, "scene.toml"), "w") as f:
        f.write(toml_text)
    with open(os.path.join(d, "README.md"), "w") as f:
        f.write(readme)


def gap():
    """A 4 x 2.5 x 4 m room; its east wall (x = 4) has a vertical slit 5 cm wide. Behind it a
    1 m deep chamber whose light sits on the wall's back and faces away from the slit: the
    room sees no light directly, only the chamber's far wall through the slit."""
    m = Mesh()
    W, H, D = 4.0, 2.5, 4.0
    floor_y(m, "floor", "grey", 0.0, 0.0, W + 1.0, 0.0, D)
    floor_y(m, "ceiling", "white", H, 0.0, W + 1.0, 0.0, D)
    wall_x(m, "west", "white", 0.0, 0.0, H, 0.0, D)
    wall_z(m, "south", "red", 0.0, 0.0, W + 1.0, 0.0, H)
    wall_z(m, "north", "blue", D, 0.0, W + 1.0, 0.0, H)
    # The slit: z in [1.975, 2.025], y in [0.2, 2.3].
    s0, s1, y0, y1 = 1.975, 2.025, 0.2, 2.3
    wall_x(m, "partition", "white", W, 0.0, H, 0.0, s0)
    wall_x(m, "partition", "white", W, 0.0, H, s1, D)
    wall_x(m, "partition", "white", W, 0.0, y0, s0, s1)
    wall_x(m, "partition", "white", W, y1, H, s0, s1)
    wall_x(m, "chamber_back", "white", W + 1.0, 0.0, H, 0.0, D)
    # The light: on the partition's back, 1 cm off it, facing +x (away from the slit).
    lx = W + 0.01
    m.quad("light", "light", (lx, 1.0, 0.4), (lx, 1.0, 1.0), (lx, 1.6, 1.0), (lx, 1.6, 0.4), facing=(1, 0, 0))
    mtl = MTL_DIFFUSE + "\nnewmtl light\nKd 0 0 0\nKe 1500 1400 1200\n"
    toml = scene_toml(
        "gap",
        "gap.obj",
        "[0.4, 1.5, 3.6]",
        "[4.0, 0.9, 1.2]",
        70.0,
        "a room lit only through a 5 cm slit, by a chamber wall the light faces.",
    )
    readme = """# gap — a room lit through a slit

A 4 × 2.5 × 4 m room (grey floor, white walls, a red south and a blue north wall). Its east
wall (x = 4 m) has a vertical slit 5 cm wide and 2.1 m tall. Behind it, a chamber 1 m deep
holds a 0.6 × 0.6 m light fixed to the back of the slit wall and facing away from it, onto
the chamber's far wall. The room never sees the light: every path that carries light into it
leaves a diffuse surface in the chamber, passes the slit and reaches the room's surfaces, so
a pixel's light arrives after at least two diffuse bounces, through a gap of 5 cm.

**What it tests.** Light that arrives through a narrow opening from a region the camera
cannot see: next-event estimation from the room fails (the light is behind a wall), and
only directions towards the slit carry light — the structure the GA's anchor cones and
the spatial guide are meant to find. Made by `scripts/make_blind_scenes.py`; never tuned on.
"""
    header = "# gap: a room lit only through a 5 cm slit (scripts/make_blind_scenes.py).\n"
    write_scene("gap", m, mtl, toml, readme, header)


def shelf():
    """A room with a glossy floor (Phong 50); a small light under a shelf along the back wall
    shines down onto the floor, hidden from the camera by the shelf."""
    m = Mesh()
    W, H, D = 4.0, 2.5, 4.0
    floor_y(m, "floor", "glossy", 0.0, 0.0, W, 0.0, D)
    floor_y(m, "ceiling", "white", H, 0.0, W, 0.0, D)
    wall_x(m, "west", "red", 0.0, 0.0, H, 0.0, D)
    wall_x(m, "east", "blue", W, 0.0, H, 0.0, D)
    wall_z(m, "back", "white", D, 0.0, W, 0.0, H)
    wall_z(m, "front", "white", 0.0, 0.0, W, 0.0, H)
    # The shelf: a 6 cm thick board at y = 0.45, 0.5 m deep along the back wall.
    m.box_x("shelf", "white", 0.8, 3.2, 0.42, 0.48, D - 0.5, D)
    # The light: 0.5 x 0.08 m, 1 cm under the shelf, facing down.
    ly = 0.41
    m.quad("light", "light", (1.75, ly, D - 0.25), (2.25, ly, D - 0.25), (2.25, ly, D - 0.17), (1.75, ly, D - 0.17), facing=(0, -1, 0))
    mtl = MTL_DIFFUSE + "\nnewmtl glossy\nKd 0.2 0.2 0.2\nKs 0.6 0.6 0.6\nNs 50\n\nnewmtl light\nKd 0 0 0\nKe 200 190 170\n"
    toml = scene_toml(
        "shelf",
        "shelf.obj",
        "[2.0, 1.6, 0.3]",
        "[2.0, 0.3, 3.2]",
        65.0,
        "a glossy floor lit by a small light hidden under a shelf.",
    )
    readme = """# shelf — a glossy floor lit from under a shelf

A 4 × 2.5 × 4 m room whose floor is glossy (Lambertian 0.2 plus a modified-Phong lobe of
albedo 0.6 and exponent 50). A 6 cm board runs along the back wall at 0.45 m, 0.5 m deep;
under it, 1 cm below, a 0.5 × 0.08 m light faces the floor. The camera, above the shelf,
sees the floor and the walls but not the light: the floor's lit patch under the shelf, its
glossy highlights and everything the patch lights by a diffuse bounce.

**What it tests.** A small, bright light reached by next-event estimation only from the
region under the shelf, and a glossy lobe: the rest of the room is lit by light that left
the floor's patch, a caustic-free but strongly directional indirect light. Made by
`scripts/make_blind_scenes.py`; never tuned on.
"""
    header = "# shelf: a glossy floor lit by a light under a shelf (scripts/make_blind_scenes.py).\n"
    write_scene("shelf", m, mtl, toml, readme, header)


def window():
    """A room lit by an emissive quad 1.5 m outside its only window."""
    m = Mesh()
    W, H, D = 4.0, 2.5, 4.0
    floor_y(m, "floor", "grey", 0.0, 0.0, W, 0.0, D)
    floor_y(m, "ceiling", "white", H, 0.0, W, 0.0, D)
    wall_x(m, "west", "white", 0.0, 0.0, H, 0.0, D)
    wall_z(m, "back", "white", D, 0.0, W, 0.0, H)
    wall_z(m, "front", "white", 0.0, 0.0, W, 0.0, H)
    # The east wall with a 1 x 1 m window, z in [1.5, 2.5], y in [1.0, 2.0].
    z0, z1, y0, y1 = 1.5, 2.5, 1.0, 2.0
    wall_x(m, "east", "red", W, 0.0, H, 0.0, z0)
    wall_x(m, "east", "red", W, 0.0, H, z1, D)
    wall_x(m, "east", "red", W, 0.0, y0, z0, z1)
    wall_x(m, "east", "red", W, y1, H, z0, z1)
    # A table in the room.
    m.box_x("table", "blue", 1.2, 2.4, 0.0, 0.75, 1.4, 2.6)
    # The light outside: 3 x 3 m, 1.5 m beyond the window, facing it; nothing else outside.
    lx = W + 1.5
    m.quad("sky", "light", (lx, 0.0, 0.5), (lx, 0.0, 3.5), (lx, 3.0, 3.5), (lx, 3.0, 0.5), facing=(-1, 0, 0))
    mtl = MTL_DIFFUSE + "\nnewmtl light\nKd 0 0 0\nKe 6 6.5 8\n"
    toml = scene_toml(
        "window",
        "window.obj",
        "[3.6, 1.5, 0.3]",
        "[0.5, 0.6, 3.0]",
        75.0,
        "a room lit by an emissive quad outside its window.",
    )
    readme = """# window — a room lit through its window

A 4 × 2.5 × 4 m room with a table and one 1 × 1 m window in its (red) east wall. Outside,
1.5 m from the wall, a 3 × 3 m emitting quad faces the window; nothing else is outside
(rays that leave through the window and miss it find nothing). The camera stands by the
window wall and looks into the room, away from the window.

**What it tests.** The classic interior lit from outside: next-event estimation to the
large light succeeds only through the window, so most of the room is lit by the patch of
floor and wall the window lights. Made by `scripts/make_blind_scenes.py`; never tuned on.
"""
    header = "# window: a room lit through its window (scripts/make_blind_scenes.py).\n"
    write_scene("window", m, mtl, toml, readme, header)


def corridor():
    """An L-shaped corridor, 1.5 m wide and 2.5 m high: 8 m along +z, then 6 m along +x; a
    light at the far end of the second leg, around the corner from the camera."""
    m = Mesh()
    w, H = 1.5, 2.5
    L1, L2 = 8.0, 6.0
    # Leg 1: x in [0, w], z in [0, L1]; leg 2: x in [0, L2], z in [L1 - w, L1].
    floor_y(m, "floor", "grey", 0.0, 0.0, w, 0.0, L1 - w)
    floor_y(m, "floor", "grey", 0.0, 0.0, L2, L1 - w, L1)
    floor_y(m, "ceiling", "white", H, 0.0, w, 0.0, L1 - w)
    floor_y(m, "ceiling", "white", H, 0.0, L2, L1 - w, L1)
    wall_x(m, "left", "white", 0.0, 0.0, H, 0.0, L1)
    wall_x(m, "inner", "white", w, 0.0, H, 0.0, L1 - w)
    wall_z(m, "inner", "white", L1 - w, w, L2, 0.0, H)
    wall_z(m, "outer", "white", L1, 0.0, L2, 0.0, H)
    wall_z(m, "start", "white", 0.0, 0.0, w, 0.0, H)
    wall_x(m, "end", "blue", L2, 0.0, H, L1 - w, L1)
    # The light: 1 x 1 m on the end wall, 2 cm off it, facing back along leg 2.
    lx = L2 - 0.02
    m.quad("light", "light", (lx, 0.75, L1 - 1.25), (lx, 0.75, L1 - 0.25), (lx, 1.75, L1 - 0.25), (lx, 1.75, L1 - 1.25), facing=(-1, 0, 0))
    mtl = MTL_DIFFUSE + "\nnewmtl light\nKd 0 0 0\nKe 60 55 45\n"
    toml = scene_toml(
        "corridor",
        "corridor.obj",
        "[0.75, 1.5, 0.3]",
        "[0.9, 1.2, 8.0]",
        60.0,
        "an L-shaped corridor lit from the far end, around the corner.",
    )
    readme = """# corridor — lit around a corner

An L-shaped corridor 1.5 m wide and 2.5 m high: 8 m straight ahead of the camera, then 6 m
to the right. A 1 × 1 m light on the (blue) wall at the end of the second leg faces back
along it. The camera, at the start of the first leg, looks down it to the corner: the light
is never in view, and only the outer wall of the bend and the end of the first leg see it.

**What it tests.** Light that turns a corner: the first leg is lit by the bend's walls, so
what matters at a vertex there is the direction of the corner, and next-event estimation
to the light fails everywhere in the first leg. Made by `scripts/make_blind_scenes.py`;
never tuned on.
"""
    header = "# corridor: an L-shaped corridor lit around the corner (scripts/make_blind_scenes.py).\n"
    write_scene("corridor", m, mtl, toml, readme, header)


if __name__ == "__main__":
    gap()
    shelf()
    window()
    corridor()
