#!/usr/bin/env python3
"""Generates the test rooms: interiors that are deliberately NOT Cornell boxes, for measuring radray
against converged path-traced references (references/<name>/, made by references/make_reference.py).

    python3 scenes/rooms/generate.py          # deterministic, no network; needs numpy and Pillow

Writes, for each room NAME: scenes/rooms/NAME/scene.obj + scene.mtl (+ textures/), and the radray
scene file scenes/rooms/NAME.toml (camera, 256x256 image; radiosity settings are left to the
quality preset on purpose, so that no room is tuned by hand).

Rooms (unit: metres, y up):
  l_room       an L-shaped room lit by a rectangular emitter on a wall, a table (top + four legs) and
               a cabinet standing against the walls, seen by a slightly rolled camera;
  gap_room     two rooms joined by a narrow door gap; the only light is a ceiling panel in the far
               room and the camera stands in the dark room, so all light it sees came through the gap;
  alcove_hall  a hall with concave corners: two alcoves, a wall niche with a sill, two pillars, a low
               ceiling beam, a ceiling light and coloured walls (colour bleeding);
  textured_box a Cornell-like box with a photo-like texture on the back wall (map_Kd with Kd 1), a
               checker floor (Kd 0.8 x map_Kd) and a JPEG wood texture on the tall block;
  rotunda      an octagonal hall (four walls at 45 degrees, 8-gon floor and ceiling) lit by a lamp on a
               diagonal wall, with a sphere on a turned plinth, a column and a torus: tessellated curved
               objects carrying smooth vertex normals (OBJ vn);
  vault_hall   a barrel-vaulted nave lit by three window-like emitters on a long wall, with ten finely
               tessellated columns, a sphere and a torus: about 40k small triangles, a scene near the
               size where the uniform mesh's matrix stops being the cheaper method;
  stair_hall   a tall hall (5.5 m) with twelve steps along a wall up to a landing 3 m up and a corridor
               leaving it, lit only by a window-like emitter high on a wall (session 21: a shape the
               hierarchy was not developed on).
  fixture_room a plain room lit only by emitters that touch other surfaces at right angles, as exporters
               write light fixtures: a ceiling fixture (a shallow box against the ceiling, bottom and
               sides emitting) and a glowing cube standing in a corner against two walls (session 31:
               the seam where a receiver meets an emitter, which sampling by area got wrong).
  living_room  a room with a bay, lit only by a glowing table lamp standing on a side table and an
               uplighter's shade on a pole, with a sofa turned by 12 degrees (its backrest standing on
               its seat), a coffee table and a bookcase against a wall; written as triangles (session 32:
               objects resting on faces off the grid of the faces they rest on, at turned angles).

Conventions (as every radray scene): right-handed; every polygon is counter-clockwise seen from its
front, and every surface is one-sided and faces into the room (room shells inwards, furniture
outwards). Emitters have Kd 0 and Ke = emitted radiance. All Kd (and Kd x texel) <= 0.8. Faces that
can never be seen (a box's face resting on the floor or against a wall) are left out, so furniture
touches the floor and walls along open edges: exactly where light leaks would show.

Room shells are built from a floor plan of cells on a non-uniform grid: every occupied cell is a
vertical column [y0, y1] (floor and ceiling height), walls are the parts of a cell's side that its
neighbour does not cover. This gives alcoves (columns outside the main plan), niches (raised floor,
lowered ceiling), pillars (empty cells), beams (a row of lower ceilings) and door gaps (a lower
column through a wall), with shared edges conforming wherever the grid lines meet.
"""
import math
import os
import shutil

import numpy as np
from PIL import Image

HERE = os.path.dirname(os.path.abspath(__file__))


# ----------------------------------------------------------------------------------------- geometry
def sub(a, b):
    return (a[0] - b[0], a[1] - b[1], a[2] - b[2])


def add(a, b):
    return (a[0] + b[0], a[1] + b[1], a[2] + b[2])


def cross(a, b):
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


def dot(a, b):
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


def normalize(a):
    n = math.sqrt(dot(a, a))
    return (a[0] / n, a[1] / n, a[2] / n)


