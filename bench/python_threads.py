#!/usr/bin/python3
"""Throughput of subd2nurbs.convert from Python: 1 thread against N threads (#32 item 5).

Converts a list of corpus cages JOBS times each, once in one thread and once spread over N
threads, and prints the wall time (median of REPEATS runs) and the speed-up. Not a unit test:
the numbers depend on the machine and its load. "cores busy" is the process's CPU time over
the wall time: a one-thread run that already keeps every core busy leaves threads nothing to add.

    PYTHONPATH=build/python /usr/bin/python3 bench/python_threads.py [--threads 4] [--repeats 3]
"""

import argparse
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


def run(cages, threads, cpu=None):
    """Wall time of converting `cages` on `threads` threads; appends the CPU time / wall (the
    cores the run kept busy) to `cpu` when given."""
    start, start_cpu = time.perf_counter(), cpu_seconds()
    if threads == 1:
        for c in cages:
            s2n.convert(c)
    else:
        with ThreadPoolExecutor(threads) as pool:
            list(pool.map(s2n.convert, cages))
    wall = time.perf_counter() - start
    if cpu is not None:
        cpu.append((cpu_seconds() - start_cpu) / wall)
    return wall


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--threads", type=int, default=4)
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--jobs", type=int, default=2, help="conversions of each cage per run")
    a = ap.parse_args()
    cages = [s2n.read_obj(os.path.join(CORPUS, n + ".obj")) for n in NAMES] * a.jobs
    s2n.convert(cages[0])  # warm up (OCCT's first-use initialisation)
    # Interleaved (1, N, 1, N, ...) so that a change of the machine's load hits both alike.
    ones, manys, cpu_one, cpu_many = [], [], [], []
    for _ in range(a.repeats):
        ones.append(run(cages, 1, cpu_one))
        manys.append(run(cages, a.threads, cpu_many))
    one, many = statistics.median(ones), statistics.median(manys)
    load = os.getloadavg()[0]
    print("| conversions | CPUs | load average | 1 thread (s) | cores busy | %d threads (s) | cores busy | speed-up |"
          % a.threads)
    print("|---|---|---|---|---|---|---|---|")
    print("| %d | %d | %.1f | %.3f | %.2f | %.3f | %.2f | %.2fx |" % (
        len(cages), os.cpu_count(), load, one, statistics.median(cpu_one), many, statistics.median(cpu_many),
        one / many))
    return 0


if __name__ == "__main__":
    sys.exit(main())
