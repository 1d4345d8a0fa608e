#!/usr/bin/env python3
"""The resource estimate against what a conversion really uses (#32 item 3): the table of
docs/hardening.md "How honest the estimate is".

    python3 scripts/measure_estimate.py SUBD2NURBS RESULTS.jsonl MODEL_OR_DIR... [--timeout S]
    python3 scripts/measure_estimate.py --table RESULTS.jsonl [MORE.jsonl...] > table.md

The first form converts each model (`convert MODEL -o out.step`, the defaults) under
`/usr/bin/time -v` and appends one JSON line per model to RESULTS.jsonl: the estimate as the
converter states it before any work (`convert --max-memory 1` refuses and names it: bytes;
`--max-faces 1` the same for the pieces), its time class (`--estimate`'s line, when the binary
has it), the measured peak RSS, wall time and CPU time (user + system), and the STEP's size.
Directories are expanded to their .obj / .off / .usd* files. The second form prints the markdown
table with the ratio estimate / measured peak RSS (goal 0.5 .. 2) and the time class against
the measured CPU time.

The cages of the costly cases are written by scripts/make_costly_cages.py.
"""
import json
import os
import re
import subprocess
import sys
import tempfile

UNITS = {"bytes": 1, "KiB": 1024, "MiB": 1024 ** 2, "GiB": 1024 ** 3, "TiB": 1024 ** 4, "PiB": 1024 ** 5}
# The time classes of `subd2nurbs convert --estimate` (converter/pipeline/resources.h).
CLASSES = [(1, "under a second"), (10, "seconds"), (60, "tens of seconds"), (600, "minutes"),
           (float("inf"), "ten minutes or more")]


def time_class(seconds):
    for limit, name in CLASSES:
        if seconds < limit:
            return name
    return CLASSES[-1][1]


def refused_estimate(exe, model, flag):
    """The estimate the guard states when refusing at a tiny limit."""
    p = subprocess.run([exe, "convert", model, "-o", os.devnull + ".step", flag, "1"], capture_output=True, text=True)
    m = re.search(r"would need about ([0-9.e+]+) (bytes|KiB|MiB|GiB|TiB|PiB) of memory", p.stderr)
    if m:
        return float(m.group(1)) * UNITS[m.group(2)]
    m = re.search(r"would make about ([0-9.e+]+) faces", p.stderr)
    if m:
        return float(m.group(1))
    return None


def summary_estimate(stderr):
    """The summary's estimate line (#32 on): with the fans as built, and before any work."""
    m = re.search(r"estimate   peak memory ([0-9.e+]+) (\S+), (.+?) of CPU time \(before any work: ([0-9.e+]+) (\S+), (.+?)\)",
                  stderr)
    if not m:
        return {}
    return {"estimate_built_bytes": float(m.group(1)) * UNITS[m.group(2)], "estimate_class": m.group(3),
            "estimate_class_before": m.group(6)}


def measure(exe, model, timeout):
    with tempfile.TemporaryDirectory() as d:
        out = os.path.join(d, "out.step")
        timing = os.path.join(d, "time.txt")
        cmd = ["/usr/bin/time", "-v", "-o", timing, exe, "convert", model, "-o", out, "--max-memory", "1T",
               "--max-faces", "1e12"]
        try:
            p = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout)
            rc = p.returncode
        except subprocess.TimeoutExpired:
            return {"rc": "timeout"}
        stated = summary_estimate(p.stderr)
        t = open(timing).read()
        val = lambda key: re.search(re.escape(key) + r":\s*(\S+)", t).group(1)
        wall = val("Elapsed (wall clock) time (h:mm:ss or m:ss)").split(":")
        seconds = sum(float(x) * 60 ** i for i, x in enumerate(reversed(wall)))
        return {"rc": rc, "rss": int(val("Maximum resident set size (kbytes)")) * 1024, "wall": seconds,
                "cpu": float(val("User time (seconds)")) + float(val("System time (seconds)")),
                "step_bytes": os.path.getsize(out) if os.path.exists(out) else None, **stated}


def models_of(args):
    for a in args:
        if os.path.isdir(a):
            for f in sorted(os.listdir(a)):
                if f.rsplit(".", 1)[-1].lower() in ("obj", "off", "usd", "usda", "usdc", "usdz"):
                    yield os.path.join(a, f)
        else:
            yield a


def run(argv):
    exe, results = argv[0], argv[1]
    timeout = 1800
    rest = argv[2:]
    if "--timeout" in rest:
        i = rest.index("--timeout")
        timeout = float(rest[i + 1])
        del rest[i:i + 2]
    for model in models_of(rest):
        row = {"model": os.path.basename(model)}
        row["estimate_bytes"] = refused_estimate(exe, model, "--max-memory")
        row["estimate_pieces"] = refused_estimate(exe, model, "--max-faces")
        row.update(measure(exe, model, timeout))
        with open(results, "a") as f:
            f.write(json.dumps(row) + "\n")
        print(json.dumps(row), file=sys.stderr, flush=True)


def table(paths):
    rows = []
    for p in paths:
        with open(p) as f:
            rows += [json.loads(line) for line in f if line.strip()]
    print("| model | peak RSS | estimate before any work | ratio | estimate as built | ratio | CPU s | class measured | class estimated | STEP |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    mb = lambda b: "%.0f MB" % (b / 1e6) if b is not None else "-"
    flag = lambda x: "" if 0.5 <= x <= 2 else " (!)"
    before, built, classes = [], [], [0, 0, 0]
    for r in rows:
        if r.get("rc") != 0:
            print("| %s | - | %s | - | - | - | - | exit %s | - | - |" % (r["model"], mb(r.get("estimate_bytes")), r.get("rc")))
            continue
        a = r["estimate_bytes"] / r["rss"]
        before.append(a)
        b = r.get("estimate_built_bytes")
        bt = "-"
        if b:
            built.append(b / r["rss"])
            bt = "%.2f%s" % (b / r["rss"], flag(b / r["rss"]))
        measured = time_class(r["cpu"])
        est = r.get("estimate_class") or "-"
        names = [c[1] for c in CLASSES]
        if est in names:
            off = abs(names.index(est) - names.index(measured))
            classes[min(off, 2)] += 1
        print("| %s | %s | %s | %.2f%s | %s | %s | %.1f | %s | %s%s | %s |" % (
            r["model"], mb(r["rss"]), mb(r["estimate_bytes"]), a, flag(a), mb(b), bt, r["cpu"], measured, est,
            "" if est in ("-", measured) else " (!)", mb(r.get("step_bytes"))))
    print()
    for what, xs in (("before any work", before), ("as built", built)):
        if xs:
            print("Estimate %s / measured peak RSS over %d models: %.2f .. %.2f, %d outside 0.5 .. 2.  " % (
                what, len(xs), min(xs), max(xs), sum(1 for x in xs if not 0.5 <= x <= 2)))
    print("Time class (as built) against the measured CPU time: %d right, %d one class off, %d further off." % tuple(classes))


if __name__ == "__main__":
    if len(sys.argv) >= 2 and sys.argv[1] == "--table":
        table(sys.argv[2:])
    elif len(sys.argv) >= 4:
        run(sys.argv[1:])
    else:
        sys.exit(__doc__)