class Model:
    """Faces grouped into named objects (one material each), with optional per-corner UVs."""

    def __init__(self):
        self.objects = {}  # name -> (material, [(points, uvs or None)])
        self.order = []
        self.materials = {}  # name -> dict of MTL statements (in order)

    def material(self, name, **kw):
        self.materials[name] = kw

    def face(self, obj, mat, pts, uvs=None, expect_normal=None, normals=None):
        """A planar convex polygon, counter-clockwise seen from its front. `expect_normal`, if given, is
        checked against the winding (guards every hand-written corner order). `normals`, if given, are
        per-corner smooth-shading normals (OBJ `vn`), for tessellated curved objects."""
        if expect_normal is not None:
            n = cross(sub(pts[1], pts[0]), sub(pts[2], pts[0]))
            assert dot(n, expect_normal) > 0, (obj, pts, expect_normal)
        key = obj if obj not in self.objects or self.objects[obj][0] == mat else obj + "_" + mat
        if key not in self.objects:
            self.objects[key] = (mat, [])
            self.order.append(key)
        nrm = [tuple(float(c) for c in n) for n in normals] if normals else None
        self.objects[key][1].append(([tuple(float(c) for c in p) for p in pts], uvs, nrm))

    def rect(self, obj, mat, o, u, v, uv_of=None):
        """Parallelogram o, o+u, o+u+v, o+v; its front normal is u x v."""
        pts = [o, add(o, u), add(add(o, u), v), add(o, v)]
        self.face(obj, mat, pts, [uv_of(p) for p in pts] if uv_of else None, cross(u, v))

    def box(self, obj, mat, lo, hi, omit=(), uv_per_face=False):
        """Axis-aligned box facing outwards; `omit` names faces to leave out: '-x', '+x', '-y', ..."""
        (x0, y0, z0), (x1, y1, z1) = lo, hi
        dx, dy, dz = (x1 - x0, 0, 0), (0, y1 - y0, 0), (0, 0, z1 - z0)
        faces = {
            "-x": ((x0, y0, z0), dz, dy), "+x": ((x1, y0, z0), dy, dz),
            "-y": ((x0, y0, z0), dx, dz), "+y": ((x0, y1, z0), dz, dx),
            "-z": ((x0, y0, z0), dy, dx), "+z": ((x0, y0, z1), dx, dy),
        }
        for k, (o, u, v) in faces.items():
            if k not in omit:
                self.rect(obj, mat, o, u, v, uv_of=None)

    def oriented_box(self, obj, mat, centre, size, angle_deg, omit_bottom=True, uv=False):
        """A box of `size` (x, y, z) standing on y = centre[1], rotated by angle about +y; faces
        outwards; with `uv`, each face maps the whole texture (v up on the sides)."""
        c, s = math.cos(math.radians(angle_deg)), math.sin(math.radians(angle_deg))
        hx, hz = size[0] / 2, size[2] / 2

        def P(x, y, z):
            return (centre[0] + c * x + s * z, centre[1] + y, centre[2] - s * x + c * z)

        H = size[1]
        ring = [P(-hx, 0, -hz), P(hx, 0, -hz), P(hx, 0, hz), P(-hx, 0, hz)]  # counter-clockwise from below
        top = [(p[0], p[1] + H, p[2]) for p in ring]
        quad_uv = [(0, 0), (1, 0), (1, 1), (0, 1)]
        for i in range(4):
            a, b = ring[i], ring[(i + 1) % 4]
            pts = [b, a, top[i], top[(i + 1) % 4]]  # seen from outside: CCW
            mid = ((a[0] + b[0]) / 2 - centre[0], 0, (a[2] + b[2]) / 2 - centre[2])
            self.face(obj, mat, pts, quad_uv if uv else None, expect_normal=mid)
        self.face(obj, mat, [top[0], top[3], top[2], top[1]], quad_uv if uv else None, expect_normal=(0, 1, 0))
        if not omit_bottom:
            self.face(obj, mat, ring, quad_uv if uv else None, expect_normal=(0, -1, 0))

    def triangle_count(self):
        return sum(len(f[0]) - 2 for _, fs in self.objects.values() for f in fs)

    def write(self, folder, header, triangulate=False):
        """scene.obj + scene.mtl in `folder`; with `triangulate`, every polygon is written as a fan of
        triangles, as most exporters write meshes."""
        os.makedirs(folder, exist_ok=True)
        vid, vlist, tid, tlist, nid, nlist = {}, [], {}, [], {}, []

        def vi(p):
            k = tuple(round(c, 6) for c in p)
            if k not in vid:
                vid[k] = len(vlist) + 1
                vlist.append(k)
            return vid[k]

        def ti(t):
            k = (round(t[0], 6), round(t[1], 6))
            if k not in tid:
                tid[k] = len(tlist) + 1
                tlist.append(k)
            return tid[k]

        def ni(n):
            k = tuple(round(c, 6) for c in n)
            if k not in nid:
                nid[k] = len(nlist) + 1
                nlist.append(k)
            return nid[k]

        body = []
        for name in self.order:
            mat, faces = self.objects[name]
            body.append("\no %s\ng %s\nusemtl %s" % (name, name, mat))
            fans = [([pts[0], pts[k], pts[k + 1]], uvs and [uvs[0], uvs[k], uvs[k + 1]],
                     nrm and [nrm[0], nrm[k], nrm[k + 1]]) for pts, uvs, nrm in faces for k in range(1, len(pts) - 1)]
            for pts, uvs, nrm in (fans if triangulate else faces):
                if nrm:
                    body.append("f " + " ".join("%d//%d" % (vi(p), ni(n)) for p, n in zip(pts, nrm)))
                elif uvs:
                    body.append("f " + " ".join("%d/%d" % (vi(p), ti(t)) for p, t in zip(pts, uvs)))
                else:
                    body.append("f " + " ".join(str(vi(p)) for p in pts))
        with open(os.path.join(folder, "scene.obj"), "w") as f:
            f.write("# %s\n# generated by scenes/rooms/generate.py (do not edit by hand); metres, CCW fronts\n"
                    % header)
            f.write("mtllib scene.mtl\n")
            for p in vlist:
                f.write("v %.6f %.6f %.6f\n" % p)
            for t in tlist:
                f.write("vt %.6f %.6f\n" % t)
            for n in nlist:
                f.write("vn %.6f %.6f %.6f\n" % n)
            f.write("\n".join(body) + "\n")
        with open(os.path.join(folder, "scene.mtl"), "w") as f:
            f.write("# Kd diffuse reflectance (linear RGB), Ke emitted radiance; map_Kd is multiplied by Kd,\n"
                    "# 8-bit textures are sRGB-encoded. generated by scenes/rooms/generate.py\n")
            for name, m in self.materials.items():
                f.write("\nnewmtl %s\n" % name)
                kd = m.get("Kd", (0, 0, 0))
                f.write("Kd %g %g %g\n" % tuple(kd))
                f.write("Ks 0 0 0\n")
                f.write("Ke %g %g %g\n" % tuple(m.get("Ke", (0, 0, 0))))
                if "map_Kd" in m:
                    f.write("map_Kd %s\n" % m["map_Kd"])
                f.write("Ni 1\nd 1\nillum 1\n")
                assert max(kd) <= 0.8 or "map_Kd" in m, name


def shell(model, xs, zs, column, mat_floor, mat_ceil, mat_wall, uv_of=None):
    """Room shell from a floor plan. column(i, j) -> None (solid) or (y0, y1) of cell
    [xs[i], xs[i+1]] x [zs[j], zs[j+1]]. mat_floor/mat_ceil(i, j) -> material; mat_wall(i, j, side, y0, y1)
    -> list of (y0, y1, material) bands for the wall of cell (i, j) on `side` ('-x', '+x', '-z', '+z', the
    side of the cell it stands on) over [y0, y1]. uv_of(material, point) -> (u, v) or None."""
    nx, nz = len(xs) - 1, len(zs) - 1

    def col(i, j):
        return column(i, j) if 0 <= i < nx and 0 <= j < nz else None

    def uvf(mat):
        if uv_of is None:
            return None
        return (lambda p: uv_of(mat, p)) if uv_of(mat, (0, 0, 0)) is not None else None

    for i in range(nx):
        for j in range(nz):
            c = col(i, j)
            if c is None:
                continue
            y0, y1 = c
            x0, x1, z0, z1 = xs[i], xs[i + 1], zs[j], zs[j + 1]
            m = mat_floor(i, j)
            model.rect("floor", m, (x0, y0, z0), (0, 0, z1 - z0), (x1 - x0, 0, 0), uvf(m))
            m = mat_ceil(i, j)
            model.rect("ceiling", m, (x0, y1, z0), (x1 - x0, 0, 0), (0, 0, z1 - z0), uvf(m))
            for side, nb in (("-x", col(i - 1, j)), ("+x", col(i + 1, j)), ("-z", col(i, j - 1)), ("+z", col(i, j + 1))):
                # the parts of [y0, y1] that the neighbour column does not cover
                gaps = [(y0, y1)] if nb is None else [(y0, min(y1, nb[0])), (max(y0, nb[1]), y1)]
                for g0, g1 in gaps:
                    if g1 - g0 <= 1e-9:
                        continue
                    for b0, b1, m in mat_wall(i, j, side, g0, g1):
                        h = (0, b1 - b0, 0)
                        if side == "-x":  # wall at x0, faces +x
                            model.rect("walls", m, (x0, b0, z0), h, (0, 0, z1 - z0), uvf(m))
                        elif side == "+x":  # wall at x1, faces -x
                            model.rect("walls", m, (x1, b0, z0), (0, 0, z1 - z0), h, uvf(m))
                        elif side == "-z":  # wall at z0, faces +z
                            model.rect("walls", m, (x0, b0, z0), (x1 - x0, 0, 0), h, uvf(m))
                        else:  # wall at z1, faces -z
                            model.rect("walls", m, (x0, b0, z1), h, (x1 - x0, 0, 0), uvf(m))


