#!/usr/bin/python3
"""Real USD files through the command line (issue #29), with the expected counts computed here,
independently of the C++ reader: from the usda text by regular expressions, and from the binary
crate by tests/usd/crate_probe.py (a separate Python reader of the format). Each file (and each
variant of the Pyramid) must read with those counts in `info --json`, and convert to a valid
B-rep (exit 0, a STEP file written); a truncated crate, a foreign format and binary junk must give
exit 2 naming the file."""
import json
import os
import re
import subprocess
import sys
import tempfile

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import crate_probe  # noqa: E402

CLI, DATA = sys.argv[1], sys.argv[2]
failures = []


def check(condition, what):
    if not condition:
        failures.append(what)
        print("FAIL:", what)


def run(*args):
    return subprocess.run([CLI, *args], capture_output=True, text=True, timeout=300)


def info(path, *variants):
    args = ["info", "--json"]
    for v in variants:
        args += ["--variant", v]
    p = run(*args, path)
    check(p.returncode == 0, "info %s %s: exit %d: %s" % (path, variants, p.returncode, p.stderr))
    return json.loads(p.stdout) if p.returncode == 0 else None


def array_after(text, anchor, name):
    """The entries of the first `name = [...]` after `anchor` in the usda text."""
    at = text.index(anchor)
    m = re.compile(r"\b%s = \[([^\]]*)\]" % re.escape(name)).search(text, at)
    return m.group(1)


def ints(s):
    return [int(x) for x in s.split(",") if x.strip()]


def tuples(s):
    return s.count("(")


def convert(path, *variants):
    with tempfile.TemporaryDirectory() as d:
        out = os.path.join(d, "out.step")
        args = ["convert", "-q", path, "-o", out]
        for v in variants:
            args += ["--variant", v]
        p = run(*args)
        check(p.returncode == 0 and os.path.getsize(out) > 1000,
              "convert %s %s: exit %d: %s" % (path, variants, p.returncode, p.stderr[-500:]))


# --- the Pyramid: three variants, counts from the text ---------------------------------------
geo = os.path.join(DATA, "geo.usda")
text = open(geo).read()
holes_faces = ints(array_after(text, '"quad_holes" (', "faceVertexCounts"))
holes = ints(array_after(text, '"quad_holes" (', "holeIndices"))
holes_points = tuples(array_after(text, '"quad_holes" (', "points"))
quad_faces = ints(array_after(text, '"quad_creases" (', "faceVertexCounts"))
quad_points = tuples(array_after(text, '"quad_creases" (', "points"))
crease_lengths = ints(array_after(text, '"edges" {', "creaseLengths"))
crease_sharp = [float(x) for x in array_after(text, '"edges" {', "creaseSharpnesses").split(",")]
corner_indices = ints(array_after(text, '"corners" {', "cornerIndices"))
print("oracle: holes variant %d faces, %d points, %d holes; quad %d faces, %d points; %d crease edges; %d corners"
      % (len(holes_faces), holes_points, len(holes), len(quad_faces), quad_points,
         sum(n - 1 for n in crease_lengths), len(corner_indices)))

# The authored selection of the strongest reference: quad_holes.
j = info(geo)
if j:
    m = j["usd"]["meshes"]
    check(len(m) == 1 and m[0]["faces"] == len(holes_faces) and m[0]["vertices"] == holes_points
          and m[0]["holes"] == len(holes), "geo default (quad_holes): %s" % m)
    check(j["holes"] == len(holes), "geo holes in the cage: %s" % j["holes"])
    check(j["usd"]["variant_sets"][0]["selection"] == "quad_holes", "geo selection: %s" % j["usd"]["variant_sets"])
j = info(geo, "geo=quad_creases", "creases=edges")
if j:
    m = j["usd"]["meshes"][0]
    expected_edges = sum(n - 1 for n in crease_lengths)
    check(m["faces"] == len(quad_faces) and m["vertices"] == quad_points and m["crease_edges"] == expected_edges,
          "geo edges: %s" % m)
    infinite = sum(1 for s in crease_sharp if s >= 10)
    check(j["creases"]["infinite_edges"] == infinite, "geo edges: infinitely sharp %s, expected %d" % (j["creases"], infinite))
j = info(geo, "geo=quad_creases", "creases=corners")
if j:
    check(j["usd"]["meshes"][0]["corners"] == len(corner_indices) and j["creases"]["corner_vertices"] == len(corner_indices),
          "geo corners: %s %s" % (j["usd"]["meshes"], j["creases"]))
