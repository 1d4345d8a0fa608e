# Shared by the downstream suite (downstream_ops.py) and scripts/cut_shell_grid.py, both run by
# freecadcmd: the cutting box and the faces it leaves, and OCCT's own B-spline face of a one-face
# closed body.
import Part
from FreeCAD import Vector


def frame(body):
    bb = body.BoundBox
    lo = [bb.XMin, bb.YMin, bb.ZMin]
    hi = [bb.XMax, bb.YMax, bb.ZMax]
    return lo, hi, bb.DiagonalLength


def half_space_box(body, axis, frac):
    """A box over the part of the body beyond the plane axis = lo + frac * extent."""
    lo, hi, diag = frame(body)
    c = lo[axis] + frac * (hi[axis] - lo[axis])
    m = 0.1 * diag
    origin = [l - m for l in lo]
    size = [h - l + 2 * m for l, h in zip(lo, hi)]
    origin[axis] = c
    size[axis] = hi[axis] - c + m
    return Part.makeBox(size[0], size[1], size[2], Vector(*origin)), c


def faces_at_cut(part, axis, c, diag):
    """The planar faces a cut at axis = c left on `part` (the faces a shell removes)."""
    return [f for f in part.Faces if f.Surface.__class__.__name__ == "Plane"
            and abs(f.CenterOfMass[axis] - c) < 1e-6 * diag]


def bspline_face_solid(body):
    """A one-face closed body's surface as OCCT's B-spline surface, made a face by OCCT itself
    (MakeFace: line pcurves, as ours), unlike toNurbs(), whose B-spline pcurves fail on their own
    (docs/downstream.md "Cut-then-shell over a grid of cuts")."""
    solid = Part.Solid(Part.Shell([Part.Face(body.Faces[0].Surface.toBSpline())]))
    if solid.Volume < 0:
        solid.reverse()
    return solid