def table(model, x0, x1, z0, z1, height, mat, top=0.04, leg=0.05, inset=0.04):
    """A table: a top slab (all six faces) on four legs standing on the floor (no bottom/top faces)."""
    model.box("table_top", mat, (x0, height - top, z0), (x1, height, z1))
    for lx in (x0 + inset, x1 - inset - leg):
        for lz in (z0 + inset, z1 - inset - leg):
            model.box("table_legs", mat, (lx, 0.0, lz), (lx + leg, height - top, lz + leg), omit=("-y", "+y"))


def chair(model, x0, z0, size, seat_h, back_h, mat, back_side):
    """A chair standing on the floor: seat slab, four legs, and a back slab rising from the seat on the
    `back_side` ('-z' or '+z') edge."""
    leg, t = 0.04, 0.04
    x1, z1 = x0 + size, z0 + size
    model.box("chairs", mat, (x0, seat_h - t, z0), (x1, seat_h, z1))
    for lx in (x0, x1 - leg):
        for lz in (z0, z1 - leg):
            model.box("chairs", mat, (lx, 0.0, lz), (lx + leg, seat_h - t, lz + leg), omit=("-y", "+y"))
    bz = (z0, z0 + t) if back_side == "-z" else (z1 - t, z1)
    model.box("chairs", mat, (x0, seat_h, bz[0]), (x1, back_h, bz[1]), omit=("-y",))


def rolled_up(eye, look_at, roll_deg):
    """The camera up vector: world +y made orthogonal to the view and rotated by roll_deg about it."""
    f = normalize(sub(look_at, eye))
    r = normalize(cross(f, (0, 1, 0)))
    u = cross(r, f)
    c, s = math.cos(math.radians(roll_deg)), math.sin(math.radians(roll_deg))
    return tuple(round(c * u[k] + s * r[k], 6) for k in range(3))


def write_toml(name, title, cam, extra=""):
    with open(os.path.join(HERE, name + ".toml"), "w") as f:
        f.write("# %s\n" % title)
        f.write("# Geometry: scenes/rooms/%s/, generated by scenes/rooms/generate.py. Reference:\n"
                "# references/%s/reference.exr (Mitsuba 3, path tracer). Radiosity settings are left to the\n"
                "# quality preset on purpose: these rooms measure radray as a user would run it.\n" % (name, name))
        f.write("[camera]\neye = [%s]\nlook_at = [%s]\nup = [%s]\nvfov_deg = %s\n\n" % (
            ", ".join(repr(float(c)) for c in cam["eye"]), ", ".join(repr(float(c)) for c in cam["look_at"]),
            ", ".join(repr(float(c)) for c in cam["up"]), repr(float(cam["vfov_deg"]))))
        f.write("[image]\nwidth = 256\nheight = 256\nsamples_per_pixel = 16\n\n")
        f.write(extra)
        f.write("[[mesh]]\nobj = \"%s/scene.obj\"\n" % name)


# -------------------------------------------------------------------------------------------- rooms
WALL = (0.72, 0.70, 0.66)
CEIL = (0.78, 0.78, 0.76)


def room_model(floor_kd, wood=True):
    """A model with the materials every room shares: white walls and ceiling, its floor, and wood."""
    m = Model()
    m.material("wall", Kd=WALL)
    m.material("ceiling", Kd=CEIL)
    m.material("floor", Kd=floor_kd)
    if wood:
        m.material("wood", Kd=(0.50, 0.33, 0.18))
    return m


def l_room():
    m = room_model((0.45, 0.32, 0.20))
    m.material("cabinet", Kd=(0.25, 0.38, 0.60))
    m.material("lamp", Kd=(0, 0, 0), Ke=(24.0, 21.6, 18.0))
    xs = [0.0, 1.5, 3.0, 4.5, 6.0]
    zs = [0.0, 1.0, 2.0, 3.0, 4.5, 6.0]
    H = 2.7

    def column(i, j):
        return (0.0, H) if zs[j] < 3.0 or xs[i] < 3.0 else None

    def walls(i, j, side, y0, y1):
        if side == "-x" and i == 0 and j == 1:  # the wall lamp: x = 0, z in [1, 2], y in [1.3, 1.9]
            return [(y0, 1.3, "wall"), (1.3, 1.9, "lamp"), (1.9, y1, "wall")]
        return [(y0, y1, "wall")]

    shell(m, xs, zs, column, lambda i, j: "floor", lambda i, j: "ceiling", walls)
    table(m, 0.35, 1.55, 3.9, 4.7, 0.75, "wood")
    chair(m, 0.7, 4.8, 0.44, 0.45, 0.92, "wood", "+z")
    chair(m, 0.75, 3.4, 0.44, 0.45, 0.92, "wood", "-z")
    # a tall cabinet with its back against the end wall z = 6 of the second arm
    m.box("cabinet", "cabinet", (1.9, 0.0, 5.45), (2.9, 1.9, 6.0), omit=("-y", "+z"))
    # a low sideboard against the wall z = 0, under nothing, touching the corner x = 6
    m.box("sideboard", "wood", (4.4, 0.0, 0.0), (6.0, 0.8, 0.45), omit=("-y", "-z", "+x"))
    m.write(os.path.join(HERE, "l_room"), "l_room: L-shaped room, wall lamp, table, chairs, cabinet, sideboard")
    eye, look = (5.7, 1.6, 0.3), (0.5, 0.8, 4.5)
    cam = {"eye": eye, "look_at": look, "up": rolled_up(eye, look, 7.0), "vfov_deg": 65.0}
    write_toml("l_room", "L-shaped room (6 x 6 m plan, 2.7 m high) lit by a lamp on a wall; a table with two "
               "chairs and a cabinet near the walls;\n# the camera is rolled by 7 degrees.", cam)
    return m, cam


