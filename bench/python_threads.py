#!/usr/bin/python3
"""Throughput of subd2nurbs.convert from Python: 1 thread against N threads (#32 item 5).

Converts a list of corpus cages JOBS times each in three ways and prints the wall time (median
of REPEATS runs, the three interleaved so that a change of the machine's load hits all alike):

* one Python thread, each conversion on every core (`threads` not given: the default);
* one Python thread, each conversion on one core (`threads=1`);
* N Python threads, `threads` not given: the conversions running at once share the cores
  (core/util/parallel.h JobShare);
* N Python threads, each conversion on one core (`threads=1`).

"cores busy" is the process's CPU time over the wall time. The results of the N-thread run are
checked against the sequential run's (the same faces and poles, the same deviation to the bit).
Not a unit test: the numbers depend on the machine and its load.

    PYTHONPATH=build/python /usr/bin/python3 bench/python_threads.py [--threads 4] [--repeats 3]
"""

import argparse
import hashlib
import os
import statistics
import sys
import time
from concurrent.futures import ThreadPoolExecutor

import subd2nurbs as s2n

HERE = os.path.dirname(os.path.abspath(__file__))
CORPUS = os.path.join(HERE, "..", "tests", "data", "corpus")
NAMES = ("catmark_car", "catmark_pawn", "catmark_rook", "catmark_bishop")


def cpu_seconds():
    """User + system CPU time of this process so far (every thread)."""
    t = os.times()
    return t.user + t.system


def fingerprint(result):
    """What must not depend on the threads: every patch's knots, poles and weights, to the bit,
    and the report's deviation."""
    h = hashlib.sha256()
    for p in result.patches:
        for key in ("knots_u", "mults_u", "knots_v", "mults_v", "poles", "weights"):
            if p[key] is not None:
                h.update(p[key].tobytes())
    return h.hexdigest(), repr(result.report.get("deviation"))


def run(cages, python_threads, converter_threads, cpu):
    """Wall time of converting `cages` on `python_threads` threads, each conversion with
    `converter_threads` (None: the default); appends CPU time / wall to `cpu`. Returns the wall
    time and the results' fingerprints in the cages' order."""
    kwargs = {} if converter_threads is None else {"threads": converter_threads}
    convert = lambda c: fingerprint(s2n.convert(c, **kwargs))
    start, start_cpu = time.perf_counter(), cpu_seconds()
    if python_threads == 1:
        prints = [convert(c) for c in cages]
    else:
        with ThreadPoolExecutor(python_threads) as pool:
            prints = list(pool.map(convert, cages))
    wall = time.perf_counter() - start
    cpu.append((cpu_seconds() - start_cpu) / wall)
    return wall, prints


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--threads", type=int, default=4)
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--jobs", type=int, default=2, help="conversions of each cage per run")
    a = ap.parse_args()
    cages = [s2n.read_obj(os.path.join(CORPUS, n + ".obj")) for n in NAMES] * a.jobs
    s2n.convert(cages[0])  # warm up (OCCT's first-use initialisation)
    configs = [("1 thread, each conversion on every core", 1, None),
               ("1 thread, threads=1", 1, 1),
               ("%d threads, threads not given" % a.threads, a.threads, None),
               ("%d threads, threads=1" % a.threads, a.threads, 1)]
    walls = [[] for _ in configs]
    busy = [[] for _ in configs]
    reference = None
    for _ in range(a.repeats):
        for k, (_, python_threads, converter_threads) in enumerate(configs):
            wall, prints = run(cages, python_threads, converter_threads, busy[k])
            walls[k].append(wall)
            if reference is None:
                reference = prints
            elif prints != reference:
                print("results differ from the sequential run's: %s" % configs[k][0], file=sys.stderr)
                return 1
    load = os.getloadavg()[0]
    medians = [statistics.median(w) for w in walls]
    print("%d conversions, %d CPUs, load average %.1f at the end; results identical in every run"
          % (len(cages), os.cpu_count(), load))
    print()
    print("| run | wall, median (s) | cores busy | throughput against 1 thread, threads=1 |"
          " against 1 thread, every core |")
    print("|---|---|---|---|---|")
    for k, (name, _, _) in enumerate(configs):
        print("| %s | %.3f | %.2f | %.2fx | %.2fx |" % (name, medians[k], statistics.median(busy[k]),
                                                    medians[1] / medians[k], medians[0] / medians[k]))
    return 0


if __name__ == "__main__":
    sys.exit(main())
