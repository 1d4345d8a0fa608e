#!/usr/bin/env python3
"""The resource estimate against the kernel's measure of the same run (#32 item 3).

    test_estimate.py SUBD2NURBS SOURCE_DIR

Converts the scaled-down costly cages of scripts/make_costly_cages.py (--small: three valence-64
fans, a flat and a wavy 60-gon, a prism with 60-gon caps, a 64-sided capsule with polar caps,
a 100 x 100 grid) and the samples to STEP, one process each, and takes the peak resident set
size from the kernel (os.wait4's rusage of that process: the oracle, independent of the
converter). Checks for each, with the estimates the converter states in its summary (before any
work, and with the fans as built):
  * 0.5 <= estimate / measured peak <= 2 (memory does not depend on the machine's load);
  * --max-memory at a quarter of the measured peak is refused before any work (exit 1), and at
    2.5 x the measured peak the conversion runs (the guard neither lets through nor refuses
    work by more than the estimate's error).
No time is asserted. Exit 0 when every check passes.
"""
import os
import re
import subprocess
import sys
import tempfile

UNITS = {"bytes": 1, "KiB": 1024, "MiB": 1024 ** 2, "GiB": 1024 ** 3, "TiB": 1024 ** 4}


def run(argv):
    """(exit code, stderr, peak RSS in bytes) of one process."""
    p = subprocess.Popen(argv, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    err = p.stderr.read()
    _, status, usage = os.wait4(p.pid, 0)
    p.returncode = os.waitstatus_to_exitcode(status)
    return p.returncode, err, usage.ru_maxrss * 1024


def main():
    exe, source = sys.argv[1], sys.argv[2]
    failures = []
    with tempfile.TemporaryDirectory() as d:
        subprocess.run([sys.executable, os.path.join(source, "scripts", "make_costly_cages.py"), d, "--small"],
                       check=True)
        models = sorted(os.path.join(d, f) for f in os.listdir(d) if f.endswith(".obj"))
        samples = os.path.join(source, "samples")
        models += sorted(os.path.join(samples, f) for f in os.listdir(samples) if f.endswith(".obj"))
        out = os.path.join(d, "out.step")
        for model in models:
            name = os.path.basename(model)
            code, err, rss = run([exe, "convert", model, "-o", out])
            m = re.search(r"estimate   peak memory ([0-9.e+]+) (\S+), .+? of CPU time \(before any work: "
                          r"([0-9.e+]+) (\S+), ", err)
            if code != 0 or not m:
                failures.append("%s: exit %d or no estimate line:\n%s" % (name, code, err[-2000:]))
                continue
            built = float(m.group(1)) * UNITS[m.group(2)]
            before = float(m.group(3)) * UNITS[m.group(4)]
            print("%-22s peak %7.1f MB, estimate before any work %7.1f MB (%.2f), as built %7.1f MB (%.2f)" % (
                name, rss / 1e6, before / 1e6, before / rss, built / 1e6, built / rss))
            for what, value in (("before any work", before), ("as built", built)):
                if not 0.5 <= value / rss <= 2:
                    failures.append("%s: estimate %s %.1f MB is %.2f x the measured peak %.1f MB" % (
                        name, what, value / 1e6, value / rss, rss / 1e6))
            code, err, _ = run([exe, "convert", model, "-o", out, "--max-memory", "%d" % (rss / 4)])
            if code != 1 or "would need about" not in err:
                failures.append("%s: --max-memory at 1/4 of the peak: exit %d, not refused:\n%s" % (name, code, err[-500:]))
            code, err, _ = run([exe, "convert", model, "-o", out, "--max-memory", "%d" % (rss * 2.5)])
            if code != 0:
                failures.append("%s: --max-memory at 2.5 x the peak: exit %d:\n%s" % (name, code, err[-500:]))
    for f in failures:
        print("FAIL " + f)
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