def gap_room():
    m = room_model((0.50, 0.48, 0.45))
    m.material("cabinet", Kd=(0.55, 0.25, 0.20))
    m.material("lamp", Kd=(0, 0, 0), Ke=(250.0, 250.0, 250.0))
    xs = [0.0, 1.0, 2.0, 2.8, 3.3, 4.0]
    zs = [0.0, 2.0, 4.0, 4.2, 6.0, 7.0, 8.0]
    H = 2.6

    def column(i, j):
        if j == 2:  # the dividing wall, 0.2 m thick; the door gap is x in [2.8, 3.3], 2.0 m high
            return (0.0, 2.0) if i == 3 else None
        return (0.0, H)

    shell(m, xs, zs, column, lambda i, j: "floor",
          lambda i, j: "lamp" if (i, j) == (1, 4) else "ceiling",
          lambda i, j, side, y0, y1: [(y0, y1, "wall")])
    m.box("cabinet", "cabinet", (0.0, 0.0, 2.4), (0.5, 1.2, 3.4), omit=("-y", "-x"))  # dark room, on wall x=0
    m.box("crate", "wood", (3.0, 0.0, 5.0), (3.8, 0.6, 5.8), omit=("-y",))  # lit room, near the door
    table(m, 1.2, 2.2, 0.0 + 0.6, 1.3, 0.72, "wood")  # dark room
    m.write(os.path.join(HERE, "gap_room"), "gap_room: a dark room lit through a 0.5 m door gap")
    eye, look = (0.5, 1.5, 0.3), (2.9, 1.0, 4.2)
    cam = {"eye": eye, "look_at": look, "up": (0.0, 1.0, 0.0), "vfov_deg": 60.0}
    write_toml("gap_room", "Two rooms joined by a 0.5 m x 2 m door gap; the only light is a ceiling panel in "
               "the far room and\n# the camera stands in the dark room: every light path it sees passes "
               "the gap.", cam)
    return m, cam


def alcove_hall():
    m = room_model((0.48, 0.45, 0.40), wood=False)
    m.material("red", Kd=(0.63, 0.12, 0.08))
    m.material("green", Kd=(0.15, 0.45, 0.12))
    m.material("blue", Kd=(0.15, 0.20, 0.55))
    m.material("yellow", Kd=(0.70, 0.60, 0.15))
    m.material("lamp", Kd=(0, 0, 0), Ke=(16.0, 16.0, 14.5))
    xs = [-0.4, 0.0, 1.0, 1.8, 2.2, 2.5, 3.5, 3.8, 4.2, 5.0, 6.0]
    zs = [0.0, 1.2, 2.0, 2.4, 3.0, 3.3, 5.0, 5.7]
    H = 3.0

    def column(i, j):
        x0, z0 = xs[i], zs[j]
        if x0 < 0:  # the niche in the left wall: 0.4 m deep, z in [2, 3], sill at 0.9 m, top at 1.9 m
            return (0.9, 1.9) if 2.0 <= z0 < 3.0 else None
        if z0 >= 5.0:  # the two alcoves in the back wall: 0.7 m deep, 2.3 m high
            return (0.0, 2.3) if (1.0 <= x0 < 2.2) or (3.8 <= x0 < 5.0) else None
        if z0 == 2.0 and (x0 == 1.8 or x0 == 3.8):  # two pillars, 0.4 x 0.4 m
            return None
        if z0 == 3.0:  # the ceiling beam, 0.3 m wide, 0.4 m deep
            return (0.0, H - 0.4)
        return (0.0, H)

    def walls(i, j, side, y0, y1):
        x0, z0 = xs[i], zs[j]
        if x0 < 0:
            return [(y0, y1, "yellow")]
        if z0 >= 5.0 and side == "+z":
            return [(y0, y1, "blue")]
        if side == "-x" and i == 1:
            return [(y0, y1, "red")]
        if side == "+x" and i == len(xs) - 2:
            return [(y0, y1, "green")]
        return [(y0, y1, "wall")]

    shell(m, xs, zs, column, lambda i, j: "floor",
          lambda i, j: "lamp" if (xs[i], zs[j]) == (2.5, 1.2) else "ceiling", walls)
    # a bench against the right (green) wall, near the front
    m.box("bench", "wall", (5.5, 0.0, 0.6), (6.0, 0.45, 2.0), omit=("-y", "+x"))
    m.write(os.path.join(HERE, "alcove_hall"), "alcove_hall: alcoves, niche, pillars, beam, coloured walls")
    eye, look = (5.6, 1.7, 0.3), (1.0, 1.0, 4.5)
    cam = {"eye": eye, "look_at": look, "up": (0.0, 1.0, 0.0), "vfov_deg": 68.0}
    write_toml("alcove_hall", "A 6 x 5 m hall, 3 m high, with concave corners everywhere: two alcoves, a niche "
               "with a sill, two\n# pillars, a low ceiling beam; a ceiling light; red, green, blue and "
               "yellow walls for colour bleeding.", cam)
    return m, cam


