# Run by freecadcmd (FreeCAD's own Python, OCCT underneath): the modelling operations a CAD
# user applies to a converted body, on our bodies and on OCCT-native bodies of similar shape
# (the reference), each checked for a valid result and a volume that adds up (docs/downstream.md).
#
# Inputs from the environment:
#   S2N_BODIES   space-separated "name=path" of our bodies (BREP or STEP files)
#   S2N_OUT      a scratch folder (the STEP round trip writes there)
#   S2N_RESULTS  optional: write the per-body, per-operation outcome as JSON there
#   S2N_HELPERS  the folder of cut_helpers.py (default: tests/downstream under the working folder)
#   S2N_COMPARE  "1" (default): fail unless every operation succeeds on our bodies (but the
#                KNOWN failures, which OCCT's own B-spline bodies share) and our success rate
#                is at least OCCT's on its own bodies converted to B-splines, on every operation
# Run as: freecadcmd -c "exec(open('downstream_ops.py').read())" (a plain script argument
# would exit 0 even when the script fails).
import json
import math
import os
import sys

import FreeCAD
import Part
from FreeCAD import Vector

sys.path.insert(0, os.environ.get("S2N_HELPERS", os.path.join(os.getcwd(), "tests", "downstream")))
from cut_helpers import bspline_face_solid, faces_at_cut, frame, half_space_box  # noqa: E402


def log(message):
    sys.stderr.write(message + "\n")
    sys.stderr.flush()


def fail(message):
    log("downstream: FAILED: " + message)
    os._exit(1)


class OpFailed(Exception):
    pass


def require(condition, what):
    if not condition:
        raise OpFailed(what)


def solid_of(shape):
    require(len(shape.Solids) == 1, "%d solids, expected 1" % len(shape.Solids))
    return shape.Solids[0]


def valid(shape, what):
    require(not shape.isNull(), what + ": null shape")
    require(shape.isValid(), what + ": BRepCheck finds the shape invalid")


def close(a, b, rel, what):
    require(abs(a - b) <= rel * max(abs(a), abs(b), 1e-300),
            "%s: %.9g vs %.9g (rel %.2g > %.2g)" % (what, a, b, abs(a - b) / max(abs(a), abs(b), 1e-300), rel))


# Relative volume tolerance of the booleans' sums: FreeCAD's Volume integrates the pieces of
# cut B-spline faces with a fixed number of points, to a few 1e-5 relative only (measured up to
# 4.5e-5), and to 3.2e-4 on capped_cylinder_nopolar since packs take in the quads at
# extraordinary vertices (their nested knots run across the pack): the same cut and common
# integrated adaptively (BRepGProp::VolumeProperties with eps 1e-7) add up to vol(A) within
# 2.5e-8. 1e-3 leaves room and still catches a missing, doubled or inside-out piece.
VOL_REL = 1e-3


def op_check(body):
    # BOPAlgo_ArgumentAnalyzer (self-interference, small edges, ...): raises on a finding.
    body.check(True)


def op_booleans(body):
    lo, hi, diag = frame(body)
    centre = [(l + h) / 2 for l, h in zip(lo, hi)]
    # A box overlapping a corner region, off every symmetry plane.
    size = [0.55 * (h - l) for l, h in zip(lo, hi)]
    tool = Part.makeBox(size[0], size[1], size[2], Vector(*[c - 0.13 * s for c, s in zip(centre, size)]))
    va, vb = body.Volume, tool.Volume
    cut = body.cut(tool)
    common = body.common(tool)
    fuse = body.fuse(tool)
    for name, s in (("cut", cut), ("common", common), ("fuse", fuse)):
        valid(s, name)
        require(s.Volume > 0, name + ": no volume")
    close(cut.Volume + common.Volume, va, VOL_REL, "vol(A-B) + vol(A&B) vs vol(A)")
    close(fuse.Volume, va + vb - common.Volume, VOL_REL, "vol(A|B) vs vol(A) + vol(B) - vol(A&B)")


# The largest safe thickness each way, from the report of the conversion (curvature_radius:
# inward = convex, the shell / inward offset limit; outward = concave): issue 33 asks the
# operations to pass "at a thickness below the reported smallest radius". run_body sets it
# per body; None for OCCT's bodies and where the surface never curves that way.
RADII = {"inward": None, "outward": None}


def thickness(body, fraction, side):
    """fraction of the diagonal, but at most half the reported smallest radius on that side."""
    t = fraction * frame(body)[2]
    r = RADII[side]
    return t if r is None else min(t, 0.5 * r)


