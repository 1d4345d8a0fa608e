# Run by freecadcmd (FreeCAD's own Python): the STEP file subd2nurbs writes must import with
# Part.read and with Import.insert (FreeCAD's STEP importer) as one valid closed solid whose
# face count is the number of quads of the cage (an all-quad cage gives one face per quad),
# or, with polar structures, one face per polar cap instead of its triangles and 1-layer.
# The packed STEP (--faces packed, the default) must import as one valid closed solid with the
# face count of its report and the same area and volume (1e-9 relative) as the per-quad one.
# Inputs come from the environment: S2N_STEP (the per-quad file), S2N_CAGE (the OBJ it came
# from), S2N_PACKED and S2N_PACKED_REPORT (the packed file and its report).
# Run as: freecadcmd -c "exec(open('check_step_import.py').read())" — a plain script
# argument would exit 0 even when the script fails.
import os
import sys

import FreeCAD
import Import
import Part


def fail(message):
    sys.stderr.write("check_step_import: FAILED: " + message + "\n")
    sys.stderr.flush()
    os._exit(1)


step = os.environ["S2N_STEP"]
cage = os.environ["S2N_CAGE"]
faces_of_cage = [[int(t.split("/")[0]) for t in line.split()[1:]] for line in open(cage) if line.startswith("f ")]
sizes = [len(f) for f in faces_of_cage]
# A cage of quads, or of quads and polar structures (poles whose faces are all triangles, see
# docs/polar.md): each pole's triangles and the quads touching its ring of neighbours (the
# 1-layer) become one polar cap face with a degenerated edge at the pole.
triangles = [f for f in faces_of_cage if len(f) == 3]
if not sizes or any(s not in (3, 4) for s in sizes):
    fail("the test expects a cage of quads and polar triangle fans: " + cage)
corners = {}
for f in faces_of_cage:
    for v in f:
        corners.setdefault(v, []).append(len(f))
poles = [v for v, fs in corners.items() if all(n == 3 for n in fs)]
if sum(len(corners[v]) for v in poles) != len(triangles):
    fail("triangles that are not around a pole: " + cage)
ring1 = {v for f in triangles for v in f if v not in poles}
layer1 = [f for f in faces_of_cage if len(f) == 4 and any(v in ring1 for v in f)]
expected_faces = sizes.count(4) - len(layer1) + len(poles)

shape = Part.read(step)
if not shape.isValid():
    fail("Part.read: shape not valid")
if len(shape.Solids) != 1:
    fail("Part.read: %d solids, expected 1" % len(shape.Solids))
if len(shape.Faces) != expected_faces:
    fail("Part.read: %d faces, expected %d" % (len(shape.Faces), expected_faces))
if not shape.Solids[0].isClosed():
    fail("Part.read: solid not closed")
degenerated = sum(1 for e in shape.Edges if e.Degenerated)
if degenerated != len(poles):
    fail("Part.read: %d degenerated edges, expected one per pole (%d)" % (degenerated, len(poles)))

doc = FreeCAD.newDocument("s2n_import")
Import.insert(step, doc.Name)
doc.recompute()
faces = sum(len(o.Shape.Faces) for o in doc.Objects if hasattr(o, "Shape"))
if faces != expected_faces:
    fail("Import.insert: %d faces in %d objects, expected %d" % (faces, len(doc.Objects), expected_faces))
area_read = shape.Area
area_insert = sum(o.Shape.Area for o in doc.Objects if hasattr(o, "Shape"))
if abs(area_read - area_insert) > 1e-9 * area_read:
    fail("areas differ: Part.read %.17g, Import.insert %.17g" % (area_read, area_insert))
FreeCAD.closeDocument(doc.Name)

import json

# FreeCAD's Shape.Area / Volume integrate to about 1e-6 only; the faces' own B-spline
# surfaces (as FreeCAD read them) are integrated here with 8 x 8 Gauss-Legendre points per
# knot span instead: the volume integrand is polynomial (exact), the area's smooth.
GAUSS = [(-0.9602898564975363, 0.1012285362903763), (-0.7966664774136267, 0.2223810344533745),
         (-0.5255324099163290, 0.3137066458778873), (-0.1834346424956498, 0.3626837833783620),
         (0.1834346424956498, 0.3626837833783620), (0.5255324099163290, 0.3137066458778873),
         (0.7966664774136267, 0.2223810344533745), (0.9602898564975363, 0.1012285362903763)]


def area_and_volume(solid):
    centre = solid.BoundBox.Center
    area = volume = 0.0
    for f in solid.Faces:
        s = f.Surface
        sign = -1.0 if f.Orientation == "Reversed" else 1.0
        uk, vk = s.getUKnots(), s.getVKnots()
        for i in range(len(uk) - 1):
            hu = (uk[i + 1] - uk[i]) / 2
            for j in range(len(vk) - 1):
                hv = (vk[j + 1] - vk[j]) / 2
                for a, wa in GAUSS:
                    for b, wb in GAUSS:
                        u, v = uk[i] + hu * (1 + a), vk[j] + hv * (1 + b)
                        n = s.getDN(u, v, 1, 0).cross(s.getDN(u, v, 0, 1))
                        w = wa * wb * hu * hv
                        area += w * n.Length
                        volume += sign * w * (s.value(u, v) - centre).dot(n)
    return area, abs(volume) / 3


packed = Part.read(os.environ["S2N_PACKED"])
packed_faces = json.load(open(os.environ["S2N_PACKED_REPORT"]))["faces"]["total"]
if not packed.isValid() or len(packed.Solids) != 1 or not packed.Solids[0].isClosed():
    fail("packed: not one valid closed solid")
if len(packed.Faces) != packed_faces:
    fail("packed: %d faces, the report says %d" % (len(packed.Faces), packed_faces))
if packed_faces > expected_faces:
    fail("packed: %d faces, more than per quad (%d)" % (packed_faces, expected_faces))
measured = area_and_volume(packed), area_and_volume(shape)
for k, what in enumerate(("area", "volume")):
    a, b = measured[0][k], measured[1][k]
    if abs(a - b) > 1e-9 * abs(b):
        fail("packed %s %.17g differs from per-quad %.17g" % (what, a, b))
print("check_step_import: ok, %d faces (packed %d), area %.12g, volume %.12g, FreeCAD %s"
      % (expected_faces, packed_faces, measured[1][0], measured[1][1], ".".join(FreeCAD.Version()[:3])))
os._exit(0)
