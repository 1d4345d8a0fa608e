# Run by freecadcmd (FreeCAD's own Python): the STEP file subd2nurbs writes must import with
# Part.read and with Import.insert (FreeCAD's STEP importer) as one valid closed solid whose
# face count is the number of quads of the cage (an all-quad cage gives one face per quad),
# or, with polar structures, one face per polar cap instead of its triangles and 1-layer.
# Inputs come from the environment: S2N_STEP (the file), S2N_CAGE (the OBJ it came from).
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
print("check_step_import: ok, %d faces, area %.12g, FreeCAD %s" % (expected_faces, area_read, ".".join(FreeCAD.Version()[:3])))
os._exit(0)