def offset_checked(body, d):
    off = body.makeOffsetShape(d, 1e-6 * frame(body)[2], join=2)
    valid(off, "offset %g" % d)
    s = solid_of(off)
    # First order: dV = area * d; the second-order term (mean curvature) stays well inside 30 %
    # at 1 % of the diagonal and at most half the smallest radius (thickness below).
    dv = s.Volume - body.Volume
    close(dv, body.Area * d, 0.3, "offset %g: volume change vs area * d" % d)
    return s


def op_offset_out(body):
    offset_checked(body, thickness(body, 0.01, "outward"))


def op_offset_in(body):
    offset_checked(body, -thickness(body, 0.01, "inward"))


def op_hollow(body):
    t = thickness(body, 0.01, "inward")
    inner = offset_checked(body, -t)
    hollow = body.cut(inner)
    valid(hollow, "hollow")
    close(hollow.Volume, body.Volume - inner.Volume, VOL_REL, "hollow volume vs vol(A) - vol(inner)")
    require(len(hollow.Shells) == 2, "hollow: %d shells, expected 2 (outside and cavity)" % len(hollow.Shells))


def op_cut_shell(body):
    """Cut flat, then shell removing the flat face(s): the usual way to hollow a smooth part."""
    lo, hi, diag = frame(body)
    results = []
    for axis in (0, 2):
        box, c = half_space_box(body, axis, 0.55)
        part = solid_of(body.cut(box))
        flats = faces_at_cut(part, axis, c, diag)
        require(flats, "cut: no flat face at the cut")
        t = thickness(body, 0.02, "inward")
        shell = part.makeThickness(flats, -t, 1e-6 * diag)
        valid(shell, "shell (axis %d)" % axis)
        s = solid_of(shell)
        kept = part.Area - sum(f.Area for f in flats)
        # A wall of thickness t under a kept area A has volume about A t (within curvature terms).
        close(s.Volume, kept * t, 0.3, "shell (axis %d): volume vs kept area * t" % axis)
        require(s.Volume < part.Volume, "shell (axis %d): not hollow" % axis)


def sharp_edges(body):
    out = []
    for e in body.Edges:
        faces = body.ancestorsOfType(e, Part.Face)
        if len(faces) != 2 or e.Degenerated:
            continue
        p = e.valueAt((e.FirstParameter + e.LastParameter) / 2)
        n = []
        for f in faces:
            u, v = f.Surface.parameter(p)
            n.append(f.normalAt(u, v))
        if n[0].getAngle(n[1]) > math.radians(20):
            out.append(e)
    return out


def op_fillet(body):
    edges = sharp_edges(body)
    if not edges:
        return "n/a"
    r = 0.02 * frame(body)[2]
    f = body.makeFillet(r, edges)
    valid(f, "fillet")
    s = solid_of(f)
    require(0 < body.Volume - s.Volume < 0.1 * body.Volume, "fillet: volume %.6g from %.6g" % (s.Volume, body.Volume))


def op_section(body):
    lo, hi, diag = frame(body)
    for axis in range(3):
        d = [0, 0, 0]
        d[axis] = 1
        c = lo[axis] + 0.45 * (hi[axis] - lo[axis])
        wires = body.slice(Vector(*d), c)
        require(wires, "section axis %d: no wire" % axis)
        for w in wires:
            require(w.isClosed(), "section axis %d: an open wire" % axis)


def op_mesh(body):
    import MeshPart
    diag = frame(body)[2]
    m = MeshPart.meshFromShape(Shape=body, LinearDeflection=2e-4 * diag, AngularDeflection=0.2)
    require(m.isSolid(), "mesh: not closed")
    require(not m.hasNonManifolds(), "mesh: non-manifold")
    close(m.Volume, body.Volume, 0.01, "mesh volume vs solid volume")


def op_step(body):
    path = os.path.join(os.environ["S2N_OUT"], "roundtrip.step")
    body.exportStep(path)
    back = Part.read(path)
    valid(back, "STEP read back")
    close(solid_of(back).Volume, body.Volume, 1e-7, "STEP read back: volume")


OPS = [("check", op_check), ("booleans", op_booleans), ("offset_out", op_offset_out),
       ("offset_in", op_offset_in), ("hollow", op_hollow), ("cut_shell", op_cut_shell),
       ("fillet", op_fillet), ("section", op_section), ("mesh", op_mesh), ("step", op_step)]


