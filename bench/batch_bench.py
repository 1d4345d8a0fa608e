#!/usr/bin/python3
"""Throughput of subd2nurbs-batch (issue #30): files per minute on a folder of models with the
local pool of 1 worker (on every core, and with --threads 1) and 2 workers (one thread each, the
batch's default: cores / workers) and a Dask cluster of 2 workers (dask-scheduler + 2 dask-workers on
127.0.0.1, one thread each, started here) reading the inputs from their path and with the inputs
sent as bytes, against a plain loop of `subd2nurbs convert IN -o OUT.step --report OUT.json -q`
over the same files (the same work, one process at a time).

Every configuration runs REPEATS times, in rounds (every other round in reverse order); wall
times are medians, ratios (speed-up against the 1-worker pool, wall and converters' CPU against
the loop) are taken within each round and their median given, so that a machine shared with
other work moves them less. CPU: the converters' user + system time (the loop's children, the
summary's cpu_s), and the Dask scheduler's and workers' own (from /proc, not their converters).
Peak memory: the largest converter process (its maximum resident set, from the summary's
peak_memory_mb or the loop's wait4) and the driver's own (the batch's Python process, threads
included; the loop's driver is this script's child, negligible). Prints a Markdown table and
the 1-minute load average seen. Not a unit test: the numbers depend on the machine and its load.

    PYTHONPATH=build/python /usr/bin/python3 bench/batch_bench.py build/subd2nurbs tests/data/corpus \
        [--repeats 3] [--level N]
"""

import argparse
import json
import os
import shutil
import statistics
import subprocess
import sys
import tempfile
import time

DRIVER = r"""
import json, resource, sys, time
from subd2nurbs import batch
args = json.loads(sys.argv[1])
start = time.perf_counter()
s = batch.run([args["input"]], args["out"], args["settings"], args.get("scheduler"), workers=args.get("workers"),
              cli=args["cli"], send_inputs=args.get("send", "auto"))
wall = time.perf_counter() - start
print(json.dumps({"wall": wall, "driver_mb": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0,
                  "converter_mb": max(r["peak_memory_mb"] or 0 for r in s.files), "ok": s.ok,
                  "converter_s": sum(r["time_s"] or 0 for r in s.files),
                  "converter_cpu": sum(r["cpu_s"] or 0 for r in s.files),
                  "files": len(s.files)}))
"""

LOOP = r"""
import json, os, resource, subprocess, sys, time
args = json.loads(sys.argv[1])
names = sorted(n for n in os.listdir(args["input"]) if n.endswith(".obj"))
start = time.perf_counter()
ok = 0
busy = 0.0
for n in names:
    stem = os.path.join(args["out"], n[:-4])
    t0 = time.monotonic()
    r = subprocess.run([args["cli"], "convert", os.path.join(args["input"], n), "-o", stem + ".step", "--report",
                        stem + ".report.json", "-q"] + args["extra"], stdout=subprocess.DEVNULL,
                       stderr=subprocess.DEVNULL)
    busy += time.monotonic() - t0
    ok += r.returncode == 0
wall = time.perf_counter() - start
children = resource.getrusage(resource.RUSAGE_CHILDREN)
print(json.dumps({"wall": wall, "driver_mb": 0, "ok": ok, "files": len(names), "converter_s": busy,
                  "converter_cpu": children.ru_utime + children.ru_stime,
                  "converter_mb": children.ru_maxrss / 1024.0}))
"""


def dask_cluster(tmp, tuned=True):
    from subd2nurbs import batch
    env = dict(os.environ, **(batch.dask_environment() if tuned else {}))
    scheduler_file = os.path.join(tmp, "scheduler.json")
    log = open(os.path.join(tmp, "dask.log"), "w")
    procs = [subprocess.Popen([shutil.which("dask-scheduler"), "--host", "127.0.0.1", "--port", "0",
                               "--no-dashboard", "--scheduler-file", scheduler_file], stdout=log,
                              stderr=subprocess.STDOUT, env=env)]
    deadline = time.monotonic() + 120
    while not os.path.exists(scheduler_file):
        if time.monotonic() > deadline:
            raise RuntimeError("dask-scheduler did not start")
        time.sleep(0.1)
    for name in ("w1", "w2"):
        procs.append(subprocess.Popen([shutil.which("dask-worker"), "--scheduler-file", scheduler_file, "--nthreads",
                                       "1", "--no-nanny", "--no-dashboard", "--host", "127.0.0.1", "--name", name,
                                       "--local-directory", os.path.join(tmp, name)], stdout=log,
                                      stderr=subprocess.STDOUT, env=env))
    import distributed
    with distributed.Client(scheduler_file=scheduler_file, timeout="120s") as client:
        client.wait_for_workers(2, timeout=120)
        address = client.scheduler.address
    return address, procs, log


def measure(code, args):
    out = subprocess.run([sys.executable, "-c", code, json.dumps(args)], check=True, stdout=subprocess.PIPE,
                         text=True)
    return json.loads(out.stdout.strip().splitlines()[-1])


def cpu_seconds(procs):
    """User + system CPU time of these processes themselves (not their children), seconds."""
    total = 0
    for p in procs:
        try:
            with open("/proc/%d/stat" % p.pid) as f:
                fields = f.read().rsplit(")", 1)[1].split()
            total += int(fields[11]) + int(fields[12])  # utime, stime (fields 14 and 15)
        except OSError:
            pass
    return total / os.sysconf("SC_CLK_TCK")


