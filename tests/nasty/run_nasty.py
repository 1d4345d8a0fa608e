#!/usr/bin/env python3
"""Runs one valid-but-nasty cage (tests/nasty/nasty_cages.py, issue #32) through the command
line's `info` and `convert` (STEP and BREP) and reads every written file back with OCCT (the
Python module's file_summary: STEPControl_Reader / BRepTools, BRepCheck_Analyzer, volume).

    run_nasty.py --cli build/subd2nurbs --case NAME [--work DIR]    (PYTHONPATH=build/python)

The rule for every case: a file that OCCT reads back valid with positive volume (or, for the
flat and open cases, zero volume), or the documented refusal (exit code and message), never
exit 0 with an invalid or inside-out file. Volumes are checked against the affine image of the
unit cube's limit (Catmull-Clark is affine invariant), converted in the same run.
docs/hardening.md lists what each case gives."""
import argparse
import os
import re
import shutil
import subprocess
import sys
import tempfile

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import nasty_cages as N  # noqa: E402
import subd2nurbs as s2n  # noqa: E402

RESOURCES = r"error: converting \d+ cage faces at level \d+ would (make|need) .*(--max-faces|--max-memory)"
CANNOT_CARRY = r"a STEP or IGES file cannot carry it .*nothing was written.*write a \.brep file"


class Run:
    def __init__(self, cli, work, name):
        self.cli, self.work, self.name, self.failures = cli, work, name, []

    def fail(self, what):
        self.failures.append(what)
        print("FAIL %s: %s" % (self.name, what))

    def run(self, *args):
        p = subprocess.run([self.cli] + list(args), cwd=self.work, capture_output=True, text=True)
        return p.returncode, p.stderr + p.stdout

    def write_cage(self, stem, cage):
        path = os.path.join(self.work, stem + ".obj")
        with open(path, "w") as f:
            f.write(N.obj_text(*cage))
        return stem + ".obj"

    def convert(self, obj, ext):
        out = os.path.splitext(obj)[0] + "." + ext
        code, text = self.run("convert", obj, "-o", out, "--input", "cage")
        exists = os.path.exists(os.path.join(self.work, out))
        if code != 0 and exists:
            self.fail("%s: exit %d but %s was written" % (ext, code, out))
        if code == 4:
            self.fail("%s: exit 4 (internal error): %s" % (ext, text[-400:]))
        leftovers = [n for n in os.listdir(self.work) if n.endswith(".tmp")]
        if leftovers:
            self.fail("temporary files left: %s" % leftovers)
        summary = s2n.file_summary(os.path.join(self.work, out)) if code == 0 else None
        return code, text, summary

    def unit_volume(self):
        code, text, s = self.convert(self.write_cage("unit_cube", N.cube(1.0)), "brep")
        if code != 0 or not s["valid"] or not (0 < s["volume"] < 1):  # inside the cage's hull
            self.fail("the unit cube did not convert to a valid solid inside its cage: %s %s" % (code, s))
            return None
        return s["volume"]

    def check_solid(self, ext, summary, case, reference):
        if not summary["valid"]:
            self.fail("%s read back invalid: %s" % (ext, summary["check_message"][:300]))
        if summary["solids"] != case.get("solids", 1):
            self.fail("%s read back with %d solids, %d shells (want %d solids)" %
                      (ext, summary["solids"], summary["shells"], case.get("solids", 1)))
        if not summary["volume"] > 0:
            self.fail("%s read back with volume %g (not positive)" % (ext, summary["volume"]))
        if reference and not abs(summary["volume"] / reference - 1) <= 1e-3:
            self.fail("%s volume %.6g, expected %.6g (the unit cube's limit scaled)" % (ext, summary["volume"], reference))

    def main(self, case):
        obj = self.write_cage(self.name, case["cage"]())
        kind = case["kind"]
        reference = None
        if "sides" in case:
            unit = self.unit_volume()
            if unit:
                x, y, z = case["sides"]
                reference = unit * x * y * z
        code, text = self.run("info", obj)
        if code != case.get("info_exit", 0):
            self.fail("info: exit %d: %s" % (code, text[-300:]))
        if code == 2 and "message" in case and not re.search(case["message"], text):
            self.fail("info: exit 2 without /%s/: %s" % (case["message"], text[-300:]))
        if "info" in case and not re.search(case["info"], text):
            self.fail("info does not say %r: %s" % (case["info"], text[-500:]))
        if "nan" in text.lower().split():
            self.fail("info printed nan")

        if kind == "refused":
            for ext in ("step", "brep"):
                code, text, _ = self.convert(obj, ext)
                if code != case["exit"] or not re.search(case["message"], text):
                    self.fail("%s: want exit %d and /%s/, got exit %d: %s" % (ext, case["exit"], case["message"],
                                                                             code, text[-400:]))
            return
        for ext in ("brep", "step"):
            code, text, summary = self.convert(obj, ext)
            if kind == "heavy" and code == 1:
                if not re.search(RESOURCES, text):
                    self.fail("%s: exit 1 without the resources message: %s" % (ext, text[-400:]))
                print("%s %s: refused by the resource guard" % (self.name, ext))
                continue
            if kind == "brep" and ext == "step":
                if code != 2 or not re.search(CANNOT_CARRY, text):
                    self.fail("step: want the refusal (exit 2, /%s/), got exit %d: %s" % (CANNOT_CARRY, code, text[-400:]))
                if "warning: the part of the cage" not in text:
                    self.fail("step: the refusal came without the %s warning" % case["warning"])
                continue
            if code != 0:
                self.fail("%s: exit %d: %s" % (ext, code, text[-400:]))
                continue
            print("%s %s: %d solids, %d shells, %d faces, valid %s, volume %.6g" % (
                self.name, ext, summary["solids"], summary["shells"], summary["faces"], summary["valid"],
                summary["volume"]))
            if kind == "brep" and case["warning"] == "tiny_part" and "less than 10 x the B-rep tolerance" not in text:
                self.fail("%s: no tiny_part warning" % ext)
            if kind == "brep" and case["warning"] == "thin_part" and " thick (2 x cage volume / area)" not in text:
                self.fail("%s: no thin_part warning" % ext)
            if kind == "flat" or (kind == "brep" and case["warning"] == "flat_part"):
                if "encloses no volume" not in text:
                    self.fail("%s: no flat_part warning" % ext)
            if kind == "flat":
                if not summary["valid"] or summary["solids"] != 1 or abs(summary["volume"]) > 1e-9:
                    self.fail("%s: want a valid flat solid of volume 0, got %s" % (ext, summary))
            elif case.get("open"):
                if not summary["valid"] or summary["solids"] != 0 or summary["faces"] == 0:
                    self.fail("%s: want a valid open shell, got %s" % (ext, summary))
            else:
                self.check_solid(ext, summary, case, reference)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--cli", required=True)
    ap.add_argument("--case", required=True, choices=sorted(N.CASES))
    ap.add_argument("--work", help="keep the files in this directory (default: a temporary one)")
    args = ap.parse_args()
    work = args.work or tempfile.mkdtemp(prefix="s2n_nasty_")
    os.makedirs(work, exist_ok=True)
    try:
        r = Run(os.path.abspath(args.cli), work, args.case)
        r.main(N.CASES[args.case])
    finally:
        if not args.work:
            shutil.rmtree(work, ignore_errors=True)
    print("%s: %s" % (args.case, "%d failures" % len(r.failures) if r.failures else "ok"))
    return 1 if r.failures else 0


if __name__ == "__main__":
    sys.exit(main())
