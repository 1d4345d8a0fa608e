#!/usr/bin/python3
"""The README's mesh picture: a triangle mesh (left, its triangle edges drawn) and the NURBS solid
that `subd2nurbs convert MESH -o X.step` makes of it (right, shaded, the B-rep faces' boundaries
drawn), side by side from the same camera, each with a caption giving the real counts of the run.

Regenerate it (from the repository root, after building the `subd2nurbs` target into build/):

    /usr/bin/python3 scripts/render_mesh_picture.py

which runs `build/subd2nurbs convert tests/data/mesh/fandisk.off -o TMP/x.step --report TMP/r.json`
with the defaults, reads the STEP back with FreeCAD (`freecadcmd`: Part.read, each face
tessellated, each edge discretised; Debian package freecad) and writes docs/images/mesh_to_nurbs.png.
Options: --cli, --mesh (an OFF file), --out, --freecadcmd, --width, --azimuth, --elevation.
Needs the Debian packages python3-numpy, python3-pil and freecad (not the build's: nothing in the
build or the tests runs this script). Takes a minute or two (most of it the z-buffer in Python).

Rendering: numpy only (PIL for the captions, the downsampling and the PNG): an orthographic
camera, a z-buffer at 3x the final size, flat shading for the mesh (its facets), smooth shading
for the NURBS faces (normals averaged within each face, so the sharp edges between faces stay
sharp), lines drawn where the z-buffer shows them, then a box filter down to the final size.
"""
import argparse
import json
import os
import shutil
import subprocess
import sys
import tempfile

import numpy as np
from PIL import Image, ImageDraw, ImageFont

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))

# Run by freecadcmd: the STEP's faces as triangles and its edges as polylines, as JSON.
FREECAD_HELPER = r'''
import json, os, Part
shape = Part.read(os.environ["S2N_PIC_STEP"])
tol = float(os.environ["S2N_PIC_TOL"])
faces = []
for f in shape.Faces:
    pts, tris = f.tessellate(tol)
    faces.append({"p": [[v.x, v.y, v.z] for v in pts], "t": [list(t) for t in tris]})
edges = []
for e in shape.Edges:
    if e.Degenerated:
        continue
    edges.append([[v.x, v.y, v.z] for v in e.discretize(Deflection=tol)])
json.dump({"faces": faces, "edges": edges, "solids": len(shape.Solids)},
          open(os.environ["S2N_PIC_OUT"], "w"))
'''


def read_off(path):
    tok = []
    for line in open(path):
        line = line.split("#", 1)[0].split()
        tok.extend(line)
    if tok[0] != "OFF":
        raise SystemExit("%s: not an OFF file" % path)
    nv, nf = int(tok[1]), int(tok[2])
    v = np.array(tok[4:4 + 3 * nv], float).reshape(nv, 3)
    tris, k = [], 4 + 3 * nv
    for _ in range(nf):
        n = int(tok[k])
        poly = [int(x) for x in tok[k + 1:k + 1 + n]]
        k += 1 + n
        tris.extend([poly[0], poly[i], poly[i + 1]] for i in range(1, n - 1))
    return v, np.array(tris, int)


def unique_edges(tris):
    e = np.concatenate([tris[:, [0, 1]], tris[:, [1, 2]], tris[:, [2, 0]]])
    return np.unique(np.sort(e, axis=1), axis=0)


class Camera:
    """Orthographic: y up, azimuth about y, elevation about x; screen x right, y down, z to the viewer."""

    def __init__(self, azimuth, elevation):
        a, e = np.radians(azimuth), np.radians(elevation)
        ry = np.array([[np.cos(a), 0, np.sin(a)], [0, 1, 0], [-np.sin(a), 0, np.cos(a)]])
        rx = np.array([[1, 0, 0], [0, np.cos(e), -np.sin(e)], [0, np.sin(e), np.cos(e)]])
        self.R = rx @ ry

    def fit(self, pts, w, h, margin=0.05):
        q = pts @ self.R.T
        lo, hi = q.min(0), q.max(0)
        self.s = (1 - 2 * margin) * min(w / (hi[0] - lo[0]), h / (hi[1] - lo[1]))
        self.c = (lo + hi) / 2
        self.w, self.h = w, h

    def rotate(self, v):
        return v @ self.R.T

    def project(self, pts):
        q = (pts @ self.R.T - self.c) * self.s
        return np.stack([self.w / 2 + q[:, 0], self.h / 2 - q[:, 1], q[:, 2]], axis=1)


KEY = np.array([-0.35, 0.55, 0.75])
KEY = KEY / np.linalg.norm(KEY)
FILL = np.array([0.6, 0.1, 0.8])
FILL = FILL / np.linalg.norm(FILL)


