#!/usr/bin/env python3
"""Interpolation benchmark: `convert --fit interpolate` against a plain `convert` of the same
cage, in the same run, repetitions interleaved; prints a Markdown section for docs/benchmarks.md.

Usage: bench_fit.py BUILD_DIR [REPS]   (default 3 repetitions; about 10 minutes on 2 cores)
       BENCH_FIT_RAW=FILE bench_fit.py ...   also dumps the measurements as JSON
       bench_fit.py --from-raw FILE            the tables again from such a dump

Cages: closed tori of 10 000 (100 x 100) and 100 000 (250 x 400) quads, radii 3 and 1.
Per repetition and cage, each in a fresh process:
  * bench/bench_fit: the interpolation alone (limit operator, sparse LU, condition estimate,
    residual check), its wall time and the process's peak resident memory before and after it;
  * `subd2nurbs convert CAGE -o X.json` (patches, continuity, deviation; no B-rep) without and
    with --fit interpolate: wall time and peak memory of the process (GNU time), and the report's
    timings_ms.fit;
  * for the 10 000-quad cage also `-o X.step` (the whole pipeline: B-rep, check, STEP write).
Wall times are medians over the repetitions; peak memory is the median of ru_maxrss.
"""
import json
import math
import os
import random
import statistics
import subprocess
import sys
import tempfile
import time


CAGES = {"10k": (100, 100), "100k": (250, 400)}
DIAGONAL = math.sqrt(8.0 ** 2 + 8.0 ** 2 + 2.0 ** 2)  # bounding box of the tori: 8 x 8 x 2


def torus(n, m, path):
    with open(path, "w") as f:
        for i in range(n):
            for j in range(m):
                u, v = 2 * math.pi * i / n, 2 * math.pi * j / m
                f.write("v %.12g %.12g %.12g\n" % ((3 + math.cos(v)) * math.cos(u), (3 + math.cos(v)) * math.sin(u),
                                                   math.sin(v)))
        for i in range(n):
            for j in range(m):
                a, b = i * m + j, ((i + 1) % n) * m + j
                c, d = ((i + 1) % n) * m + (j + 1) % m, i * m + (j + 1) % m
                f.write("f %d %d %d %d\n" % (a + 1, b + 1, c + 1, d + 1))


def run(cmd, tmp):
    """Wall seconds, peak RSS in kB, stdout of one process. The peak comes from GNU time, whose
    own child starts small: a child's ru_maxrss includes its parent's size at fork."""
    mem = os.path.join(tmp, "maxrss")
    t = time.monotonic()
    p = subprocess.run(["/usr/bin/time", "-f", "%M", "-o", mem] + cmd, stdout=subprocess.PIPE,
                       stderr=subprocess.DEVNULL)
    wall = time.monotonic() - t
    if p.returncode != 0:
        raise SystemExit("failed: %s" % " ".join(cmd))
    return wall, int(open(mem).read().split()[-1]), p.stdout.decode()