def occt_bodies():
    box = Part.makeBox(2, 1.6, 1.2)
    fbox = box.makeFillet(0.3, box.Edges)
    boss = Part.makeBox(2, 1.6, 1.2).fuse(Part.makeCylinder(0.5, 1.0, Vector(1, 0.8, 1.2))).removeSplitter()
    return [("occt_torus", Part.makeTorus(1.0, 0.35)), ("occt_sphere", Part.makeSphere(1.0)),
            ("occt_box", box), ("occt_filleted_box", fbox), ("occt_cylinder", Part.makeCylinder(0.8, 2.0)),
            ("occt_box_with_boss", boss)]


# Known failures of our bodies, each also a failure of OCCT's own B-spline body of the same
# shape (docs/downstream.md): OCCT's offset algorithm on B-spline faces, not our edges. A
# listed failure is not counted as a success; when it starts passing the run says so.
# Empty since the faces that close onto themselves are written periodic (issue 33): the
# capped cylinder's cut through the side, then the shell, failed with the clamped side face
# (0 of 4 cut positions) and passes now, so the suite checks it (capped_cylinder_polar,
# capped_cylinder_nopolar cut_shell).
KNOWN = set()


def run_body(name, body, radii=None):
    RADII.update(radii or {"inward": None, "outward": None})
    outcome = {}
    for op, fn in OPS:
        try:
            r = fn(body)
            outcome[op] = r if r == "n/a" else "ok"
        except OpFailed as e:
            outcome[op] = "fail: " + str(e)
        except Exception as e:  # an OCCT exception surfaces as a Part.OCCError / FreeCAD.Base error
            outcome[op] = "fail: %s: %s" % (type(e).__name__, str(e)[:200])
        log("  %-18s %-10s %s" % (name, op, outcome[op]))
    return outcome


results = {"ours": {}, "occt": {}, "occt_nurbs": {}, "occt_bspline_faces": {}}
for item in os.environ.get("S2N_BODIES", "").split():
    name, path = item.split("=", 1)
    shape = Part.read(path)
    if len(shape.Solids) != 1:
        fail("%s: %d solids in %s, expected one" % (name, len(shape.Solids), path))
    # The conversion's report beside the body (NAME.json): its smallest radii of curvature.
    radii = None
    report = os.path.splitext(path)[0] + ".json"
    if os.path.exists(report):
        cr = json.load(open(report))["curvature_radius"]
        radii = {side: cr[side]["radius"] if cr.get(side) else None for side in ("inward", "outward")}
        log("  %-18s smallest radius inward %s, outward %s" % (name, radii["inward"], radii["outward"]))
    results["ours"][name] = run_body(name, shape.Solids[0], radii)
for name, body in occt_bodies():
    results["occt"][name] = run_body(name, solid_of(body))
    # The same body with its faces and edges converted to B-splines by OCCT (like ours).
    results["occt_nurbs"][name] = run_body(name + "_nurbs", solid_of(body.toNurbs()))
    if len(body.Faces) == 1:  # the torus and the sphere
        results["occt_bspline_faces"][name] = run_body(name + "_bspline_face", bspline_face_solid(body))

if os.environ.get("S2N_RESULTS"):
    with open(os.environ["S2N_RESULTS"], "w") as f:
        json.dump(results, f, indent=1, sort_keys=True)


def rate(group, op):
    done = [o[op] for o in results[group].values() if o[op] != "n/a"]
    return (sum(1 for o in done if o == "ok"), len(done))


problems = []
for op, _ in OPS:
    ours, ref = rate("ours", op), rate("occt", op)
    nurbs, faces = rate("occt_nurbs", op), rate("occt_bspline_faces", op)
    log("%-10s ours %d/%d   occt %d/%d   occt as B-splines %d/%d   occt B-spline faces %d/%d" %
        (op, ours[0], ours[1], ref[0], ref[1], nurbs[0], nurbs[1], faces[0], faces[1]))
    # Our rate at least OCCT's own on its bodies turned into B-splines (the like-for-like
    # references: toNurbs, and B-spline faces OCCT makes itself), and every one of our failures
    # a known one (below).
    for other in (nurbs, faces):
        if ours[1] and other[1] and ours[0] * other[1] < other[0] * ours[1]:
            problems.append("%s: our success rate %d/%d is below OCCT's %d/%d" % (op, ours[0], ours[1], other[0], other[1]))
for name, outcome in results["ours"].items():
    for op, r in outcome.items():
        if r not in ("ok", "n/a") and (name, op) not in KNOWN:
            problems.append("%s %s: %s" % (name, op, r))
        if r == "ok" and (name, op) in KNOWN:
            log("note: %s %s now passes: remove it from KNOWN" % (name, op))
if not results["ours"]:
    problems.append("no bodies of ours were tested (S2N_BODIES)")
if os.environ.get("S2N_COMPARE", "1") == "1" and problems:
    fail("; ".join(problems))
log("downstream: OK")