def shade(normals, base):
    """Two-sided Lambert from a key and a fill light + a little specular (Blinn, view along z)."""
    n = normals / np.maximum(np.linalg.norm(normals, axis=-1, keepdims=True), 1e-300)
    n = np.where(n[..., 2:3] < 0, -n, n)
    key, fill = np.clip(n @ KEY, 0, 1), np.clip(n @ FILL, 0, 1)
    half = KEY + np.array([0, 0, 1.0])
    half /= np.linalg.norm(half)
    spec = np.clip(n @ half, 0, 1) ** 40
    rgb = np.asarray(base) * (0.30 + 0.55 * key[..., None] + 0.25 * fill[..., None]) + 0.18 * spec[..., None]
    return np.clip(rgb, 0, 1)


def rasterise(img, zbuf, S, tris, col, smooth):
    """S: screen points (x, y, z); col: per triangle (flat) or per point (smooth) rgb."""
    H, W = zbuf.shape
    for t, (i0, i1, i2) in enumerate(tris):
        (x0, y0, z0), (x1, y1, z1), (x2, y2, z2) = S[i0], S[i1], S[i2]
        area = (x1 - x0) * (y2 - y0) - (x2 - x0) * (y1 - y0)
        if abs(area) < 1e-12:
            continue
        xa, xb = max(int(min(x0, x1, x2)), 0), min(int(max(x0, x1, x2)) + 1, W - 1)
        ya, yb = max(int(min(y0, y1, y2)), 0), min(int(max(y0, y1, y2)) + 1, H - 1)
        if xa > xb or ya > yb:
            continue
        qx, qy = np.meshgrid(np.arange(xa, xb + 1) + 0.5, np.arange(ya, yb + 1) + 0.5)
        w1 = ((qx - x0) * (y2 - y0) - (x2 - x0) * (qy - y0)) / area
        w2 = ((x1 - x0) * (qy - y0) - (qx - x0) * (y1 - y0)) / area
        w0 = 1 - w1 - w2
        z = w0 * z0 + w1 * z1 + w2 * z2
        zb = zbuf[ya:yb + 1, xa:xb + 1]
        m = (w0 >= 0) & (w1 >= 0) & (w2 >= 0) & (z > zb)
        if not m.any():
            continue
        zb[m] = z[m]
        if smooth:
            c = w0[m, None] * col[i0] + w1[m, None] * col[i1] + w2[m, None] * col[i2]
        else:
            c = col[t]
        img[ya:yb + 1, xa:xb + 1][m] = c


