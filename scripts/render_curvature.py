#!/usr/bin/env python3
"""Renders patch JSON files (subd2nurbs-patches v1, docs/formats.md) side by side, coloured by
mean curvature, seen from above: for comparing conversions near a pole.

    python3 scripts/render_curvature.py OUT.png "title A" a.json "title B" b.json [--zmin Z]

Each patch is evaluated on a grid (numpy; B-spline basis with first and second derivatives,
The NURBS Book A2.3), the mean curvature H = (EN - 2FM + GL) / (2(EG - F^2)) is computed from
the fundamental forms, and the part with z >= zmin is drawn in the xy plane (Gouraud-shaded
grids, painter's order by z) with one colour scale for all panels (1st to 99th percentile). Needs python3-numpy and python3-matplotlib.
"""
import json
import sys

import numpy as np
import matplotlib
matplotlib.use("Agg")
import matplotlib.pyplot as plt


def flat(kv):
    return np.repeat(np.array(kv["values"], float), kv["mults"])


def basis(U, p, x):
    """Values, first and second derivatives of all basis functions at x (NURBS Book A2.3)."""
    n = len(U) - p - 1
    span = p
    while span < n - 1 and U[span + 1] <= x:
        span += 1
    ders = np.zeros((3, p + 1))
    ndu = np.zeros((p + 1, p + 1))
    ndu[0, 0] = 1.0
    left = np.zeros(p + 1)
    right = np.zeros(p + 1)
    for j in range(1, p + 1):
        left[j] = x - U[span + 1 - j]
        right[j] = U[span + j] - x
        saved = 0.0
        for r in range(j):
            ndu[j, r] = right[r + 1] + left[j - r]
            temp = ndu[r, j - 1] / ndu[j, r]
            ndu[r, j] = saved + right[r + 1] * temp
            saved = left[j - r] * temp
        ndu[j, j] = saved
    ders[0] = ndu[:, p]
    a = np.zeros((2, p + 1))
    for r in range(p + 1):
        s1, s2 = 0, 1
        a[0, 0] = 1.0
        for k in range(1, 3):
            d = 0.0
            rk, pk = r - k, p - k
            if r >= k:
                a[s2, 0] = a[s1, 0] / ndu[pk + 1, rk]
                d = a[s2, 0] * ndu[rk, pk]
            j1 = 1 if rk >= -1 else -rk
            j2 = k - 1 if r - 1 <= pk else p - r
            for j in range(j1, j2 + 1):
                a[s2, j] = (a[s1, j] - a[s1, j - 1]) / ndu[pk + 1, rk + j]
                d += a[s2, j] * ndu[rk + j, pk]
            if r <= pk:
                a[s2, k] = -a[s1, k - 1] / ndu[pk + 1, r]
                d += a[s2, k] * ndu[r, pk]
            ders[k, r] = d
            s1, s2 = s2, s1
    ders[1] *= p
    ders[2] *= p * (p - 1)
    full = np.zeros((3, n))
    full[:, span - p:span + 1] = ders
    return full


def sample(patch, mu, mv):
    """Grids (mu x mv) of points and mean curvature over the patch's domain."""
    du, dv = patch["degree"]
    U, V = flat(patch["knots_u"]), flat(patch["knots_v"])
    nu, nv = patch["num_poles"]
    P = np.array(patch["poles"], float).reshape(nu, nv, 3)
    if "weights" in patch:
        raise SystemExit("rational patches are not supported by this script")
    Bu = np.array([basis(U, du, x) for x in np.linspace(1e-5, 1, mu)])  # (mu, 3, nu)
    Bv = np.array([basis(V, dv, x) for x in np.linspace(0, 1, mv)])     # (mv, 3, nv)
    d = lambda a, b: np.einsum("si,tj,ijk->stk", Bu[:, a], Bv[:, b], P)
    X, Xu, Xv, Xuu, Xuv, Xvv = d(0, 0), d(1, 0), d(0, 1), d(2, 0), d(1, 1), d(0, 2)
    n = np.cross(Xu, Xv)
    n /= np.maximum(np.linalg.norm(n, axis=2, keepdims=True), 1e-300)
    dot = lambda a, b: np.einsum("stk,stk->st", a, b)
    E, F, G = dot(Xu, Xu), dot(Xu, Xv), dot(Xv, Xv)
    L, M, N = dot(Xuu, n), dot(Xuv, n), dot(Xvv, n)
    H = (E * N - 2 * F * M + G * L) / (2 * (E * G - F * F))
    return X, H


def load(path, zmin):
    doc = json.load(open(path))
    grids = []
    for patch in doc["patches"]:
        P = np.array(patch["poles"], float)
        if P[:, 2].max() < zmin:
            continue
        if patch["kind"] == "polar_cap":  # one patch around the whole pole: sample it finely
            mv = 16 * (patch["num_poles"][1] - 3) + 1
            grids.append(sample(patch, 120, mv))
        else:
            grids.append(sample(patch, 17, 17))
    return grids, len(doc["patches"])


def main():
    args = sys.argv[1:]
    zmin = 0.9
    if "--zmin" in args:
        i = args.index("--zmin")
        zmin = float(args[i + 1])
        del args[i:i + 2]
    out, panels = args[0], list(zip(args[1::2], args[2::2]))
    data = [(title,) + load(path, zmin) for title, path in panels]
    allH = np.concatenate([H[X[:, :, 2] >= zmin] for _, grids, _ in data for X, H in grids])
    lo, hi = np.percentile(allH, 1), np.percentile(allH, 99)
    norm = matplotlib.colors.Normalize(lo, hi)
    fig, axes = plt.subplots(1, len(data), figsize=(6 * len(data), 6.2))
    for ax, (title, grids, count) in zip(np.atleast_1d(axes), data):
        for X, H in sorted(grids, key=lambda g: g[0][:, :, 2].mean()):  # painter's order
            Hm = np.where(X[:, :, 2] >= zmin, H, np.nan)
            ax.pcolormesh(X[:, :, 0], X[:, :, 1], np.clip(Hm, lo, hi), cmap="turbo", norm=norm, shading="gouraud")
        ax.set_aspect("equal")
        ax.set_title(f"{title}\n({count} faces)")
        ax.set_xticks([])
        ax.set_yticks([])
    fig.colorbar(matplotlib.cm.ScalarMappable(norm=norm, cmap="turbo"), ax=axes, shrink=0.8,
                 label="mean curvature H")
    fig.savefig(out, dpi=110, bbox_inches="tight")
    print(f"wrote {out}: colour scale [{lo:.4g}, {hi:.4g}] (1st to 99th percentile)")
    for title, grids, _ in data:
        H = np.concatenate([H[X[:, :, 2] >= zmin] for X, H in grids])
        print(f"  {title}: H min {H.min():.4g} max {H.max():.4g}")


if __name__ == "__main__":
    main()
