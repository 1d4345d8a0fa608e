#!/usr/bin/python3
"""Throughput of subd2nurbs.convert from Python: 1 thread against N threads (#32 item 5).

Converts a list of corpus cages JOBS times each, once in one thread and once spread over N
threads, and prints the wall time (median of REPEATS runs) and the speed-up. Not a unit test:
the numbers depend on the machine and its load.

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


def run(cages, threads):
    start = time.perf_counter()
    if threads == 1:
        for c in cages:
            s2n.convert(c)
    else:
        with ThreadPoolExecutor(threads) as pool:
            list(pool.map(s2n.convert, cages))
    return time.perf_counter() - start


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--threads", type=int, default=4)
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--jobs", type=int, default=2, help="conversions of each cage per run")
    a = ap.parse_args()
    cages = [s2n.read_obj(os.path.join(CORPUS, n + ".obj")) for n in NAMES] * a.jobs
    s2n.convert(cages[0])  # warm up (OCCT's first-use initialisation)
    one = statistics.median(run(cages, 1) for _ in range(a.repeats))
    many = statistics.median(run(cages, a.threads) for _ in range(a.repeats))
    load = os.getloadavg()[0]
    print("| conversions | CPUs | load average | 1 thread (s) | %d threads (s) | speed-up |" % a.threads)
    print("|---|---|---|---|---|---|")
    print("| %d | %d | %.1f | %.3f | %.3f | %.2fx |" % (len(cages), os.cpu_count(), load, one, many, one / many))
    return 0


if __name__ == "__main__":
    sys.exit(main())