def draw_lines(img, zbuf, segs, colour, alpha, radius, eps):
    """segs: (n, 2, 3) screen segments; a sample is drawn where it is not behind the z-buffer by
    more than eps; radius in pixels (a square brush of side 2 radius + 1)."""
    if len(segs) == 0:
        return
    H, W = zbuf.shape
    a, b = segs[:, 0], segs[:, 1]
    n = np.maximum(np.ceil(np.linalg.norm((b - a)[:, :2], axis=1) * 2).astype(int), 1) + 1
    seg = np.repeat(np.arange(len(segs)), n)
    t = np.concatenate([np.linspace(0, 1, k) for k in n])
    p = a[seg] + (b - a)[seg] * t[:, None]
    x, y, z = p[:, 0].astype(int), p[:, 1].astype(int), p[:, 2]
    ok = (x >= 0) & (x < W) & (y >= 0) & (y < H)
    x, y, z = x[ok], y[ok], z[ok]
    vis = z >= zbuf[y, x] - eps
    x, y = x[vis], y[vis]
    mask = np.zeros((H, W), bool)
    for dy in range(-radius, radius + 1):
        for dx in range(-radius, radius + 1):
            xx, yy = np.clip(x + dx, 0, W - 1), np.clip(y + dy, 0, H - 1)
            mask[yy, xx] = True
    img[mask] = (1 - alpha) * img[mask] + alpha * np.asarray(colour)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--cli", default=os.path.join(ROOT, "build", "subd2nurbs"))
    ap.add_argument("--mesh", default=os.path.join(ROOT, "tests", "data", "mesh", "fandisk.off"))
    ap.add_argument("--out", default=os.path.join(ROOT, "docs", "images", "mesh_to_nurbs.png"))
    ap.add_argument("--freecadcmd", default="freecadcmd")
    ap.add_argument("--width", type=int, default=1200)
    ap.add_argument("--height", type=int, default=500)
    ap.add_argument("--azimuth", type=float, default=30.0)
    ap.add_argument("--elevation", type=float, default=20.0)
    ap.add_argument("--workdir", help="keep the STEP, the report and FreeCAD's dump here (default: a new temporary directory)")
    ap.add_argument("--reuse", action="store_true", help="with --workdir: reuse its files instead of converting again")
    a = ap.parse_args()

    tmp = a.workdir or tempfile.mkdtemp(prefix="s2n_pic_")
    os.makedirs(tmp, exist_ok=True)
    step, report = os.path.join(tmp, "x.step"), os.path.join(tmp, "r.json")
    helper, dump = os.path.join(tmp, "fc_dump.py"), os.path.join(tmp, "brep.json")
    reuse = a.reuse and os.path.exists(report) and os.path.exists(dump)
    cmd = [a.cli, "convert", a.mesh, "-o", step, "--report", report, "-q"]
    if not reuse:
        print("+", " ".join(cmd), file=sys.stderr)
        subprocess.run(cmd, check=True)
    r = json.load(open(report))
    triangles = r["mesh"]["input_triangles"]
    nfaces = r["brep"]["faces"]

    verts, tris = read_off(a.mesh)
    diag = float(np.linalg.norm(verts.max(0) - verts.min(0)))
    if not reuse:
        open(helper, "w").write(FREECAD_HELPER)
        env = dict(os.environ, S2N_PIC_STEP=step, S2N_PIC_OUT=dump, S2N_PIC_TOL=repr(5e-4 * diag))
        print("+ %s -c exec(open(%r).read())" % (a.freecadcmd, helper), file=sys.stderr)
        subprocess.run([a.freecadcmd, "-c", "exec(open(%r).read())" % helper], check=True, env=env,
                       stdout=subprocess.DEVNULL)
    brep = json.load(open(dump))
    if len(brep["faces"]) != nfaces:
        raise SystemExit("FreeCAD reads %d faces, the report says %d" % (len(brep["faces"]), nfaces))

    SS = 3  # supersampling
    caption_h = 44
    pw, ph = a.width // 2 * SS, (a.height - caption_h) * SS
    cam = Camera(a.azimuth, a.elevation)
    cam.fit(verts, pw, ph)
    eps = 4e-3 * diag * cam.s
    background = np.array([0.975, 0.978, 0.985])

    # Left: the mesh, flat shaded, its triangle edges drawn.
    img_l = np.empty((ph, pw, 3))
    img_l[:] = background
    z_l = np.full((ph, pw), -np.inf)
    S = cam.project(verts)
    fn = np.cross(verts[tris[:, 1]] - verts[tris[:, 0]], verts[tris[:, 2]] - verts[tris[:, 0]])
    rasterise(img_l, z_l, S, tris, shade(cam.rotate(fn), (0.80, 0.80, 0.81)), smooth=False)
    e = unique_edges(tris)
    draw_lines(img_l, z_l, S[e], (0.15, 0.16, 0.2), 0.85, 0, eps)

    # Right: the B-rep's faces, smooth shaded per face, the face boundaries drawn.
    img_r = np.empty((ph, pw, 3))
    img_r[:] = background
    z_r = np.full((ph, pw), -np.inf)
    for f in brep["faces"]:
        p, t = np.array(f["p"], float), np.array(f["t"], int)
        if len(t) == 0:
            continue
        tn = np.cross(p[t[:, 1]] - p[t[:, 0]], p[t[:, 2]] - p[t[:, 0]])
        vn = np.zeros_like(p)
        for k in range(3):
            np.add.at(vn, t[:, k], tn)
        rasterise(img_r, z_r, cam.project(p), t, shade(cam.rotate(vn), (0.62, 0.74, 0.90)), smooth=True)
    segs = []
    for pl in brep["edges"]:
        q = cam.project(np.array(pl, float))
        segs.append(np.stack([q[:-1], q[1:]], axis=1))
    draw_lines(img_r, z_r, np.concatenate(segs), (0.05, 0.08, 0.16), 1.0, 1, eps)

    def to_image(arr):
        im = Image.fromarray((np.clip(arr, 0, 1) * 255 + 0.5).astype(np.uint8))
        return im.resize((pw // SS, ph // SS), Image.BOX)

    out = Image.new("RGB", (a.width, a.height), tuple(int(c * 255 + 0.5) for c in background))
    out.paste(to_image(img_l), (0, 0))
    out.paste(to_image(img_r), (a.width // 2, 0))
    d = ImageDraw.Draw(out)
    try:
        font = ImageFont.truetype("/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf", 19)
    except OSError:
        font = ImageFont.load_default()

    def thousands(n):
        return "{:,}".format(n).replace(",", " ")

    captions = ["%s triangles (%s input)" % (thousands(triangles), os.path.splitext(a.mesh)[1][1:].upper()),
                "%d NURBS faces, STEP (subd2nurbs convert)" % nfaces]
    for k, text in enumerate(captions):
        x0 = k * a.width // 2
        tw = d.textlength(text, font=font)
        d.text((x0 + (a.width // 2 - tw) / 2, a.height - caption_h + 8), text, fill=(40, 44, 52), font=font)
    d.line([(a.width // 2, 20), (a.width // 2, a.height - 20)], fill=(205, 208, 214), width=1)
    out.save(a.out, optimize=True)
    print("%s: %d triangles -> %d NURBS faces (%d solid(s)); %d bytes"
          % (a.out, triangles, nfaces, brep["solids"], os.path.getsize(a.out)), file=sys.stderr)
    # The numbers the README's paragraph under the picture quotes.
    after = r["mesh"]["fit"]["after"]
    print("two-sided distance max %.2g of the diagonal; %d pair(s) of faces cross"
          % (max(after["limit_to_target"]["max"], after["target_to_limit"]["max"]),
             r["self_intersection"]["crossing_face_pairs"]), file=sys.stderr)
    if not a.workdir:
        shutil.rmtree(tmp)


if __name__ == "__main__":
    main()
