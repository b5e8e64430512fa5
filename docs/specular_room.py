#!/usr/bin/env python3
"""A large room with a glass and a mirror sphere, for trying the hierarchy's light through mirrors and
glass at scale (docs/accuracy.md, session 23).

usage: python3 docs/specular_room.py OUT_DIR [CELLS]

Writes OUT_DIR/room.obj, room.mtl and room.toml: a 10 x 4 x 10 m room whose six walls are each a grid
of CELLS (default 120) cells per 10 m edge, two triangles per cell (about 2.3 x CELLS^2 triangles in
all: 122k at 120), a glass sphere (Ni 1.5) and a mirror sphere (Ks 0.9) of radius 1 m, 9,216 triangles
each, and a 2 x 2 m lamp (Ke 10) under the ceiling. The scene file asks for the hierarchy.
"""
import math
import os
import sys


def main():
    if len(sys.argv) < 2:
        sys.exit(__doc__)
    out = sys.argv[1]
    cells = int(sys.argv[2]) if len(sys.argv) > 2 else 120
    os.makedirs(out, exist_ok=True)
    width, height = 10.0, 4.0
    vertices, faces = [], []

    def vertex(p):
        vertices.append(p)
        return len(vertices)

    def grid(origin, u, v, nu, nv, material):
        """Cells over origin + s*u + t*v, facing u x v."""
        ids = [[vertex(tuple(origin[k] + u[k] * i / nu + v[k] * j / nv for k in range(3))) for j in range(nv + 1)]
               for i in range(nu + 1)]
        for i in range(nu):
            for j in range(nv):
                a, b, c, d = ids[i][j], ids[i + 1][j], ids[i + 1][j + 1], ids[i][j + 1]
                faces.append((material, (a, b, c)))
                faces.append((material, (a, c, d)))

    tall = max(1, int(cells * height / width))
    grid((0, 0, 0), (0, 0, width), (width, 0, 0), cells, cells, "floor")
    grid((0, height, 0), (width, 0, 0), (0, 0, width), cells, cells, "white")
    grid((0, 0, 0), (width, 0, 0), (0, height, 0), cells, tall, "white")
    grid((0, 0, width), (0, height, 0), (width, 0, 0), tall, cells, "red")
    grid((0, 0, 0), (0, height, 0), (0, 0, width), tall, cells, "green")
    grid((width, 0, 0), (0, 0, width), (0, height, 0), cells, tall, "white")

    def sphere(centre, radius, material, rings=48, segments=96):
        base = len(vertices)
        for i in range(rings + 1):
            theta = math.pi * i / rings
            for j in range(segments):
                phi = 2 * math.pi * j / segments
                vertices.append((centre[0] + radius * math.sin(theta) * math.cos(phi),
                                 centre[1] + radius * math.cos(theta),
                                 centre[2] + radius * math.sin(theta) * math.sin(phi)))
        for i in range(rings):
            for j in range(segments):
                a = base + 1 + i * segments + j
                b = base + 1 + i * segments + (j + 1) % segments
                c = base + 1 + (i + 1) * segments + (j + 1) % segments
                d = base + 1 + (i + 1) * segments + j
                faces.append((material, (a, b, c)))
                faces.append((material, (a, c, d)))

    sphere((3.5, 1.0, 4.0), 1.0, "glass")
    sphere((6.5, 1.0, 6.0), 1.0, "mirror")
    y = height - 0.01
    lamp = [vertex((4.0, y, 4.0)), vertex((6.0, y, 4.0)), vertex((6.0, y, 6.0)), vertex((4.0, y, 6.0))]
    faces.append(("light", (lamp[0], lamp[1], lamp[2])))
    faces.append(("light", (lamp[0], lamp[2], lamp[3])))

    with open(os.path.join(out, "room.obj"), "w") as f:
        f.write("mtllib room.mtl\n")
        for p in vertices:
            f.write("v %.5f %.5f %.5f\n" % p)
        current = None
        for material, (a, b, c) in faces:
            if material != current:
                f.write("usemtl %s\n" % material)
                current = material
            f.write("f %d %d %d\n" % (a, b, c))
    with open(os.path.join(out, "room.mtl"), "w") as f:
        f.write("newmtl white\nKd 0.7 0.7 0.7\nnewmtl floor\nKd 0.5 0.5 0.5\n"
                "newmtl red\nKd 0.6 0.1 0.1\nnewmtl green\nKd 0.1 0.5 0.1\n"
                "newmtl glass\nKd 0 0 0\nKs 1 1 1\nNi 1.5\nd 0\nillum 7\n"
                "newmtl mirror\nKd 0 0 0\nKs 0.9 0.9 0.9\nillum 3\n"
                "newmtl light\nKd 0 0 0\nKe 10 10 10\n")
    with open(os.path.join(out, "room.toml"), "w") as f:
        f.write('[camera]\neye = [5.0, 2.0, 9.5]\nlook_at = [5.0, 1.2, 3.0]\nup = [0.0, 1.0, 0.0]\nvfov_deg = 60.0\n\n'
                '[image]\nwidth = 192\nheight = 128\nsamples_per_pixel = 4\n\n'
                '[radiosity]\nmethod = "hierarchical"\n\n[[mesh]]\nobj = "room.obj"\n')
    print("%d triangles in %s" % (len(faces), out))


if __name__ == "__main__":
    main()
