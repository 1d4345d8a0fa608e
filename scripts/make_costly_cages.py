#!/usr/bin/env python3
"""Valid but costly cages for the resource estimate (#32 item 3): high valence, big n-gons,
a big quad grid. Writes OBJ files into a folder; `--small` writes scaled-down versions (the
ctest of the estimate uses them).

    python3 scripts/make_costly_cages.py OUTDIR [--small]

Cases (n = 1024 / 1000, or 64 / 60 with --small):
  fans3_<n>.obj     three separate quad "stars", each with one interior vertex of valence n
                    (n quads around it, a ring of 2n vertices)
  ngon_<n>.obj      one planar n-gon (a circle's polygon): one face, boundary all around
  wavy_<n>.obj      one n-gon whose boundary waves up and down (z = 0.2 sin 3t): its fan is
                    deepened by the default tolerance (12 levels at n = 1000)
  prism_<n>.obj     a prism with n-gon caps: 2 n-gons and n side quads (closed)
  capsule_<n>.obj   an n-sided capsule: a cylinder of quads with 8 rings, each end closed by a
                    fan of n triangles around a pole (polar structures at both ends)
  grid_<m>.obj      an m x m grid of quads (m = 1000, or 100 with --small), flat with a bump
"""
import math
import os
import sys


def write(path, verts, faces):
    with open(path, "w") as f:
        for v in verts:
            f.write("v %.17g %.17g %.17g\n" % v)
        for face in faces:
            f.write("f " + " ".join(str(i + 1) for i in face) + "\n")


def star(n, cx=0.0, cy=0.0, z=0.0, height=0.3):
    """One valence-n interior vertex: n quads (centre, a_i, b_i, a_{i+1}); a raised centre."""
    verts = [(cx, cy, z + height)]
    for i in range(2 * n):
        r = 1.0 if i % 2 == 0 else 1.15
        t = math.pi * i / n
        verts.append((cx + r * math.cos(t), cy + r * math.sin(t), z))
    faces = []
    for i in range(n):
        a, b, c = 1 + 2 * i, 1 + 2 * i + 1, 1 + (2 * i + 2) % (2 * n)
        faces.append((0, a, b, c))
    return verts, faces


def fans3(n):
    verts, faces = [], []
    for k in range(3):
        v, f = star(n, cx=3.0 * k)
        off = len(verts)
        verts += v
        faces += [tuple(i + off for i in face) for face in f]
    return verts, faces


def ngon(n):
    verts = [(math.cos(2 * math.pi * i / n), math.sin(2 * math.pi * i / n), 0.0) for i in range(n)]
    return verts, [tuple(range(n))]


def wavy_ngon(n):
    verts = [(math.cos(2 * math.pi * i / n), math.sin(2 * math.pi * i / n), 0.2 * math.sin(6 * math.pi * i / n))
             for i in range(n)]
    return verts, [tuple(range(n))]


def prism(n):
    verts = [(math.cos(2 * math.pi * i / n), math.sin(2 * math.pi * i / n), z) for z in (0.0, 1.0) for i in range(n)]
    faces = [tuple(reversed(range(n))), tuple(range(n, 2 * n))]
    faces += [(i, (i + 1) % n, n + (i + 1) % n, n + i) for i in range(n)]
    return verts, faces


def capsule(n, rings=8):
    verts = [(0.0, 0.0, -1.5)]
    for r in range(rings):
        z = -1.0 + 2.0 * r / (rings - 1)
        verts += [(math.cos(2 * math.pi * i / n), math.sin(2 * math.pi * i / n), z) for i in range(n)]
    verts.append((0.0, 0.0, 1.5))
    top = len(verts) - 1
    ring = lambda r, i: 1 + r * n + i % n
    faces = [(0, ring(0, i + 1), ring(0, i)) for i in range(n)]
    for r in range(rings - 1):
        faces += [(ring(r, i), ring(r, i + 1), ring(r + 1, i + 1), ring(r + 1, i)) for i in range(n)]
    faces += [(top, ring(rings - 1, i), ring(rings - 1, i + 1)) for i in range(n)]
    return verts, faces


def grid(m):
    verts = []
    for j in range(m + 1):
        for i in range(m + 1):
            x, y = i / m, j / m
            verts.append((x, y, 0.1 * math.exp(-20 * ((x - 0.5) ** 2 + (y - 0.5) ** 2))))
    w = m + 1
    faces = [(j * w + i, j * w + i + 1, (j + 1) * w + i + 1, (j + 1) * w + i) for j in range(m) for i in range(m)]
    return verts, faces


def main():
    if len(sys.argv) < 2:
        sys.exit(__doc__)
    out = sys.argv[1]
    small = "--small" in sys.argv[2:]
    os.makedirs(out, exist_ok=True)
    n, ng, m = (64, 60, 100) if small else (1024, 1000, 1000)
    for name, (v, f) in [
        ("fans3_%d" % n, fans3(n)),
        ("ngon_%d" % ng, ngon(ng)),
        ("wavy_%d" % ng, wavy_ngon(ng)),
        ("prism_%d" % ng, prism(ng)),
        ("capsule_%d" % n, capsule(n)),
        ("grid_%d" % m, grid(m)),
    ]:
        write(os.path.join(out, name + ".obj"), v, f)


if __name__ == "__main__":
    main()
