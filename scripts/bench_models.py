#!/usr/bin/env python3
"""Real models through the command line, as a user runs them: table 6 of docs/benchmarks.md.

Usage: scripts/bench_models.py SUBD2NURBS CORPUS_DIR REPS > table.md

Each model is converted REPS times with the report (`convert X -o X.step --report r.json`, the
defaults) and REPS times without it, alternating, under /usr/bin/time, and checked REPS times
(`check X --json q.json`). The table gives the median wall time and peak RSS with the report,
the STEP size, the faces and the poles (from the report), the patches' and the quality stage's
own times, and what the report costs against the conversion: the wall time `--report` adds
(median with it minus median without it, over the median without it; the quality stage runs
beside packing, OCCT's B-rep and the STEP writing, which use one core), and for `check` (no
B-rep) the time it waited for the stage after its own stages (`quality_wait_ms`) over the
median conversion without the report. Generated cages, written to a temporary directory: a
regular 100 000-quad torus (500 x 200) and the triangle mesh of catmark_car (every face split
into triangles, as a game asset or a scan would give it).
"""
import json
import math
import os
import statistics
import subprocess
import sys
import tempfile


def torus_obj(path, nu, nv, major=3.0, minor=1.0):
    with open(path, "w") as f:
        for i in range(nu):
            a = 2 * math.pi * i / nu
            for j in range(nv):
                b = 2 * math.pi * j / nv
                r = major + minor * math.cos(b)
                f.write("v %.17g %.17g %.17g\n" % (r * math.cos(a), r * math.sin(a), minor * math.sin(b)))
        for i in range(nu):
            for j in range(nv):
                def idx(x, y):
                    return (x % nu) * nv + (y % nv) + 1
                f.write("f %d %d %d %d\n" % (idx(i, j), idx(i + 1, j), idx(i + 1, j + 1), idx(i, j + 1)))


def triangulated_obj(src, dst):
    """Every face split into a fan of triangles; tags dropped (a mesh, not a cage)."""
    with open(src) as f, open(dst, "w") as g:
        for line in f:
            if line.startswith("v "):
                g.write(line)
            elif line.startswith("f "):
                ids = [t.split("/")[0] for t in line.split()[1:]]
                for k in range(1, len(ids) - 1):
                    g.write("f %s %s %s\n" % (ids[0], ids[k], ids[k + 1]))


def timed(cmd, out_dir):
    """Runs cmd under /usr/bin/time: (wall s, peak RSS MB)."""
    timing = os.path.join(out_dir, "time.txt")
    subprocess.run(["/usr/bin/time", "-f", "%e %M", "-o", timing] + cmd, check=True,
                   stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    with open(timing) as f:
        wall, rss_kb = f.read().split()[-2:]
    return float(wall), int(rss_kb) / 1024.0


def run(cli, obj, out_dir, report=True):
    """convert obj to STEP (with --report): wall, RSS, STEP MB, the report (or None)."""
    step = os.path.join(out_dir, "out.step")
    path = os.path.join(out_dir, "r.json")
    wall, rss = timed([cli, "convert", obj, "-o", step, "-q"] + (["--report", path] if report else []), out_dir)
    r = None
    if report:
        with open(path) as f:
            r = json.load(f)
    return wall, rss, os.path.getsize(step) / 1e6, r


def check_quality_wait_s(cli, obj, out_dir):
    """check obj: the time it waited for its quality stage after its own stages (s)."""
    path = os.path.join(out_dir, "q.json")
    timed([cli, "check", obj, "--json", path, "-q"], out_dir)
    with open(path) as f:
        return json.load(f)["quality_wait_ms"] / 1000.0


def main():
    cli, corpus, reps = sys.argv[1], sys.argv[2], int(sys.argv[3])
    with tempfile.TemporaryDirectory() as tmp:
        torus = os.path.join(tmp, "torus_100k.obj")
        torus_obj(torus, 500, 200)
        car_tris = os.path.join(tmp, "car_triangles.obj")
        triangulated_obj(os.path.join(corpus, "catmark_car.obj"), car_tris)
        models = [("catmark_bishop", os.path.join(corpus, "catmark_bishop.obj")),
                  ("catmark_rook", os.path.join(corpus, "catmark_rook.obj")),
                  ("catmark_car", os.path.join(corpus, "catmark_car.obj")),
                  ("catmark_pawn", os.path.join(corpus, "catmark_pawn.obj")),
                  ("catmark_helmet", os.path.join(corpus, "catmark_helmet.obj")),
                  ("catmark_car as triangles", car_tris),
                  ("100 000-quad regular torus", torus)]
        print("| model (cage faces) | wall, median (s) | peak RSS, median (MB) | STEP (MB) | B-rep faces | poles | poles per face | patches / quality stage (s) | wall without --report (s) | --report adds (of that wall) | check's wait for its quality stage / conversion |")
        print("|---|---|---|---|---|---|---|---|---|---|---|")
        for label, obj in models:
            with open(obj) as f:
                faces = sum(1 for line in f if line.startswith("f "))
            runs, plain, checks = [], [], []
            for _ in range(reps):  # alternating, so that the machine's drift hits all alike
                runs.append(run(cli, obj, tmp))
                plain.append(run(cli, obj, tmp, report=False)[0])
                checks.append(check_quality_wait_s(cli, obj, tmp))
            wall = statistics.median(x[0] for x in runs)
            rss = statistics.median(x[1] for x in runs)
            without = statistics.median(plain)
            size, r = runs[-1][2], runs[-1][3]
            ms = r["timings_ms"]
            quality_s = statistics.median(x[3].get("quality_ms", 0.0) for x in runs) / 1000.0
            # The B-rep's faces and their poles (packed faces by default; the quad patches
            # before packing are r["patches"]).
            poles = r["faces"]["poles"]
            nfaces = r["brep"]["faces"]
            added = (wall - without) / without
            check_ratio = statistics.median(checks) / without
            print("| %s (%d) | %.2f | %.0f | %.1f | %d | %d | %.1f | %.2f / %.2f | %.2f | %+.3f | %.3f |"
                  % (label, faces, wall, rss, size, nfaces, poles, poles / nfaces,
                     ms["patches"] / 1000.0, quality_s, without, added, check_ratio))

if __name__ == "__main__":
    main()