def stair_hall():
    m = room_model((0.42, 0.40, 0.38))
    m.material("stone", Kd=(0.62, 0.60, 0.55))
    m.material("plaster", Kd=(0.70, 0.55, 0.42))
    m.material("window", Kd=(0, 0, 0), Ke=(30.0, 27.0, 22.0))
    # 12 steps of 0.3 m x 0.25 m along the left wall (x in [0, 1.1]) rise from z = 1.0 to the landing
    # (z in [4.6, 6.0], 3 m up, across the hall); a 1 m wide upper corridor leaves the landing at the back.
    steps = [round(1.0 + 0.3 * k, 6) for k in range(13)]  # 1.0 ... 4.6
    xs = [0.0, 1.1, 2.0, 3.0, 5.0]
    zs = [0.0] + steps + [6.0, 7.5, 9.0]
    H = 5.5

    def column(i, j):
        z0 = zs[j]
        if z0 >= 6.0:  # the upper corridor, x in [2, 3], 2 m high
            return (3.0, 5.0) if xs[i] == 2.0 else None
        if z0 >= 4.6:  # the landing
            return (3.0, H)
        if i == 0 and z0 >= 1.0:  # the stairs
            return (0.25 * (steps.index(z0) + 1), H)
        return (0.0, H)

    def walls(i, j, side, y0, y1):
        z0 = zs[j]
        if side == "+x" and i == len(xs) - 2 and 1.6 <= z0 < 3.4:  # the window, high on the right wall
            return [(y0, 3.4, "wall"), (3.4, 4.6, "window"), (4.6, y1, "wall")]
        if i == 0 and z0 < 4.6 and side == "-x":
            return [(y0, y1, "plaster")]
        if side == "-x" and xs[i] == 1.1 and 1.0 <= z0 < 4.6:  # the staircase's open side
            return [(y0, y1, "stone")]
        return [(y0, y1, "wall")]

    def floor_mat(i, j):
        return "stone" if i == 0 and 1.0 <= zs[j] < 4.6 else "floor"

    shell(m, xs, zs, column, floor_mat, lambda i, j: "ceiling", walls)
    table(m, 2.6, 3.8, 1.6, 2.5, 0.75, "wood")
    m.box("chest", "wood", (3.6, 3.0, 5.4), (4.8, 3.6, 6.0), omit=("-y", "+z"))  # on the landing, at the back wall
    m.write(os.path.join(HERE, "stair_hall"), "stair_hall: a tall hall with stairs, a landing, an upper corridor")
    eye, look = (4.6, 1.6, 0.3), (1.2, 2.7, 5.5)
    cam = {"eye": eye, "look_at": look, "up": rolled_up(eye, look, 0.0), "vfov_deg": 72.0}
    write_toml("stair_hall", "A tall hall (5 x 6 m, 5.5 m high) with twelve steps along a wall up to a landing "
               "3 m up and a corridor\n# leaving it; the only light is a window-like emitter high on the "
               "right wall, out of view.", cam)
    return m, cam


# ----------------------------------------------------------------------------------------- textures
def srgb_encode(lin):
    lin = np.clip(lin, 0.0, 1.0)
    return np.where(lin <= 0.0031308, 12.92 * lin, 1.055 * np.power(lin, 1 / 2.4) - 0.055)


def to8(lin):
    """Linear RGB in [0, 0.8] -> sRGB-encoded 8-bit (the cap keeps every texel albedo <= 0.8)."""
    return np.round(srgb_encode(np.clip(lin, 0.0, 0.8)) * 255.0).astype(np.uint8)


def smooth_noise(rng, n, octaves=5):
    """Deterministic value noise on an n x n grid in [0, 1], periodic, sum of octaves."""
    out = np.zeros((n, n))
    amp, tot = 1.0, 0.0
    for o in range(octaves):
        k = 4 * 2 ** o
        g = rng.random((k, k))
        t = np.arange(n) * k / n
        i0 = np.floor(t).astype(int)
        f = t - i0
        f = f * f * (3 - 2 * f)
        i1 = (i0 + 1) % k
        rows = g[i0][:, i0] * (1 - f)[None, :] + g[i0][:, i1] * f[None, :]
        rows1 = g[i1][:, i0] * (1 - f)[None, :] + g[i1][:, i1] * f[None, :]
        out += amp * (rows * (1 - f)[:, None] + rows1 * f[:, None])
        tot += amp
        amp *= 0.5
    return out / tot


def photo_texture(n=256):
    """A photo-like landscape (linear RGB): sky gradient, sun, clouds, two mountain ridges, a lake with
    the sky's reflection, a meadow and a tree. Row 0 is the top of the picture."""
    rng = np.random.default_rng(20261201)
    y, x = np.mgrid[0:n, 0:n] / (n - 1.0)
    img = np.zeros((n, n, 3))
    sky = np.stack([0.20 + 0.45 * y, 0.35 + 0.40 * y, 0.75 + 0.05 * y], axis=-1)
    clouds = np.clip(smooth_noise(rng, n) * 1.8 - 0.9, 0, 1)[..., None]
    sky = sky * (1 - 0.8 * clouds) + 0.78 * clouds
    sun = np.exp(-((x - 0.72) ** 2 + (y - 0.2) ** 2) / 0.002)[..., None]
    sky = sky + sun * np.array([0.6, 0.5, 0.2])
    img[:] = sky
    ridge_n = smooth_noise(rng, n)[0]
    ridge1 = 0.42 + 0.10 * np.sin(x[0] * 7.0 + 1.0) + 0.06 * (ridge_n - 0.5)
    ridge2 = 0.52 + 0.05 * np.sin(x[0] * 13.0) + 0.05 * (smooth_noise(rng, n)[3] - 0.5)
    rock = smooth_noise(rng, n)
    far = y > ridge1[None, :]
    img[far] = (np.array([0.30, 0.32, 0.42]) * (0.8 + 0.4 * rock[..., None]))[far]
    snow = far & (y < ridge1[None, :] + 0.03)
    img[snow] = np.array([0.78, 0.78, 0.80])
    near = y > ridge2[None, :]
    img[near] = (np.array([0.12, 0.22, 0.10]) * (0.7 + 0.6 * rock[..., None]))[near]
    lake = (y > 0.62) & (y < 0.74)
    refl = img[np.clip((2 * 0.62 * (n - 1) - np.arange(n) * 1.0).astype(int), 0, n - 1)][:, :]
    img[lake] = (0.55 * refl + np.array([0.02, 0.06, 0.10]))[lake]
    grass = smooth_noise(rng, n, 6)
    meadow = y >= 0.74
    img[meadow] = (np.array([0.18, 0.40, 0.08]) * (0.6 + 0.8 * grass[..., None]))[meadow]
    trunk = (np.abs(x - 0.22) < 0.012) & (y > 0.55) & (y < 0.82)
    img[trunk] = np.array([0.20, 0.12, 0.06])
    crown = ((x - 0.22) ** 2 / 0.006 + (y - 0.52) ** 2 / 0.012) < 1
    img[crown] = (np.array([0.06, 0.20, 0.05]) * (0.6 + 0.8 * grass[..., None]))[crown]
    return img


def checker_texture(n=256, squares=8):
    y, x = np.mgrid[0:n, 0:n] * squares // n
    light = ((x + y) % 2 == 0)[..., None]
    return np.where(light, np.array([0.75, 0.72, 0.66]), np.array([0.05, 0.05, 0.06]))


def wood_texture(n=256):
    rng = np.random.default_rng(7)
    y, x = np.mgrid[0:n, 0:n] / float(n)
    wobble = smooth_noise(rng, n, 4)
    rings = 0.5 + 0.5 * np.sin(2 * np.pi * (x * 9.0 + 1.5 * wobble + 0.3 * y))
    return np.array([0.45, 0.26, 0.11])[None, None, :] * (0.55 + 0.45 * rings[..., None])


