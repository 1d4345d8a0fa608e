# Run by freecadcmd: cut-then-shell over a grid of cuts, on our bodies, on the same surfaces
# given OCCT's own edges, and on OCCT's own bodies of similar shape (docs/downstream.md
# "Cut-then-shell over a grid of cuts").
#
# Each body is cut by a plane across x, y and z at 35, 45, 55 and 65 % of its extent, the flat
# face(s) of the cut removed and the rest shelled inward (Part.Shape.makeThickness, as the
# downstream suite's cut_shell): `.` a valid single solid of smaller volume, `x` an exception or
# an invalid or wrong result, `-` the cut leaves several solids (not tried), `c` the cut failed.
# Thickness: 2 % of the diagonal, at most half the smallest inward radius of curvature of our
# report (`curvature_radius.inward.radius` of NAME.json beside NAME.brep), as the suite's.
#
# Bodies:
# * ours, as converted;
# * "OCCT's edges": each of our faces' surfaces made into a face by OCCT (Geom surface ->
#   toShape, i.e. BRepBuilderAPI_MakeFace over the face's parameter range) and the faces sewn
#   (Shape.sewShape): the same surfaces with the edges and pcurves OCCT builds itself;
# * OCCT's own: analytic (makeTorus, makeSphere, makeCylinder), converted by toNurbs() (B-spline
#   surfaces *and* B-spline pcurves), and the analytic surface as a B-spline surface made into a
#   face by OCCT (toBSpline -> MakeFace: rational quadratic, line pcurves); an uneven ellipsoid.
#
# Inputs from the environment:
#   S2N_BODIES  space-separated "name=path.brep" (the report path.json beside each is read)
#   S2N_TABLE   where the Markdown table is written
# Run as: S2N_BODIES="bob=/tmp/bob.brep" S2N_TABLE=/tmp/t.md \
#         freecadcmd -c "exec(open('scripts/cut_shell_grid.py').read())"
import json
import os
import sys

import FreeCAD
import Part

sys.path.insert(0, os.path.join(os.getcwd(), "tests", "downstream"))  # run from the repository's root
from cut_helpers import bspline_face_solid, faces_at_cut, frame, half_space_box  # noqa: E402

FRACTIONS = (0.35, 0.45, 0.55, 0.65)


def grid(body, thickness):
    """The outcome string of the 12 cuts (x, y, z groups separated by spaces) and passed / tried."""
    diag = frame(body)[2]
    groups = []
    for axis in range(3):
        group = ""
        for frac in FRACTIONS:
            box, c = half_space_box(body, axis, frac)
            try:
                part = body.cut(box)
            except Exception:
                group += "c"
                continue
            if len(part.Solids) != 1:
                group += "-"
                continue
            part = part.Solids[0]
            flats = faces_at_cut(part, axis, c, diag)
            try:
                shell = part.makeThickness(flats, -thickness, 1e-6 * diag)
                ok = (shell.isValid() and len(shell.Solids) == 1
                      and shell.Solids[0].Volume < part.Volume)
            except Exception:
                ok = False
            group += "." if ok else "x"
        groups.append(group)
    text = " ".join(groups)
    return text, text.count("."), text.count(".") + text.count("x")


rows = []


def add(name, body, thickness, diag=None):
    text, passed, tried = grid(body, thickness)
    diag = diag or body.BoundBox.DiagonalLength
    rows.append("| %s | %.5f | `%s` | %d/%d |" % (name, thickness / diag, text, passed, tried))
    open(os.environ.get("S2N_TABLE", "cut_shell_grid.md") + ".part", "w").write("\n".join(rows) + "\n")


def with_occt_edges(body):
    """The same surfaces, each made a face by OCCT over its parameter range, sewn into a solid."""
    shell = Part.Shell([f.Surface.toShape(*f.ParameterRange) for f in body.Faces])
    shell.sewShape()
    # a single closed face (a packed torus) has its seams already: the sewing returns no shell
    solid = Part.Solid(shell.Shells[0] if shell.Shells else Part.Shell(shell.Faces))
    if solid.Volume < 0:
        solid.reverse()
    return solid


for item in os.environ.get("S2N_BODIES", "").split():
    name, path = item.split("=", 1)
    shape = Part.Shape()
    shape.read(path)
    body = shape.Solids[0]
    report = json.load(open(os.path.splitext(path)[0] + ".json"))
    radius = report.get("curvature_radius", {}).get("inward", {}).get("radius")
    t = 0.02 * body.BoundBox.DiagonalLength
    t = t if radius is None else min(t, 0.5 * radius)
    add(name, body, t)
    add(name + ", OCCT's edges", with_occt_edges(body), t, body.BoundBox.DiagonalLength)

# OCCT's own; an ellipsoid has no analytic form in OCCT (a sphere scaled unevenly becomes
# B-splines).
squash = FreeCAD.Matrix()
squash.scale(1.0, 0.6, 0.4)
references = [("OCCT torus", Part.makeTorus(2.0, 0.8), True), ("OCCT sphere", Part.makeSphere(1.0), True),
              ("OCCT cylinder", Part.makeCylinder(1.0, 2.0), False)]
for name, body, one_face in references:
    diag = body.BoundBox.DiagonalLength
    add(name, body, 0.02 * diag)
    add(name + " `toNurbs()`", body.toNurbs().Solids[0], 0.02 * diag, diag)
    if one_face:
        add(name + " as a B-spline face", bspline_face_solid(body), 0.02 * diag, diag)
ellipsoid = Part.makeSphere(1.0).toNurbs().transformGeometry(squash).Solids[0]
add("OCCT ellipsoid `toNurbs()`", ellipsoid, 0.02 * ellipsoid.BoundBox.DiagonalLength)
ellipsoid = bspline_face_solid(Part.makeSphere(1.0)).transformGeometry(squash).Solids[0]
add("OCCT ellipsoid as a B-spline face", ellipsoid, 0.02 * ellipsoid.BoundBox.DiagonalLength)

table = ["| body | thickness / diagonal | x, y, z at 35/45/55/65 % | passed |", "|---|---|---|---|"] + rows
out = os.environ.get("S2N_TABLE", "cut_shell_grid.md")
open(out, "w").write("\n".join(table) + "\n")
os.remove(out + ".part")  # the rows so far, written as they came (a run takes minutes)