def main():
    if sys.argv[1] == "--from-raw":  # tables again from a BENCH_FIT_RAW dump
        runs = json.load(open(sys.argv[2]))
        results = {(r["cage"], r["kind"], r["output"]): r["runs"] for r in runs}
        print_tables(results, len(runs[0]["runs"]))
        return
    build = sys.argv[1]
    reps = int(sys.argv[2]) if len(sys.argv) > 2 else 3
    exe, fit_exe = os.path.join(build, "subd2nurbs"), os.path.join(build, "bench", "bench_fit")
    tmp = tempfile.mkdtemp()
    cages = CAGES
    paths = {}
    for name, (n, m) in cages.items():
        paths[name] = os.path.join(tmp, name + ".obj")
        torus(n, m, paths[name])
    jobs = []
    for name in cages:
        jobs.append((name, "solve", None))
        for ext in ([".json", ".step"] if name == "10k" else [".json"]):
            jobs.append((name, "plain", ext))
            jobs.append((name, "interpolate", ext))
    results = {}
    for rep in range(reps):
        order = jobs[:]
        random.Random(rep).shuffle(order)
        for name, kind, ext in order:
            key = (name, kind, ext)
            if kind == "solve":
                wall, rss, out = run([fit_exe, paths[name]], tmp)
                d = json.loads(out)
                results.setdefault(key, []).append({"wall": d["fit_ms"] / 1000, "rss": d["peak_kb_after"],
                                                    "rss_before": d["peak_kb_before"], "residual": d["residual_max"],
                                                    "condition": d["condition"]})
            else:
                report = os.path.join(tmp, "r.json")
                cmd = [exe, "convert", paths[name], "-o", os.path.join(tmp, "out" + ext), "-q", "--report", report]
                if kind == "interpolate":
                    cmd += ["--fit", "interpolate"]
                wall, rss, _ = run(cmd, tmp)
                r = json.load(open(report))
                results.setdefault(key, []).append({"wall": wall, "rss": rss, "fit_ms": r["timings_ms"]["fit"],
                                                    "residual": (r["fit"]["residual"] or {}).get("max_relative")})
            print("rep %d %s %s %s: %.2f s" % (rep, name, kind, ext, results[key][-1]["wall"]), file=sys.stderr)

    raw = os.environ.get("BENCH_FIT_RAW")
    if raw:  # the measurements themselves, for a second look
        json.dump([{"cage": k[0], "kind": k[1], "output": k[2], "runs": v} for k, v in results.items()],
                  open(raw, "w"), indent=1)

    print_tables(results, reps)


def print_tables(results, reps):
    cages = CAGES
    def med(key, field):
        return statistics.median(x[field] for x in results[key])

    print("## 6. Interpolation: `convert --fit interpolate` against a plain `convert` (`scripts/bench_fit.py`)")
    print()
    print("Generated by `python3 scripts/bench_fit.py build %d` (%d repetitions, interleaved, medians; each run "
          "a fresh process). Cages: closed tori of 10 000 (100 x 100) and 100 000 (250 x 400) quads. "
          "Peak memory is the process's maximum resident set (GNU time's %%M; for the solve alone, VmHWM before and after it). The solve is the interpolation alone "
          "(`bench/bench_fit`: limit operator, sparse LU, condition estimate, residual check); `convert` to "
          "`.json` runs every stage but the B-rep (patches, continuity, deviation), `.step` the whole pipeline."
          % (reps, reps))
    print()
    print("| cage | vertices | solve alone (s) | solve peak memory (MB, before -> after) | residual (x diagonal) | condition |")
    print("|---|---|---|---|---|---|")
    for name in cages:
        k = (name, "solve", None)
        print("| %s quads | %d | %.3f | %.0f -> %.0f | %.1e | %.3g |" % (
            name, cages[name][0] * cages[name][1], med(k, "wall"), med(k, "rss_before") / 1024, med(k, "rss") / 1024,
            max(x["residual"] for x in results[k]) / DIAGONAL, med(k, "condition")))
    print()
    def spread(key):
        w = [x["wall"] for x in results[key]]
        return "%.2f (%.2f-%.2f)" % (statistics.median(w), min(w), max(w))

    print("| cage | output | plain convert (s, min-max) | with --fit interpolate (s, min-max) | of which fit (s) | ratio of medians | plain peak (MB) | interpolate peak (MB) |")
    print("|---|---|---|---|---|---|---|---|")
    for name in cages:
        for ext in ([".json", ".step"] if name == "10k" else [".json"]):
            a, b = (name, "plain", ext), (name, "interpolate", ext)
            print("| %s quads | %s | %s | %s | %.2f | %.2f | %.0f | %.0f |" % (
                name, ext, spread(a), spread(b), med(b, "fit_ms") / 1000, med(b, "wall") / med(a, "wall"),
                med(a, "rss") / 1024, med(b, "rss") / 1024))
    print()
    print("The residual column is the solve's own check (max |L P - c| over the bounding-box diagonal); the tests "
          "measure residuals independently (docs/fitting.md).")




if __name__ == "__main__":
    main()