def textured_box():
    m = Model()
    folder = os.path.join(HERE, "textured_box")
    tex = os.path.join(folder, "textures")
    os.makedirs(tex, exist_ok=True)
    Image.fromarray(to8(photo_texture())).save(os.path.join(tex, "photo.png"), optimize=False)
    Image.fromarray(to8(checker_texture())).save(os.path.join(tex, "checker.png"), optimize=False)
    Image.fromarray(to8(wood_texture())).save(os.path.join(tex, "wood.jpg"), quality=92, subsampling=0)
    m.material("white", Kd=(0.73, 0.71, 0.68))
    m.material("red", Kd=(0.63, 0.065, 0.05))
    m.material("green", Kd=(0.14, 0.45, 0.091))
    m.material("photo", Kd=(1, 1, 1), map_Kd="textures/photo.png")  # as exporters write it
    m.material("checker", Kd=(0.8, 0.8, 0.8), map_Kd="textures/checker.png")
    m.material("wood", Kd=(0.7, 0.7, 0.7), map_Kd="textures/wood.jpg")
    m.material("lamp", Kd=(0, 0, 0), Ke=(18.0, 15.0, 10.5))
    S = 2.0
    xs = [0.0, 0.75, 1.25, 2.0]
    zs = [0.0, 0.75, 1.25, 2.0]

    def walls(i, j, side, y0, y1):
        if side == "-z":
            return []  # open front, as in the Cornell box
        if side == "+z":
            return [(y0, y1, "photo")]
        return [(y0, y1, "green" if side == "-x" else "red")]  # image-right is -x: red on the left

    def uv_of(mat, p):
        if mat == "photo":  # back wall z = 2, seen from -z: image-right is -x
            return ((S - p[0]) / S, p[1] / S)
        if mat == "checker":  # floor: u along -x, v along +z (far side at the top of the image)
            return ((S - p[0]) / S, p[2] / S)
        return None

    shell(m, xs, zs, lambda i, j: (0.0, S), lambda i, j: "checker",
          lambda i, j: "lamp" if (i, j) == (1, 1) else "white", walls, uv_of)
    m.oriented_box("short_block", "white", (0.65, 0.0, 0.70), (0.6, 0.6, 0.6), -17.0)
    m.oriented_box("tall_block", "wood", (1.32, 0.0, 1.30), (0.6, 1.2, 0.6), 17.0, uv=True)
    m.write(folder, "textured_box: Cornell-like box with a photo back wall, checker floor, wood block")
    cam = {"eye": (1.0, 1.0, -2.9), "look_at": (1.0, 1.0, 0.0), "up": (0.0, 1.0, 0.0), "vfov_deg": 39.3}
    write_toml("textured_box", "A Cornell-like 2 m box, open at the front, with textures made by "
               "generate.py: a photo-like\n# picture on the back wall (Kd 1 x map_Kd), a checker floor "
               "(Kd 0.8 x map_Kd) and a wood JPEG on the tall block.", cam)
    return m, cam


# ------------------------------------------------------------------------------- curved objects
def oriented_face(model, obj, mat, pts, want, normals=None):
    """A convex polygon whose corner order is chosen so that its front faces `want`."""
    n = cross(sub(pts[1], pts[0]), sub(pts[2], pts[0]))
    if dot(n, want) < 0:
        pts = pts[::-1]
        normals = normals[::-1] if normals else None
    model.face(obj, mat, pts, expect_normal=want, normals=normals)


def surface_of_revolution(model, obj, mat, point_normal, nu, nv):
    """A tessellated smooth surface (u around, v along) with per-corner normals: point_normal(u, v) ->
    (point, outward unit normal) for u, v in [0, 1]; quads, or triangles where two corners coincide
    (the poles of a sphere). Fronts face along the normal."""
    for i in range(nu):
        for j in range(nv):
            corners = [point_normal(i / nu, j / nv), point_normal((i + 1) / nu, j / nv),
                       point_normal((i + 1) / nu, (j + 1) / nv), point_normal(i / nu, (j + 1) / nv)]
            pts, nrm = [], []
            for p, n in corners:
                if not pts or max(abs(a - b) for a, b in zip(p, pts[-1])) > 1e-9:
                    pts.append(p)
                    nrm.append(n)
            if max(abs(a - b) for a, b in zip(pts[0], pts[-1])) <= 1e-9:
                pts.pop()
                nrm.pop()
            if len(pts) < 3:
                continue
            mean_n = tuple(sum(n[k] for n in nrm) for k in range(3))
            oriented_face(model, obj, mat, pts, mean_n, nrm)


def sphere(model, obj, mat, centre, radius, nu=32, nv=16):
    def pn(u, v):
        th, ph = 2 * math.pi * u, math.pi * v
        n = (math.sin(ph) * math.cos(th), math.cos(ph), math.sin(ph) * math.sin(th))
        return add(centre, tuple(radius * c for c in n)), n
    surface_of_revolution(model, obj, mat, pn, nu, nv)


def cylinder(model, obj, mat, base, radius, height, nu=24):
    """An uncapped vertical cylinder (a column from floor to ceiling needs no caps)."""
    def pn(u, v):
        th = 2 * math.pi * u
        n = (math.cos(th), 0.0, math.sin(th))
        return (base[0] + radius * n[0], base[1] + height * v, base[2] + radius * n[2]), n
    surface_of_revolution(model, obj, mat, pn, nu, 1)


def torus(model, obj, mat, centre, major, minor, nu=32, nv=16):
    """A torus lying flat (axis +y)."""
    def pn(u, v):
        th, ph = 2 * math.pi * u, 2 * math.pi * v
        n = (math.cos(ph) * math.cos(th), math.sin(ph), math.cos(ph) * math.sin(th))
        ring = (major * math.cos(th), 0.0, major * math.sin(th))
        return add(centre, add(ring, tuple(minor * c for c in n))), n
    surface_of_revolution(model, obj, mat, pn, nu, nv)