j = info(geo, "geo=quad_creases", "creases=none")
if j:
    check(j["creases"]["infinite_edges"] == 0 and j["creases"]["corner_vertices"] == 0, "geo none: %s" % j["creases"])
for variants in [(), ("geo=quad_creases", "creases=edges"), ("geo=quad_creases", "creases=corners")]:
    convert(geo, *variants)
p = run("info", "--variant", "geo=nosuch", geo)
check(p.returncode == 2 and "nosuch" not in p.stdout, "a variant the set lacks: exit %d" % p.returncode)
p = run("info", "--variant", "size=big", geo)
check(p.returncode == 2 and "no variant set 'size'" in p.stderr, "an unknown variant set: %d %s" % (p.returncode, p.stderr))
p = run("info", "--variant", "novalue", geo)
check(p.returncode == 1, "--variant without '=': exit %d" % p.returncode)

# --- the Utah teapot (text in a .usd) ----------------------------------------------------------
teapot = os.path.join(DATA, "UtahTeapot.usd")
text = open(teapot).read()
faces = ints(array_after(text, 'def Mesh "Geometry"', "faceVertexCounts"))
points = tuples(array_after(text, 'def Mesh "Geometry"', "points"))
j = info(teapot)
if j:
    check(j["faces"] == len(faces) and j["vertices"] == points and j["usd"]["encoding"] == "usda"
          and j["usd"]["up_axis"] == "Y" and j["usd"]["meters_per_unit"] == 1, "teapot: %s" % j["usd"])
convert(teapot)
with tempfile.TemporaryDirectory() as d:
    p = run("refine", teapot, "-l", "1", "-o", os.path.join(d, "r.obj"))
    check(p.returncode == 0, "refine teapot: %d %s" % (p.returncode, p.stderr))
    q = os.path.join(d, "q.txt")
    open(q, "w").write("0 0.5 0.5\n")
    p = run("limit", teapot, q)
    check(p.returncode == 0 and len(p.stdout.split()) == 12, "limit teapot: %d %s" % (p.returncode, p.stderr))

# --- the rook: a binary crate, counts from the Python crate reader ------------------------------
rook = os.path.join(DATA, "OpenChessSet_Rook_geom.usd")
attrs = dict(crate_probe.Crate(open(rook, "rb").read()).attributes())
faces = attrs["/Rook/Geom/Render.faceVertexCounts"]
points = len(attrs["/Rook/Geom/Render.points"]) // 3
j = info(rook)
if j:
    check(j["faces"] == len(faces) and j["vertices"] == points and j["usd"]["encoding"] == "usdc"
          and j["usd"]["meshes"][0]["path"] == "/Rook/Geom/Render" and j["usd"]["meshes"][0]["scheme"] == "catmullClark",
          "rook: %s faces %d vertices %d, expected %d %d" % (j["usd"], j["faces"], j["vertices"], len(faces), points))
    sizes = {}
    for n in faces:
        sizes[str(n)] = sizes.get(str(n), 0) + 1
    check(j["face_sizes"] == sizes, "rook face sizes %s, expected %s" % (j["face_sizes"], sizes))
convert(rook)

# --- refused input: exit 2 naming the file -----------------------------------------------------
with tempfile.TemporaryDirectory() as d:
    data = open(rook, "rb").read()
    for n in (50, 1000, len(data) // 2, len(data) - 100):
        cut = os.path.join(d, "cut%d.usdc" % n)
        open(cut, "wb").write(data[:n])
        p = run("info", cut)
        check(p.returncode == 2 and cut in p.stderr, "truncated crate (%d bytes): exit %d %s" % (n, p.returncode, p.stderr))
    fbx = os.path.join(d, "model.fbx")
    open(fbx, "wb").write(b"Kaydara FBX Binary  \x00\x1a\x00")
    p = run("info", fbx)
    check(p.returncode == 2 and "not a format subd2nurbs reads" in p.stderr, "fbx: %d %s" % (p.returncode, p.stderr))
    junk = os.path.join(d, "model.bin")
    open(junk, "wb").write(bytes(range(256)) * 4)
    p = run("convert", junk, "-o", os.path.join(d, "x.step"))
    check(p.returncode == 2 and "not a format subd2nurbs reads" in p.stderr and not os.path.exists(os.path.join(d, "x.step")),
          "binary junk: %d %s" % (p.returncode, p.stderr))
    noext = os.path.join(d, "teapot_noext")
    open(noext, "w").write(open(teapot).read())
    p = run("info", noext)
    check(p.returncode == 0, "usda content without an extension: %d %s" % (p.returncode, p.stderr))

print("%d failures" % len(failures))
sys.exit(1 if failures else 0)
