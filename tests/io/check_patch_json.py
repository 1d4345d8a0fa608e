#!/usr/bin/env python3
"""Checks the patch JSON export with Python's json module and the evaluator of docs/formats.md.

usage: check_patch_json.py WRITER FORMATS_MD
WRITER writes tests/io/sample_patch_set.h's PatchSet to the path it is given.
"""
import json
import math
import os
import re
import struct
import subprocess
import sys
import tempfile


def fail(msg):
    print("FAIL:", msg)
    sys.exit(1)


def ordered(pairs):
    keys = [k for k, _ in pairs]
    if len(set(keys)) != len(keys):
        fail("duplicate key in %s" % keys)
    return pairs  # a list of (key, value): keeps the file's order


def reject_constant(name):
    fail("non-standard JSON constant " + name)


def obj(pairs):
    return dict(pairs)


def keys_of(pairs):
    return [k for k, _ in pairs]


def bits(x):
    return struct.pack("<d", x)


def flat(kv):
    return [x for x, m in zip(kv["values"], kv["mults"]) for _ in range(m)]


def basis(p, t, n, x):
    """Cox-de Boor recursion: the n basis functions of degree p on flat knots t at x."""
    k = max(i for i in range(p, n) if t[i] <= x)
    N = [1.0 if i == k else 0.0 for i in range(len(t) - 1)]
    for d in range(1, p + 1):
        for i in range(len(t) - 1 - d):
            a = (x - t[i]) / (t[i + d] - t[i]) * N[i] if t[i + d] > t[i] else 0.0
            b = (t[i + d + 1] - x) / (t[i + d + 1] - t[i + 1]) * N[i + 1] if t[i + d + 1] > t[i + 1] else 0.0
            N[i] = a + b
    return N[:n]


def eval_by_basis(P, u, v):
    (nu, nv), (du, dv) = P["num_poles"], P["degree"]
    w = P.get("weights", [1.0] * (nu * nv))
    Nu, Nv = basis(du, flat(P["knots_u"]), nu, u), basis(dv, flat(P["knots_v"]), nv, v)
    acc = [0.0] * 4
    for i in range(nu):
        for j in range(nv):
            n = i * nv + j
            c = Nu[i] * Nv[j] * w[n]
            for k in range(3):
                acc[k] += c * P["poles"][n][k]
            acc[3] += c
    return [a / acc[3] for a in acc[:3]]


