#!/usr/bin/env python3
"""The picture of docs/fitting.md: input vertices against the approximating and the
interpolating surface, and a noisy sphere before and after fairing.

    PYTHONPATH=build/python /usr/bin/python3 scripts/render_fit.py OUT.png [--size 480]

Top row: samples/rounded_box.obj converted as is and with fit="interpolate"; the cage's
vertices are drawn as dots coloured by their distance to the surface (blue 0, red the largest
over both panels; the distance is to the nearest point of a fine tessellation of the patches).
Bottom row: a cube-sphere cage (8 x 8 quads per side, vertices moved radially by up to 3 %,
seeded) converted with fit="interpolate" and with fair=0.3, coloured by the patches' mean
curvature on one scale (white at the unit sphere's H = -1, blue/red -1 -/+ 3). Needs the
subd2nurbs Python module, numpy and Pillow (python3-pil). Rasterised here, orthographic,
z-buffered, Lambert-shaded, like scripts/render_glb.py.
"""
import argparse
import math
import os
import sys

import numpy as np
from PIL import Image, ImageDraw

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, "..", "build", "python"))
import subd2nurbs as s2n  # noqa: E402


def cube_sphere(n, noise, seed):
    rng = np.random.default_rng(seed)
    ids, verts, faces = {}, [], []

    def vertex(p):
        key = tuple(int(round(c * 1e6)) for c in p)
        if key not in ids:
            ids[key] = len(verts)
            verts.append(np.array(p, float) / np.linalg.norm(p))
        return ids[key]

    for axis in range(3):
        for sign in (1, -1):
            a, b = (axis + 1) % 3, (axis + 2) % 3
            for i in range(n):
                for j in range(n):
                    q = []
                    for di, dj in ((0, 0), (1, 0), (1, 1), (0, 1)):
                        p = [0.0, 0.0, 0.0]
                        p[axis] = sign
                        p[a] = -1 + 2.0 * (i + di) / n
                        p[b] = (-1 + 2.0 * (j + dj) / n) * sign
                        q.append(vertex(p))
                    faces.append(q)
    v = np.array(verts) * (1 + rng.uniform(-noise, noise, size=(len(verts), 1)))
    return s2n.Cage(v, faces, name="noisy sphere")


def view_matrix(azimuth, elevation):
    az, el = math.radians(azimuth), math.radians(elevation)
    rz = np.array([[math.cos(az), -math.sin(az), 0], [math.sin(az), math.cos(az), 0], [0, 0, 1]])
    # z up -> screen y up; then tilt by the elevation about the screen x axis.
    to_screen = np.array([[1, 0, 0], [0, 0, 1], [0, -1, 0]], float)
    rx = np.array([[1, 0, 0], [0, math.cos(el), -math.sin(el)], [0, math.sin(el), math.cos(el)]])
    return rx @ to_screen @ rz