LOOP_NAME = "plain `convert` loop"
ONE = "local pool, 1 worker"
ONE_T1 = "local pool, 1 worker, --threads 1"


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("cli")
    ap.add_argument("input", help="a folder of .obj files (not searched recursively by the loop)")
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--level", help="convert --level (default: the tolerance's choice)")
    ap.add_argument("--dask-defaults", action="store_true",
                    help="Dask's default settings for the cluster (not batch.DASK_CONFIG's quieter monitors)")
    a = ap.parse_args()
    cli = os.path.abspath(a.cli)
    settings = {"level": a.level} if a.level else {}
    extra = ["--level", a.level] if a.level else []
    tmp = tempfile.mkdtemp(prefix="s2n-batch-bench-")
    address, procs, log = dask_cluster(tmp, tuned=not a.dask_defaults)
    configs = [(LOOP_NAME, LOOP, {"extra": extra}),
               (ONE, DRIVER, {"workers": 1, "settings": settings}),
               (ONE_T1, DRIVER, {"workers": 1, "settings": dict(settings, threads=1)}),
               ("local pool, 2 workers", DRIVER, {"workers": 2, "settings": settings}),
               ("Dask cluster, 2 workers", DRIVER, {"scheduler": address, "settings": settings, "send": "never"}),
               ("Dask cluster, 2 workers, inputs sent", DRIVER, {"scheduler": address, "settings": settings,
                                                                 "send": "always"})]
    results = {name: [] for name, _, _ in configs}
    loads = []
    try:
        for rep in range(a.repeats):
            # Every other round in reverse order: each configuration runs early and late; the
            # local pool of 2 and the Dask cluster stay next to each other.
            for name, code, extra_args in (configs if rep % 2 == 0 else list(reversed(configs))):
                out = os.path.join(tmp, "out")
                shutil.rmtree(out, ignore_errors=True)
                os.makedirs(out)
                load0 = os.getloadavg()[0]
                dask0 = cpu_seconds(procs)
                r = measure(code, dict(extra_args, input=os.path.abspath(a.input), out=out, cli=cli))
                r["dask_cpu"] = cpu_seconds(procs) - dask0
                r["rep"] = rep
                loads += [load0, os.getloadavg()[0]]
                results[name].append(r)
                print("rep %d %-38s %.1f s, converters' CPU %.1f s, %d/%d ok, load %.1f-%.1f" % (
                    rep + 1, name, r["wall"], r["converter_cpu"], r["ok"], r["files"], load0, os.getloadavg()[0]),
                    file=sys.stderr)
    finally:
        for p in reversed(procs):
            p.terminate()
        for p in procs:
            p.wait()
        log.close()
        shutil.rmtree(tmp, ignore_errors=True)
    files = results[LOOP_NAME][0]["files"]
    med = statistics.median
    wall = {name: med(r["wall"] for r in rs) for name, rs in results.items()}
    loop_cpu = med(r["converter_cpu"] for r in results[LOOP_NAME])
    print("| run (%d files, %d ok) | wall (s) | files / min | speed-up vs 1 worker | vs 1 worker, --threads 1 | "
          "wall vs the loop | converters' CPU, sum (s) | CPU vs the loop | own time per file | "
          "Dask processes' CPU (s) | largest converter (MB) | driver (MB) |" % (files, results[ONE][0]["ok"]))
    print("|---|---|---|---|---|---|---|---|---|---|---|---|")
    for name, _, _ in configs:
        rs = results[name]
        serial = name in (LOOP_NAME, ONE, ONE_T1)
        # Ratios within each round (the runs of one round are minutes apart, the rounds more),
        # then their median.
        speed = med(o["wall"] / r["wall"] for o, r in zip(results[ONE], rs))
        speed_t1 = med(o["wall"] / r["wall"] for o, r in zip(results[ONE_T1], rs))
        vs_loop = med(r["wall"] / l["wall"] - 1 for l, r in zip(results[LOOP_NAME], rs))
        cpu = med(r["converter_cpu"] for r in rs)
        cpu_vs = med(r["converter_cpu"] / l["converter_cpu"] - 1 for l, r in zip(results[LOOP_NAME], rs))
        # Own time: what the driver adds between conversions, within each run (wall - the
        # converters' walls, one at a time), so the machine's load between runs cancels out.
        own = med((r["wall"] - r["converter_s"]) / files for r in rs)
        busy = med(r["converter_s"] for r in rs)
        print("| %s | %.1f | %.1f | %s | %s | %+.1f %% | %.1f | %+.1f %% | %s | %s | %.0f | %s |" % (
            name, wall[name], 60 * files / wall[name], "-" if name == LOOP_NAME else "%.2fx" % speed,
            "-" if name == LOOP_NAME else "%.2fx" % speed_t1,
            100 * vs_loop, cpu, 100 * cpu_vs,
            "%.1f ms (%.1f %%)" % (1000 * own, 100 * own * files / busy) if serial else "-",
            "%.1f" % med(r["dask_cpu"] for r in rs) if name.startswith("Dask") else "-",
            max(r["converter_mb"] for r in rs),
            "-" if name == LOOP_NAME else "%.0f" % max(r["driver_mb"] for r in rs)))
    print()
    print("%d runs of each, medians (ratios: within each round, then the median); %d CPUs; 1-minute load "
          "average at the starts and ends of the runs %.1f-%.1f (median %.1f)." % (
              a.repeats, os.cpu_count(), min(loads), max(loads), med(loads)))
    for name, rs in results.items():
        print("%s: walls %s" % (name, ", ".join("%.1f" % r["wall"] for r in rs)))


if __name__ == "__main__":
    main()
