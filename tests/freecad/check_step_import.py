# Run by freecadcmd (FreeCAD's own Python): the STEP file subd2nurbs writes must import with
# Part.read and with Import.insert (FreeCAD's STEP importer) as one valid closed solid whose
# face count is the number of quads of the cage (an all-quad cage gives one face per quad).
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
sizes = [len(line.split()) - 1 for line in open(cage) if line.startswith("f ")]
if not sizes or any(s != 4 for s in sizes):
    fail("the test expects an all-quad cage: " + cage)
expected_faces = len(sizes)

shape = Part.read(step)
if not shape.isValid():
    fail("Part.read: shape not valid")
if len(shape.Solids) != 1:
    fail("Part.read: %d solids, expected 1" % len(shape.Solids))
if len(shape.Faces) != expected_faces:
    fail("Part.read: %d faces, expected %d" % (len(shape.Faces), expected_faces))
if not shape.Solids[0].isClosed():
    fail("Part.read: solid not closed")

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
