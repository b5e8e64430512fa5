#!/usr/bin/env python3
"""Generates the showcase scene (scene.obj + scene.mtl): a 4 x 3 x 5 m gallery lit by a ceiling
panel, with a red and a blue wall for colour bleeding, a finely tessellated diffuse torus knot and
pillars for soft shadows, a mirror panel and a mirror sphere, and a glass sphere.

Deterministic, standard library only:  python3 scenes/showcase/generate.py
Conventions (as every radray scene): metres, right-handed, y up, every face counter-clockwise seen
from the side it faces (room walls face inwards, objects outwards).
"""
import math
import os

HERE = os.path.dirname(os.path.abspath(__file__))
W, H, D = 4.0, 3.0, 5.0  # room: x in [0, W], y in [0, H], z in [0, D]; the camera looks along +z

verts = []
normals = []  # per vertex: a unit normal for smooth (curved) surfaces, or None for flat ones
faces = []  # (material, [vertex indices, 1-based])
objects = []  # (name, first face, last face)


def v(p, n=None):
    verts.append(p)
    normals.append(n)
    return len(verts)


def begin(name):
    objects.append([name, len(faces), None])


def end():
    objects[-1][2] = len(faces)


def quad(a, b, c, d, mat):
    faces.append((mat, [v(a), v(b), v(c), v(d)]))


def box(lo, hi, mat, bottom=True):
    """An axis-aligned box facing outwards; `bottom=False` leaves out the face resting on the floor."""
    (x0, y0, z0), (x1, y1, z1) = lo, hi
    p = lambda i, j, k: (x1 if i else x0, y1 if j else y0, z1 if k else z0)
    quad(p(0, 0, 0), p(0, 0, 1), p(0, 1, 1), p(0, 1, 0), mat)  # x-
    quad(p(1, 0, 0), p(1, 1, 0), p(1, 1, 1), p(1, 0, 1), mat)  # x+
    if bottom:
        quad(p(0, 0, 0), p(1, 0, 0), p(1, 0, 1), p(0, 0, 1), mat)  # y- (bottom)
    quad(p(0, 1, 0), p(0, 1, 1), p(1, 1, 1), p(1, 1, 0), mat)  # y+
    quad(p(0, 0, 0), p(0, 1, 0), p(1, 1, 0), p(1, 0, 0), mat)  # z-
    quad(p(0, 0, 1), p(1, 0, 1), p(1, 1, 1), p(0, 1, 1), mat)  # z+


def grid_surface(f, nu, nv, mat):
    """A closed parametric surface f(u, v) -> (point, normal), u and v in [0, 1) wrapping, as triangles
    facing outwards."""
    idx = [[v(*f(i / nu, j / nv)) for j in range(nv)] for i in range(nu)]
    for i in range(nu):
        for j in range(nv):
            a, b = idx[i][j], idx[(i + 1) % nu][j]
            c, d = idx[(i + 1) % nu][(j + 1) % nv], idx[i][(j + 1) % nv]
            faces.append((mat, [a, b, c]))
            faces.append((mat, [a, c, d]))


def sphere(centre, r, nu, nv, mat):
    cx, cy, cz = centre
    idx = {}
    for j in range(1, nv):
        th = math.pi * j / nv
        for i in range(nu):
            ph = 2 * math.pi * i / nu
            n = (math.sin(th) * math.cos(ph), math.cos(th), -math.sin(th) * math.sin(ph))
            idx[i, j] = v((cx + r * n[0], cy + r * n[1], cz + r * n[2]), n)
    top, bottom = v((cx, cy + r, cz), (0.0, 1.0, 0.0)), v((cx, cy - r, cz), (0.0, -1.0, 0.0))
    for i in range(nu):
        k = (i + 1) % nu
        faces.append((mat, [top, idx[i, 1], idx[k, 1]]))
        for j in range(1, nv - 1):
            faces.append((mat, [idx[i, j], idx[i, j + 1], idx[k, j + 1]]))
            faces.append((mat, [idx[i, j], idx[k, j + 1], idx[k, j]]))
        faces.append((mat, [idx[i, nv - 1], bottom, idx[k, nv - 1]]))