def rotunda():
    m = room_model((0.42, 0.40, 0.38), wood=False)
    m.material("orange", Kd=(0.70, 0.32, 0.10))
    m.material("stone", Kd=(0.62, 0.60, 0.56))
    m.material("blue", Kd=(0.15, 0.25, 0.60))
    m.material("plinth", Kd=(0.30, 0.45, 0.30))
    m.material("lamp", Kd=(0, 0, 0), Ke=(26.0, 23.0, 19.0))
    R, H = 3.0, 3.0  # wall midpoints at R, 3 m high
    rc = R / math.cos(math.pi / 8)
    corner = [(rc * math.cos(math.pi / 8 + k * math.pi / 4), rc * math.sin(math.pi / 8 + k * math.pi / 4))
              for k in range(8)]
    oriented_face(m, "floor", "floor", [(x, 0.0, z) for x, z in corner], (0, 1, 0))
    oriented_face(m, "ceiling", "ceiling", [(x, H, z) for x, z in corner], (0, -1, 0))
    lamp_wall, y0, y1, half = 1, 1.5, 2.1, 0.6  # the wall at azimuth 45 degrees; lamp 1.2 x 0.6 m
    for k in range(8):
        (ax, az), (bx, bz) = corner[k], corner[(k + 1) % 8]
        inward = (-(ax + bx) / 2, 0.0, -(az + bz) / 2)

        def band(t0, t1, lo, hi, mat):
            pa = (ax + (bx - ax) * t0, az + (bz - az) * t0)
            pb = (ax + (bx - ax) * t1, az + (bz - az) * t1)
            oriented_face(m, "walls", mat, [(pa[0], lo, pa[1]), (pb[0], lo, pb[1]), (pb[0], hi, pb[1]),
                                            (pa[0], hi, pa[1])], inward)

        if k != lamp_wall:
            band(0.0, 1.0, 0.0, H, "wall")
            continue
        w = math.hypot(bx - ax, bz - az)
        t0, t1 = 0.5 - half / w, 0.5 + half / w
        band(0.0, 1.0, 0.0, y0, "wall")
        band(0.0, t0, y0, y1, "wall")
        band(t0, t1, y0, y1, "lamp")
        band(t1, 1.0, y0, y1, "wall")
        band(0.0, 1.0, y1, H, "wall")
    # a plinth turned 30 degrees carrying a smooth sphere, a column, a torus on the floor
    m.oriented_box("plinth", "plinth", (0.6, 0.0, -0.4), (0.6, 0.5, 0.6), 30.0)
    sphere(m, "sphere", "orange", (0.6, 0.95, -0.4), 0.45)
    cylinder(m, "column", "stone", (-1.5, 0.0, 1.5), 0.25, H)
    torus(m, "torus", "blue", (-0.9, 0.12, -0.3), 0.4, 0.12)
    m.write(os.path.join(HERE, "rotunda"), "rotunda: octagonal hall, wall lamp, smooth sphere, column, torus")
    eye, look = (0.9, 1.7, -2.6), (-0.6, 0.8, 0.9)
    cam = {"eye": eye, "look_at": look, "up": (0.0, 1.0, 0.0), "vfov_deg": 66.0}
    write_toml("rotunda", "An octagonal hall (walls at 45 degrees, 3 m high) lit by a lamp on a diagonal "
               "wall; a smooth sphere\n# (OBJ vn) on a turned plinth, a column and a torus: curved, "
               "tessellated objects with shading normals.", cam)
    return m, cam


def vault_hall():
    """A barrel-vaulted nave (6 x 12 m, walls 3 m, semicircular vault to 6 m) lit by three window-like
    emitters on one long wall, with ten finely tessellated columns carrying capitals, a sphere on a
    pedestal and a torus: about 40k triangles, most of them small (as exported meshes are), so that
    the uniform mesh's matrix is near the size where `auto` leaves it for the hierarchy."""
    m = room_model((0.45, 0.42, 0.38), wood=False)
    m.material("stone", Kd=(0.62, 0.60, 0.56))
    m.material("orange", Kd=(0.70, 0.32, 0.10))
    m.material("blue", Kd=(0.15, 0.25, 0.60))
    m.material("window", Kd=(0, 0, 0), Ke=(9.0, 8.6, 7.8))
    W, L, H, arc = 3.0, 12.0, 3.0, 64  # half width, length, spring height, vault segments
    oriented_face(m, "floor", "floor", [(-W, 0, 0), (W, 0, 0), (W, 0, L), (-W, 0, L)], (0, 1, 0))
    # the vault: a half cylinder of radius W about the axis (0, H, z), facing the axis (OBJ vn)
    def vault(u, v):
        th = math.pi * u
        out = (math.cos(th), math.sin(th), 0.0)
        return (W * out[0], H + W * out[1], L * v), (-out[0], -out[1], 0.0)
    surface_of_revolution(m, "vault", "ceiling", vault, arc, 24)
    # end walls: the rectangle below the spring line and the lunette under the arc, conforming to it
    arc_pts = [(W * math.cos(math.pi * i / arc), H + W * math.sin(math.pi * i / arc)) for i in range(arc + 1)]
    for z, facing in ((0.0, (0, 0, 1)), (L, (0, 0, -1))):
        oriented_face(m, "end_walls", "wall", [(-W, 0, z), (W, 0, z), (W, H, z), (-W, H, z)], facing)
        for i in range(arc):
            (xa, ya), (xb, yb) = arc_pts[i], arc_pts[i + 1]
            oriented_face(m, "end_walls", "wall", [(0.0, H, z), (xa, ya, z), (xb, yb, z)], facing)
    # the long walls; three windows (1.0 x 1.2 m) on the one at x = +W
    windows = [(2.5, 3.5), (5.5, 6.5), (8.5, 9.5)]
    y0, y1 = 1.2, 2.4
    oriented_face(m, "walls", "wall", [(-W, 0, 0), (-W, 0, L), (-W, H, L), (-W, H, 0)], (1, 0, 0))
    def band(z0, z1, lo, hi, mat):
        oriented_face(m, "walls", mat, [(W, lo, z0), (W, lo, z1), (W, hi, z1), (W, hi, z0)], (-1, 0, 0))
    band(0.0, L, 0.0, y0, "wall")
    band(0.0, L, y1, H, "wall")
    edges = [0.0] + [z for w in windows for z in w] + [L]
    for k in range(len(edges) - 1):
        band(edges[k], edges[k + 1], y0, y1, "window" if k % 2 == 1 else "wall")
    # ten columns (r 0.18 m, 2.8 m, 128 x 12 facets) under 0.5 m capitals
    for x in (-1.8, 1.8):
        for z in (2.0, 4.0, 6.0, 8.0, 10.0):
            def column(u, v, x=x, z=z):
                th = 2 * math.pi * u
                n = (math.cos(th), 0.0, math.sin(th))
                return (x + 0.18 * n[0], 2.8 * v, z + 0.18 * n[2]), n
            surface_of_revolution(m, "columns", "stone", column, 128, 12)
            m.oriented_box("capitals", "stone", (x, 2.8, z), (0.5, 0.2, 0.5), 0.0, omit_bottom=False)
    # a sphere on a pedestal and a torus on the floor, in the aisle
    m.oriented_box("pedestal", "stone", (0.3, 0.0, 6.8), (0.6, 0.7, 0.6), 20.0)
    sphere(m, "sphere", "orange", (0.3, 1.05, 6.8), 0.35, nu=64, nv=32)
    torus(m, "torus", "blue", (-0.6, 0.1, 4.2), 0.45, 0.1, nu=48, nv=24)
    m.write(os.path.join(HERE, "vault_hall"), "vault_hall: barrel-vaulted nave, window lights, ten columns, sphere, torus")
    eye, look = (-1.0, 1.6, 0.7), (0.6, 2.3, 11.0)
    cam = {"eye": eye, "look_at": look, "up": rolled_up(eye, look, 0.0), "vfov_deg": 70.0}
    write_toml("vault_hall", "A barrel-vaulted nave (6 x 12 m, vault to 6 m) lit by three window-like emitters on a long "
               "wall; ten finely\n# tessellated columns with capitals, a sphere on a pedestal, a torus: about 40k "
               "triangles.", cam)
    return m, cam


