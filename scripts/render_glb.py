#!/usr/bin/env python3
"""Renders a subd2nurbs preview GLB (convert --preview, docs/formats.md) to a PNG, headless and
with the Python standard library only: the GLB's POSITION / NORMAL / COLOR_0 / indices are read
from its binary chunk, projected orthographically, rasterised with a z-buffer, and each pixel
gets the interpolated vertex colour times a Lambert term (ambient 0.35) from the normal.

    python3 scripts/render_glb.py IN.glb OUT.png [--size 640] [--up y|z] [--azimuth 30] [--elevation 20]
    python3 scripts/render_glb.py MESH.{off,obj} OUT.png [--edges] ...   a polygon mesh, flat grey
                                                                          (--edges: its edges drawn)

Used for docs/images/ (see docs/limit.md, "Pictures").
"""
import argparse
import json
import math
import struct
import zlib


def read_glb(path):
    data = open(path, "rb").read()
    magic, version, length = struct.unpack_from("<4sII", data, 0)
    if magic != b"glTF" or version != 2:
        raise SystemExit("%s: not a glTF 2.0 binary" % path)
    off, doc, binary = 12, None, None
    while off < length:
        clen, ctype = struct.unpack_from("<II", data, off)
        chunk = data[off + 8: off + 8 + clen]
        if ctype == 0x4E4F534A:
            doc = json.loads(chunk)
        elif ctype == 0x004E4942:
            binary = chunk
        off += 8 + clen
    prim = doc["meshes"][0]["primitives"][0]

    def accessor(i, fmt, width):
        a = doc["accessors"][i]
        v = doc["bufferViews"][a["bufferView"]]
        start = v.get("byteOffset", 0) + a.get("byteOffset", 0)
        n = a["count"] * width
        return struct.unpack_from("<%d%s" % (n, fmt), binary, start)

    pos = accessor(prim["attributes"]["POSITION"], "f", 3)
    nrm = accessor(prim["attributes"]["NORMAL"], "f", 3)
    col = accessor(prim["attributes"]["COLOR_0"], "f", 3)
    idx = accessor(prim["indices"], "I", 1)
    return pos, nrm, col, idx


def read_polygons(path):
    """(positions, faces) of an OFF or OBJ file (vertices and faces only)."""
    pts, faces = [], []
    if path.lower().endswith(".off"):
        words = [l.split("#")[0].split() for l in open(path)]
        words = [w for w in words if w]
        start = 1 if words[0][0].endswith("OFF") and len(words[0]) == 1 else 0
        head = words[start] if start else words[0][1:]
        nv, nf = int(head[0]), int(head[1])
        body = words[start + 1:]
        pts = [tuple(map(float, w[:3])) for w in body[:nv]]
        faces = [[int(x) for x in w[1:1 + int(w[0])]] for w in body[nv:nv + nf]]
    else:
        for line in open(path):
            w = line.split()
            if w and w[0] == "v":
                pts.append(tuple(map(float, w[1:4])))
            elif w and w[0] == "f":
                faces.append([int(x.split("/")[0]) - 1 for x in w[1:]])
    return pts, faces


def flat_mesh(pts, faces, grey=0.75):
    """GLB-like arrays of a polygon mesh with flat normals: one vertex per face corner."""
    pos, nrm, col, idx = [], [], [], []
    for f in faces:
        a, b, c = pts[f[0]], pts[f[1]], pts[f[2]]
        u = [b[k] - a[k] for k in range(3)]
        v = [c[k] - a[k] for k in range(3)]
        n = (u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0])
        ln = math.sqrt(sum(x * x for x in n)) or 1.0
        base = len(pos) // 3
        for k in f:
            pos.extend(pts[k])
            nrm.extend(x / ln for x in n)
            col.extend((grey, grey, grey))
        for t in range(1, len(f) - 1):
            idx.extend((base, base + t, base + t + 1))
    return pos, nrm, col, idx