def main():
    writer, formats_md = sys.argv[1], sys.argv[2]
    with tempfile.TemporaryDirectory() as tmp:
        path = os.path.join(tmp, "sample.json")
        subprocess.run([writer, path], check=True)
        text = open(path).read()
        raw = json.loads(text, object_pairs_hook=ordered, parse_constant=reject_constant)
        data = json.loads(text, parse_constant=reject_constant)

        # --- layout and key order
        if keys_of(raw) != ["format", "version", "model_size", "closed", "patches", "curves", "corners"]:
            fail("top-level keys %s" % keys_of(raw))
        if data["format"] != "subd2nurbs-patches" or data["version"] != 1:
            fail("format / version")
        if bits(data["model_size"]) != bits(2.0 / 3.0):
            fail("model_size not exact: %r" % data["model_size"])
        raw_patches = dict(raw)["patches"]
        for n, (P, rawP) in enumerate(zip(data["patches"], raw_patches)):
            want = ["kind", "degree", "knots_u", "knots_v", "num_poles", "poles"]
            want += ["weights"] if "weights" in P else []
            want += ["base_faces", "corners", "curves", "curve_reversed"]
            if keys_of(rawP) != want:
                fail("patch %d keys %s" % (n, keys_of(rawP)))
            if P["kind"] not in ("regular", "pccm", "polar_cap"):
                fail("patch kind " + P["kind"])
            (nu, nv), (du, dv) = P["num_poles"], P["degree"]
            for kv, deg, num in ((P["knots_u"], du, nu), (P["knots_v"], dv, nv)):
                if kv["periodic"] is not False or sum(kv["mults"]) - deg - 1 != num:
                    fail("patch %d knot vector %s" % (n, kv))
                if any(b <= a for a, b in zip(kv["values"], kv["values"][1:])):
                    fail("knots not increasing")
                if kv["mults"][0] != deg + 1 or kv["mults"][-1] != deg + 1:
                    fail("knot vector not clamped")
            if len(P["poles"]) != nu * nv or any(len(p) != 3 for p in P["poles"]):
                fail("patch %d poles" % n)
            if "weights" in P and len(P["weights"]) != nu * nv:
                fail("patch %d weights" % n)
            if len(P["corners"]) != 4 or len(P["curves"]) != 4 or len(P["curve_reversed"]) != 4:
                fail("patch %d corner / curve lists" % n)
            for c in P["corners"]:
                if not -1 <= c < len(data["corners"]):
                    fail("patch %d corner index %d" % (n, c))
            for s, c in enumerate(P["curves"]):
                if c == -1:
                    continue
                uses = [u for u in data["curves"][c]["uses"] if u["patch"] == n and u["side"] == s]
                if len(uses) != 1 or uses[0]["reversed"] != P["curve_reversed"][s]:
                    fail("patch %d side %d: no matching use in curve %d" % (n, s, c))
        for c, C in enumerate(data["curves"]):
            if C["continuity"] not in ("boundary", "C0", "G1", "C1", "C2"):
                fail("continuity " + C["continuity"])
            if sum(C["knots"]["mults"]) - C["degree"] - 1 != len(C["poles"]):
                fail("curve %d pole count" % c)
        if not (len(data["patches"]) == 3 and "weights" not in data["patches"][0]
                and "weights" in data["patches"][1]):
            fail("weights must appear exactly on the rational patch")

        # --- exact numbers (%.17g round trip)
        cap = data["patches"][2]["poles"]
        if math.copysign(1.0, cap[0][0]) != -1.0 or cap[0][0] != 0.0:
            fail("-0 lost")
        if cap[1][0] != 5e-324 or cap[3][0] != 1.2345678901234567e+300 or cap[6][0] != 1.0 / 3:
            fail("pole values not exact: %r" % cap[:7])
        if data["corners"][2]["position"][2] != 1.0 / 7 or data["corners"][2]["base_vertex"] != -1:
            fail("corner 2")

        # --- the evaluator of docs/formats.md
        blocks = re.findall(r"```python\n(.*?)```", open(formats_md).read(), re.S)
        if len(blocks) != 1:
            fail("expected one python block in " + formats_md)
        ns = {"__name__": "formats_md"}
        exec(blocks[0], ns)
        eval_patch = ns["eval_patch"]
        worst = 0.0
        for n, P in enumerate(data["patches"]):
            for u in (0.0, 0.1, 0.25, 0.5, 0.6, 0.9, 1.0):
                for v in (0.0, 0.3, 0.5, 1.0):
                    p = eval_patch(P, u, v)
                    q = eval_by_basis(P, u, v)
                    scale = max(1.0, max(abs(c) for c in q))
                    worst = max(worst, max(abs(a - b) for a, b in zip(p, q)) / scale)
                    # patches 0 and 1 lie on the plane z = 0.1 + 2x - 0.7y; the polynomial one
                    # (poles at the Greville abscissae) with x = u, y = v
                    exact = [u, v, 0.1 + 2 * u - 0.7 * v] if n == 0 else [p[0], p[1], 0.1 + 2 * p[0] - 0.7 * p[1]]
                    if n < 2 and max(abs(a - b) for a, b in zip(p, exact)) > 1e-14:
                        fail("patch %d at (%g, %g): %r, expected %r" % (n, u, v, p, exact))
        if worst > 1e-13:
            fail("de Boor and Cox-de Boor disagree by %g" % worst)
        # corners of a clamped patch are its corner poles
        P = data["patches"][1]
        nu, nv = P["num_poles"]
        for (u, v), idx in (((0, 0), 0), ((1, 0), (nu - 1) * nv), ((1, 1), nu * nv - 1), ((0, 1), nv - 1)):
            if max(abs(a - b) for a, b in zip(eval_patch(P, u, v), P["poles"][idx])) > 1e-15:
                fail("corner (%d, %d) is not the corner pole" % (u, v))

        # --- the block as a script
        script = os.path.join(tmp, "eval.py")
        open(script, "w").write(blocks[0])
        out = subprocess.run([sys.executable, script, path, "0", "0.5", "0.25"], check=True,
                             capture_output=True, text=True).stdout
        got = [float(x) for x in out.strip().strip("[]").split(",")]
        if max(abs(a - b) for a, b in zip(got, [0.5, 0.25, 0.1 + 1.0 - 0.175])) > 1e-14:
            fail("script output " + out)
    print("patch JSON: OK (de Boor vs Cox-de Boor %.3g)" % worst)


main()