def fixture_room():
    m = room_model((0.42, 0.36, 0.30))
    m.material("cabinet", Kd=(0.20, 0.45, 0.30))
    m.material("fixture", Kd=(0, 0, 0), Ke=(14.0, 14.0, 13.0))
    m.material("glow", Kd=(0, 0, 0), Ke=(7.0, 5.0, 2.6))
    xs, zs, H = [0.0, 2.5, 5.0], [0.0, 2.0, 4.0], 2.6
    shell(m, xs, zs, lambda i, j: (0.0, H), lambda i, j: "floor", lambda i, j: "ceiling",
          lambda i, j, side, y0, y1: [(y0, y1, "wall")])
    # the ceiling fixture: 0.8 x 0.8 m, 0.12 m deep, its top against the ceiling; bottom and sides emit
    m.box("fixture", "fixture", (2.1, H - 0.12, 1.6), (2.9, H, 2.4), omit=("+y",))
    # a glowing 0.4 m cube on the floor in the corner x = 5, z = 4, touching both walls
    m.box("glow_cube", "glow", (4.6, 0.0, 3.6), (5.0, 0.4, 4.0), omit=("-y", "+x", "+z"))
    table(m, 1.2, 2.4, 2.6, 3.4, 0.74, "wood")
    m.box("cabinet", "cabinet", (2.9, 0.0, 3.5), (3.7, 1.6, 4.0), omit=("-y", "+z"))
    m.write(os.path.join(HERE, "fixture_room"), "fixture_room: a plain room lit by a ceiling fixture and a glowing cube")
    eye, look = (0.4, 1.45, 0.3), (3.9, 1.0, 3.5)
    cam = {"eye": eye, "look_at": look, "up": rolled_up(eye, look, 0.0), "vfov_deg": 75.0}
    write_toml("fixture_room", "A plain 5 x 4 m room, 2.6 m high, lit only by emitters that touch other surfaces at "
               "right angles: a ceiling\n# fixture (bottom and sides emit) and a glowing cube in a corner; a table "
               "and a cabinet.", cam)
    return m, cam


def living_room():
    m = room_model((0.40, 0.28, 0.17))
    m.material("sofa", Kd=(0.18, 0.28, 0.50))
    m.material("shelves", Kd=(0.62, 0.58, 0.50))
    m.material("metal", Kd=(0.10, 0.10, 0.10))
    m.material("table_lamp", Kd=(0, 0, 0), Ke=(30.0, 24.0, 15.0))
    m.material("uplighter", Kd=(0, 0, 0), Ke=(26.0, 25.0, 23.0))
    # a 5.5 x 4.5 m room, 2.7 m high, with a 2.5 m wide, 0.8 m deep bay in the wall z = 4.5
    xs, zs, H = [0.0, 1.5, 4.0, 5.5], [0.0, 2.5, 4.5, 5.3], 2.7

    def column(i, j):
        return (0.0, H) if j < 2 or i == 1 else None

    shell(m, xs, zs, column, lambda i, j: "floor", lambda i, j: "ceiling",
          lambda i, j, side, y0, y1: [(y0, y1, "wall")])
    # a sofa turned by 12 degrees: a seat block with a backrest standing on it, both on the floor plan
    m.oriented_box("sofa", "sofa", (2.55, 0.0, 3.55), (2.1, 0.42, 0.9), 12.0)
    m.oriented_box("sofa_back", "sofa", (2.55 + 0.38 * math.sin(math.radians(12)), 0.42,
                                          3.55 + 0.38 * math.cos(math.radians(12))), (2.1, 0.4, 0.14), 12.0)
    # a side table beside it with a glowing lamp block (sides and top emit) standing on it, turned 30 deg
    m.box("side_table", "wood", (0.75, 0.0, 3.35), (1.25, 0.55, 3.85), omit=("-y",))
    m.oriented_box("table_lamp", "table_lamp", (1.0, 0.55, 3.6), (0.28, 0.34, 0.28), 30.0)
    # an uplighter near the corner x = 5.5, z = 4.5: a thin pole on the floor carrying a glowing shallow shade
    m.oriented_box("pole", "metal", (4.3, 0.0, 4.1), (0.04, 1.7, 0.04), 0.0)
    m.oriented_box("uplighter", "uplighter", (4.3, 1.7, 4.1), (0.42, 0.1, 0.42), 45.0, omit_bottom=False)
    # a low coffee table in front of the sofa and a bookcase against the wall x = 0
    table(m, 2.0, 3.1, 1.95, 2.55, 0.42, "wood")
    m.box("bookcase", "shelves", (0.0, 0.0, 0.9), (0.35, 1.9, 2.2), omit=("-y", "-x"))
    m.write(os.path.join(HERE, "living_room"), "living_room: a room with a bay, lit by a table lamp and an uplighter",
            triangulate=True)
    eye, look = (4.9, 1.55, 0.35), (1.4, 0.75, 3.9)
    cam = {"eye": eye, "look_at": look, "up": rolled_up(eye, look, 0.0), "vfov_deg": 70.0}
    write_toml("living_room", "A 5.5 x 4.5 m room with a bay, 2.7 m high, lit only by a glowing table lamp standing on a "
               "side table and an\n# uplighter's shade on a pole; a turned sofa, a coffee table, a bookcase. "
               "Written as triangles, as exporters do.", cam)
    return m, cam


if __name__ == "__main__":
    for make in (l_room, gap_room, alcove_hall, textured_box, rotunda, vault_hall, stair_hall, fixture_room,
                 living_room):
        model, _ = make()
        print("%-12s %4d triangles, %d materials" % (make.__name__, model.triangle_count(), len(model.materials)))
