#!/usr/bin/env python3
"""Packed faces against one face per quad, through the command line: table 8 of docs/benchmarks.md.

Usage: scripts/bench_packing.py SUBD2NURBS CORPUS_DIR REPS > table.md

Each model is converted REPS times with `convert X -o X.step -q --faces per-quad` and REPS
times with `--faces packed` (the default), in alternating order, under /usr/bin/time (no
report: the whole pipeline a user waits for). One more run of each with --report gives the
counts (faces, edges, poles). Generated cages, written to a temporary directory: the regular
10 000-quad torus (100 x 100), the same torus with 36 edge rotations (72 valence-3 and 72
valence-5 vertices, as bench_convert's torus_ev) and the regular 100 000-quad torus (500 x
200). A second table gives the face totals over every two-manifold corpus shape.
"""
import json
import os
import statistics
import subprocess
import sys
import tempfile

from bench_models import torus_obj


def torus_with_rotated_edges_obj(path, n=100, sites=6, spacing=16, first=8):
    """torus(n, n) with an edge rotation at each site: (a b c d), (b e f c) -> (d a b e), (e f c d)."""
    torus_obj(path, n, n)
    with open(path) as f:
        lines = f.read().splitlines()
    verts = [line for line in lines if line.startswith("v ")]
    faces = [[int(t) for t in line.split()[1:]] for line in lines if line.startswith("f ")]

    def vtx(a, b):
        return (a % n) * n + (b % n) + 1

    for si in range(sites):
        for sj in range(sites):
            i, j = first + spacing * si, first + spacing * sj
            a, b, c, d = vtx(i, j), vtx(i + 1, j), vtx(i + 1, j + 1), vtx(i, j + 1)
            e, g = vtx(i + 2, j), vtx(i + 2, j + 1)
            f1, f2 = (i % n) * n + (j % n), ((i + 1) % n) * n + (j % n)
            assert faces[f1] == [a, b, c, d] and faces[f2] == [b, e, g, c]
            faces[f1], faces[f2] = [d, a, b, e], [e, g, c, d]
    with open(path, "w") as f:
        f.write("\n".join(verts) + "\n")
        for q in faces:
            f.write("f %d %d %d %d\n" % tuple(q))


def timed(cli, obj, faces, tmp):
    step = os.path.join(tmp, "out.step")
    timing = os.path.join(tmp, "time.txt")
    subprocess.run(["/usr/bin/time", "-f", "%e %M", "-o", timing, cli, "convert", obj, "-o", step, "-q",
                    "--faces", faces], check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    with open(timing) as f:
        wall, rss_kb = f.read().split()[-2:]
    return float(wall), int(rss_kb) / 1024.0, os.path.getsize(step) / 1e6


def counts(cli, obj, faces, tmp):
    report = os.path.join(tmp, "r.json")
    subprocess.run([cli, "convert", obj, "-o", os.path.join(tmp, "out.brep"), "-q", "--faces", faces,
                    "--report", report], check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    with open(report) as f:
        r = json.load(f)
    return r["brep"]["faces"], r["brep"]["edges"], r["faces"]["poles"], r["brep"]["valid"]


def json_faces(cli, obj, faces, tmp):
    out = os.path.join(tmp, "p.json")
    res = subprocess.run([cli, "convert", obj, "-o", out, "-q", "--faces", faces],
                         stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    if res.returncode != 0:
        return None
    with open(out) as f:
        return len(json.load(f)["patches"])


def main():
    cli, corpus, reps = sys.argv[1], sys.argv[2], int(sys.argv[3])
    with tempfile.TemporaryDirectory() as tmp:
        t10 = os.path.join(tmp, "torus_10k.obj")
        torus_obj(t10, 100, 100)
        t10ev = os.path.join(tmp, "torus_10k_ev.obj")
        torus_with_rotated_edges_obj(t10ev)
        t100 = os.path.join(tmp, "torus_100k.obj")
        torus_obj(t100, 500, 200)
        models = [("10 000-quad regular torus", t10), ("10 000-quad torus with EVs", t10ev),
                  ("100 000-quad regular torus", t100)]
        models += [(name, os.path.join(corpus, name + ".obj"))
                   for name in ("catmark_bishop", "catmark_rook", "catmark_car", "catmark_pawn", "catmark_helmet")]
        print("| model | faces | wall, median (s) | peak RSS, median (MB) | STEP (MB) | B-rep faces | B-rep edges | poles | "
              "packed / per-quad: wall, faces, poles |")
        print("|---|---|---|---|---|---|---|---|---|")
        for label, obj in models:
            runs = {"per-quad": [], "packed": []}
            for rep in range(reps):
                order = ("per-quad", "packed") if rep % 2 == 0 else ("packed", "per-quad")
                for mode in order:
                    runs[mode].append(timed(cli, obj, mode, tmp))
            row = {}
            for mode in ("per-quad", "packed"):
                wall = statistics.median(x[0] for x in runs[mode])
                rss = statistics.median(x[1] for x in runs[mode])
                size = runs[mode][-1][2]
                faces, edges, poles, valid = counts(cli, obj, mode, tmp)
                assert valid, (label, mode)
                row[mode] = (wall, rss, size, faces, edges, poles)
            q, p = row["per-quad"], row["packed"]
            for mode, r in (("per-quad", q), ("packed", p)):
                ratio = "%.2f, %.3f, %.3f" % (p[0] / q[0], p[3] / q[3], p[5] / q[5]) if mode == "packed" else ""
                print("| %s | %s | %.2f | %.0f | %.2f | %d | %d | %d | %s |"
                      % (label if mode == "per-quad" else "", mode, r[0], r[1], r[2], r[3], r[4], r[5], ratio))
        # Face totals over the corpus (patch JSON: no B-rep, so fast).
        total = {"per-quad": 0, "packed": 0}
        shapes = 0
        for name in sorted(os.listdir(corpus)):
            if not name.endswith(".obj"):
                continue
            counted = {mode: json_faces(cli, os.path.join(corpus, name), mode, tmp) for mode in total}
            if None in counted.values():
                continue  # refused (non-manifold): not converted either way
            shapes += 1
            for mode in total:
                total[mode] += counted[mode]
        print()
        print("Every corpus shape that converts (%d of them), `convert X -o X.json` (the patches, no B-rep):"
              % shapes)
        print()
        print("| faces | total over the corpus |")
        print("|---|---|")
        for mode in ("per-quad", "packed"):
            print("| %s | %d |" % (mode, total[mode]))


if __name__ == "__main__":
    main()