def render(pos, nrm, rgb, tris, dots, dot_rgb, size, view, bounds):
    P = pos @ view.T
    N = nrm @ view.T
    lo, hi = bounds
    scale = 0.9 * size / max(hi[0] - lo[0], hi[1] - lo[1])
    cx, cy = size / 2 - (lo[0] + hi[0]) / 2 * scale, size / 2 + (lo[1] + hi[1]) / 2 * scale
    S = np.column_stack([cx + P[:, 0] * scale, cy - P[:, 1] * scale, P[:, 2]])
    light = np.array([0.3, 0.5, 0.8]) / np.linalg.norm([0.3, 0.5, 0.8])
    shade = rgb * (0.35 + 0.65 * np.abs(N @ light))[:, None]
    zbuf = np.full((size, size), -1e300)
    img = np.full((size, size, 3), 255.0)
    for t in tris:
        x, y, z = S[t, 0], S[t, 1], S[t, 2]
        area = (x[1] - x[0]) * (y[2] - y[0]) - (x[2] - x[0]) * (y[1] - y[0])
        if area == 0:
            continue
        xa, xb = max(int(x.min()), 0), min(int(x.max()) + 1, size - 1)
        ya, yb = max(int(y.min()), 0), min(int(y.max()) + 1, size - 1)
        if xa > xb or ya > yb:
            continue
        gx, gy = np.meshgrid(np.arange(xa, xb + 1) + 0.5, np.arange(ya, yb + 1) + 0.5)
        w1 = ((gx - x[0]) * (y[2] - y[0]) - (x[2] - x[0]) * (gy - y[0])) / area
        w2 = ((x[1] - x[0]) * (gy - y[0]) - (gx - x[0]) * (y[1] - y[0])) / area
        w0 = 1 - w1 - w2
        inside = (w0 >= 0) & (w1 >= 0) & (w2 >= 0)
        zz = w0 * z[0] + w1 * z[1] + w2 * z[2]
        sub = zbuf[ya:yb + 1, xa:xb + 1]
        upd = inside & (zz > sub)
        sub[upd] = zz[upd]
        c = (w0[..., None] * shade[t[0]] + w1[..., None] * shade[t[1]] + w2[..., None] * shade[t[2]]) * 255
        img[ya:yb + 1, xa:xb + 1][upd] = c[upd]
    im = Image.fromarray(np.clip(img, 0, 255).astype(np.uint8))
    if dots is not None:
        draw = ImageDraw.Draw(im)
        D = dots @ view.T
        r = max(3, size // 90)
        for (px, py, pz), col in zip(np.column_stack([cx + D[:, 0] * scale, cy - D[:, 1] * scale, D[:, 2]]),
                                     dot_rgb):
            ix, iy = int(px), int(py)
            if 0 <= ix < size and 0 <= iy < size and pz >= zbuf[iy, ix] - 0.02 * (hi[0] - lo[0]):
                draw.ellipse([px - r, py - r, px + r, py + r], fill=tuple(int(255 * c) for c in col),
                             outline=(0, 0, 0))
    return im


def diverging(v, centre, half):
    t = np.clip((v - centre) / half, -1, 1)
    white = np.ones(3)
    blue, red = np.array([0.2, 0.35, 0.85]), np.array([0.85, 0.2, 0.2])
    return np.where(t[:, None] < 0, white + (-t[:, None]) * (blue - white), white + t[:, None] * (red - white))


def ramp(t):
    t = np.clip(t, 0, 1)[:, None]
    return (1 - t) * np.array([0.15, 0.3, 0.95]) + t * np.array([0.95, 0.15, 0.1])


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("png")
    ap.add_argument("--size", type=int, default=480)
    a = ap.parse_args()
    size = a.size
    panels = []

    box = s2n.read_cage(os.path.join(HERE, "..", "samples", "rounded_box.obj"))
    results = [s2n.convert(box, brep=False, preview="curvature", preview_samples=24),
               s2n.convert(box, fit="interpolate", brep=False, preview="curvature", preview_samples=24)]
    dists = []
    for r in results:
        pts = r.preview["positions"].astype(float)
        d = np.sqrt(((box.vertices[:, None, :] - pts[None, :, :]) ** 2).sum(axis=2)).min(axis=1)
        dists.append(d)
    dmax = max(d.max() for d in dists)
    view = view_matrix(35, 25)
    allp = np.vstack([r.preview["positions"] for r in results] + [box.vertices]) @ view.T
    bounds = (allp.min(axis=0), allp.max(axis=0))
    titles = ["approximate: the surface misses the cage's vertices (max %.2g)" % dists[0].max(),
              "--fit interpolate: through every vertex (max %.1g)" % dists[1].max()]
    for r, d, title in zip(results, dists, titles):
        p = r.preview
        grey = np.full((len(p["positions"]), 3), 0.82)
        panels.append((render(p["positions"].astype(float), p["normals"].astype(float), grey, p["triangles"],
                              box.vertices, ramp(d / dmax), size, view, bounds), title))

    sphere = cube_sphere(8, 0.03, 11)
    results = [s2n.convert(sphere, fit="interpolate", brep=False, preview="curvature", preview_samples=12),
               s2n.convert(sphere, fit="interpolate", fair=0.3, brep=False, preview="curvature", preview_samples=12)]
    view = view_matrix(30, 20)
    allp = np.vstack([r.preview["positions"] for r in results]) @ view.T
    bounds = (allp.min(axis=0), allp.max(axis=0))
    titles = ["noisy sphere, interpolated: follows the noise", "--fit interpolate --fair 0.3: smooth"]
    for r, title in zip(results, titles):
        p = r.preview
        colours = diverging(p["values"].astype(float), -1.0, 3.0)
        panels.append((render(p["positions"].astype(float), p["normals"].astype(float), colours, p["triangles"],
                              None, None, size, view, bounds), title))

    label = 22
    out = Image.new("RGB", (2 * size, 2 * (size + label)), "white")
    draw = ImageDraw.Draw(out)
    for k, (im, title) in enumerate(panels):
        x, y = (k % 2) * size, (k // 2) * (size + label)
        out.paste(im, (x, y + label))
        draw.text((x + 8, y + 4), title, fill=(0, 0, 0))
    out.save(a.png)
    print("wrote %s; rounded box: vertex distance max %.3g (approximate), %.3g (interpolate)"
          % (a.png, dists[0].max(), dists[1].max()))


if __name__ == "__main__":
    main()