def torus_knot(centre, scale, p, q, tube, nu, nv, mat):
    """A (p, q) torus knot tube: the curve c(t) swept by a circle of radius `tube` (Frenet-free frame)."""
    cx, cy, cz = centre

    def curve(t):
        a = 2 * math.pi * t
        r = 2 + math.cos(q * a)
        return (scale * r * math.cos(p * a), scale * -math.sin(q * a), scale * r * math.sin(p * a))

    def sub(a, b):
        return (a[0] - b[0], a[1] - b[1], a[2] - b[2])

    def cross(a, b):
        return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])

    def norm(a):
        n = math.sqrt(sum(x * x for x in a))
        return tuple(x / n for x in a)

    def f(u, w):
        c = curve(u)
        t = norm(sub(curve(u + 1e-4), curve(u - 1e-4)))
        n = norm(cross(t, (0.0, 1.0, 0.0)))
        b = cross(n, t)
        a = 2 * math.pi * w
        radial = tuple(math.cos(a) * n[k] + math.sin(a) * b[k] for k in range(3))
        # y is "up" in the scene: flatten the knot's height and lift it to `centre`
        p = (cx + c[0] + tube * radial[0], cy + c[1] * 0.6 + tube * radial[1], cz + c[2] + tube * radial[2])
        return p, radial

    grid_surface(f, nu, nv, mat)


# The room (faces look inwards). Floor, ceiling, back, left (red), right (blue), front (white, behind
# the camera, so light stays in the room).
begin("room")
quad((0, 0, 0), (0, 0, D), (W, 0, D), (W, 0, 0), "floor")
quad((0, H, 0), (W, H, 0), (W, H, D), (0, H, D), "white")
quad((0, 0, D), (0, H, D), (W, H, D), (W, 0, D), "white")
quad((0, 0, 0), (0, H, 0), (0, H, D), (0, 0, D), "red")
quad((W, 0, 0), (W, 0, D), (W, H, D), (W, H, 0), "blue")
quad((0, 0, 0), (W, 0, 0), (W, H, 0), (0, H, 0), "white")
end()

# Ceiling light panel (faces down), 0.2 mm below the ceiling.
begin("light")
y = H - 0.0002
quad((1.4, y, 2.0), (2.6, y, 2.0), (2.6, y, 3.0), (1.4, y, 3.0), "light")
end()

# A mirror panel on the back wall, 5 mm in front of it, facing the room (-z).
begin("mirror_panel")
z = D - 0.005
quad((1.3, 0.6, z), (1.3, 2.2, z), (2.7, 2.2, z), (2.7, 0.6, z), "mirror")
end()

begin("pillars")
box((0.45, 0.0, 3.6), (0.85, 2.2, 4.0), "white", bottom=False)
box((3.15, 0.0, 3.6), (3.55, 1.4, 4.0), "white", bottom=False)
end()

begin("plinth")
box((1.45, 0.0, 2.55), (2.55, 0.45, 3.65), "white", bottom=False)
end()

begin("torus_knot")
torus_knot((2.0, 0.595, 3.1), 0.13, 2, 3, 0.06, 192, 16, "clay")
end()

begin("glass_sphere")
sphere((0.95, 0.38, 2.2), 0.38, 96, 48, "glass")
end()

begin("mirror_sphere")
sphere((2.9, 0.36, 2.3), 0.36, 96, 48, "mirror")
end()

with open(os.path.join(HERE, "scene.obj"), "w") as out:
    out.write("# radray showcase scene, generated by generate.py (do not edit by hand)\n")
    out.write("mtllib scene.mtl\n")
    for p in verts:
        out.write("v %.6f %.6f %.6f\n" % p)
    normal_index = {}
    for i, n in enumerate(normals):
        if n is not None:
            out.write("vn %.6f %.6f %.6f\n" % n)
            normal_index[i + 1] = len(normal_index) + 1
    for name, first, last in objects:
        out.write("o %s\n" % name)
        current = None
        for mat, idx in faces[first:last]:
            if mat != current:
                out.write("usemtl %s\n" % mat)
                current = mat
            if all(i in normal_index for i in idx):
                out.write("f %s\n" % " ".join("%d//%d" % (i, normal_index[i]) for i in idx))
            else:
                out.write("f %s\n" % " ".join(str(i) for i in idx))

MTL = """# radray showcase materials: Kd diffuse reflectance, Ke emitted radiance (W/sr/m^2),
# Ks mirror reflectance, Ni index of refraction, d < 1 transparent dielectric.
newmtl white
Kd 0.75 0.74 0.72
newmtl floor
Kd 0.55 0.52 0.48
newmtl red
Kd 0.70 0.08 0.06
newmtl blue
Kd 0.07 0.15 0.65
newmtl clay
Kd 0.80 0.55 0.25
newmtl light
Kd 0 0 0
Ke 12 11 9.5
newmtl mirror
Kd 0 0 0
Ks 0.92 0.92 0.92
newmtl glass
Kd 0 0 0
Ks 1 1 1
Ni 1.5
d 0
"""
with open(os.path.join(HERE, "scene.mtl"), "w") as out:
    out.write(MTL)

print("%d vertices, %d faces (%d triangles)" % (len(verts), len(faces), sum(len(f[1]) - 2 for f in faces)))