def write_png(path, w, h, rgb):
    raw = b"".join(b"\x00" + bytes(rgb[y * w * 3:(y + 1) * w * 3]) for y in range(h))

    def chunk(t, d):
        c = struct.pack(">I", len(d)) + t + d
        return c + struct.pack(">I", zlib.crc32(t + d) & 0xFFFFFFFF)

    png = b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 8, 2, 0, 0, 0))
    png += chunk(b"IDAT", zlib.compress(raw, 9)) + chunk(b"IEND", b"")
    open(path, "wb").write(png)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("glb")
    ap.add_argument("png")
    ap.add_argument("--size", type=int, default=640)
    ap.add_argument("--up", choices=["y", "z"], default="y")
    ap.add_argument("--azimuth", type=float, default=30.0)
    ap.add_argument("--elevation", type=float, default=20.0)
    ap.add_argument("--edges", action="store_true", help="a polygon mesh: draw its edges")
    a = ap.parse_args()
    edges = []
    if a.glb.lower().endswith((".off", ".obj")):
        pts, faces = read_polygons(a.glb)
        pos, nrm, col, idx = flat_mesh(pts, faces)
        if a.edges:
            corner = 0
            for f in faces:
                edges.extend((corner + k, corner + (k + 1) % len(f)) for k in range(len(f)))
                corner += len(f)
    else:
        pos, nrm, col, idx = read_glb(a.glb)
    nv = len(pos) // 3
    # Camera: rotate the model so that `up` is screen-up, then azimuth about up, elevation about x.
    az, el = math.radians(a.azimuth), math.radians(a.elevation)

    def view(x, y, z):
        if a.up == "z":
            x, y, z = x, z, -y
        x, z = x * math.cos(az) + z * math.sin(az), -x * math.sin(az) + z * math.cos(az)
        y, z = y * math.cos(el) - z * math.sin(el), y * math.sin(el) + z * math.cos(el)
        return x, y, z  # screen x right, y up, z towards the viewer

    P = [view(pos[3 * i], pos[3 * i + 1], pos[3 * i + 2]) for i in range(nv)]
    N = [view(nrm[3 * i], nrm[3 * i + 1], nrm[3 * i + 2]) for i in range(nv)]
    lo = [min(p[k] for p in P) for k in range(2)]
    hi = [max(p[k] for p in P) for k in range(2)]
    W = a.size
    scale = 0.92 * W / max(hi[0] - lo[0], hi[1] - lo[1])
    H = int((hi[1] - lo[1]) * scale / 0.92) + 1
    cx, cy = W / 2 - (lo[0] + hi[0]) / 2 * scale, H / 2 + (lo[1] + hi[1]) / 2 * scale
    S = [(cx + p[0] * scale, cy - p[1] * scale, p[2]) for p in P]
    light = (0.3, 0.5, 0.8)
    ln = math.sqrt(sum(c * c for c in light))
    light = tuple(c / ln for c in light)
    shade = []
    for i in range(nv):
        n = N[i]
        lam = abs(n[0] * light[0] + n[1] * light[1] + n[2] * light[2])  # two-sided
        f = 0.35 + 0.65 * lam
        shade.append((col[3 * i] * f, col[3 * i + 1] * f, col[3 * i + 2] * f))
    zbuf = [-1e300] * (W * H)
    img = bytearray([255] * (W * H * 3))
    for t in range(0, len(idx), 3):
        i0, i1, i2 = idx[t], idx[t + 1], idx[t + 2]
        (x0, y0, z0), (x1, y1, z1), (x2, y2, z2) = S[i0], S[i1], S[i2]
        area = (x1 - x0) * (y2 - y0) - (x2 - x0) * (y1 - y0)
        if area == 0:
            continue
        xa, xb = max(int(min(x0, x1, x2)), 0), min(int(max(x0, x1, x2)) + 1, W - 1)
        ya, yb = max(int(min(y0, y1, y2)), 0), min(int(max(y0, y1, y2)) + 1, H - 1)
        c0, c1, c2 = shade[i0], shade[i1], shade[i2]
        for py in range(ya, yb + 1):
            for px in range(xa, xb + 1):
                qx, qy = px + 0.5, py + 0.5
                w1 = ((qx - x0) * (y2 - y0) - (x2 - x0) * (qy - y0)) / area
                w2 = ((x1 - x0) * (qy - y0) - (qx - x0) * (y1 - y0)) / area
                w0 = 1 - w1 - w2
                if w0 < 0 or w1 < 0 or w2 < 0:
                    continue
                z = w0 * z0 + w1 * z1 + w2 * z2
                k = py * W + px
                if z <= zbuf[k]:
                    continue
                zbuf[k] = z
                for ch in range(3):
                    v = w0 * c0[ch] + w1 * c1[ch] + w2 * c2[ch]
                    img[3 * k + ch] = max(0, min(255, int(v * 255 + 0.5)))
    for i0, i1 in edges:  # dark lines over the faces, visible where they are not behind a face
        (x0, y0, z0), (x1, y1, z1) = S[i0], S[i1]
        steps = int(max(abs(x1 - x0), abs(y1 - y0))) + 1
        for t in range(steps + 1):
            f = t / steps
            px, py, z = int(x0 + f * (x1 - x0)), int(y0 + f * (y1 - y0)), z0 + f * (z1 - z0)
            if 0 <= px < W and 0 <= py < H:
                k = py * W + px
                if z >= zbuf[k] - 1e-3 * scale ** -1 * W:
                    img[3 * k:3 * k + 3] = bytes((40, 40, 40))
    write_png(a.png, W, H, img)


if __name__ == "__main__":
    main()
