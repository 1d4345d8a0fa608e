# GUI test of the Subd2Nurbs workbench (label freecad), run by run_gui_test.sh as
# `freecad gui_convert.py` under Xvfb with the workbench installed in $HOME's Mod folder:
# FreeCAD must have loaded the workbench from there; "Convert to NURBS" on an imported cage must
# give one valid solid with one face per cage quad; "Check surface quality" must run; the view
# is saved as a PNG (S2N_SCREENSHOT); "Colour map" must draw the curvature colours, saved as a
# second PNG next to it (..._colormap.png); "Convert to NURBS" on a triangle Mesh (S2N_MESH) must
# open the mesh task panel, whose preview shows the cage and whose OK adds a valid solid with the
# face count the preview gave (a third PNG, ..._mesh_panel.png, shows the preview). Exits through os._exit (0 = pass) so the GUI closes.
import os
import sys
import traceback


def main():
    import FreeCAD as App
    import FreeCADGui as Gui

    cage_path = os.environ["S2N_CAGE"]
    out = os.environ["S2N_SCREENSHOT"]
    quads = sum(1 for line in open(cage_path) if line.startswith("f "))

    Gui.activateWorkbench("Subd2NurbsWorkbench")
    wb = Gui.activeWorkbench()
    assert wb.name() == "Subd2NurbsWorkbench", wb.name()
    assert "Subd2Nurbs_Convert" in Gui.listCommands()
    import s2n_freecad
    mod_dir = os.path.join(os.environ["HOME"], ".local", "share", "FreeCAD", "Mod")
    assert os.path.realpath(s2n_freecad.__file__).startswith(os.path.realpath(mod_dir)), s2n_freecad.__file__

    import s2n_freecad.api as api
    from s2n_freecad import features
    doc = App.newDocument("Subd2NurbsGui")
    cage = api.make_cage(cage_path, doc=doc, name="Cage")
    Gui.Selection.clearSelection()
    Gui.Selection.addSelection(cage)
    Gui.runCommand("Subd2Nurbs_Convert")
    made = [o for o in doc.Objects if isinstance(getattr(o, "Proxy", None), features.NurbsFeature)]
    assert len(made) == 1, [o.Name for o in doc.Objects]
    nurbs = made[0]
    shape = nurbs.Shape
    # Packed faces: as many as the module makes of the cage (rounded_box: one per side), fewer
    # than its quads.
    import subd2nurbs
    faces = subd2nurbs.convert(subd2nurbs.read_cage(cage_path)).brep["faces"]
    assert faces < quads, (faces, quads)
    assert shape.isValid() and len(shape.Solids) == 1 and len(shape.Faces) == faces, \
        (shape.isValid(), len(shape.Solids), len(shape.Faces), faces)
    Gui.Selection.clearSelection()
    Gui.Selection.addSelection(nurbs)
    Gui.runCommand("Subd2Nurbs_CheckQuality")
    colors = nurbs.ViewObject.LineColorArray
    assert len(colors) == len(shape.Edges), (len(colors), len(shape.Edges))

    cage.ViewObject.Visibility = True
    nurbs.ViewObject.Transparency = 20
    nurbs.ViewObject.ShapeColor = (0.91, 0.64, 0.24)
    view = Gui.activeDocument().activeView()
    view.viewIsometric()
    view.fitAll()
    Gui.updateGui()
    view.saveImage(out, 1000, 700, "White")
    assert os.path.getsize(out) > 10000, os.path.getsize(out)

    # The colour map (mean curvature) drawn by its Coin view provider, in a second picture.
    Gui.Selection.clearSelection()
    Gui.Selection.addSelection(nurbs)
    Gui.runCommand("Subd2Nurbs_ColorMap")
    maps = [o for o in doc.Objects if isinstance(getattr(o, "Proxy", None), features.ColorMapFeature)]
    assert len(maps) == 1, [o.Name for o in doc.Objects]
    colour = maps[0]
    assert colour.isValid() and len(colour.Colors) == len(colour.Points) > 0
    Gui.Selection.clearSelection()
    cage.ViewObject.Visibility = False
    view.viewIsometric()
    view.fitAll()
    Gui.updateGui()
    out2 = out[:-4] + "_colormap.png"
    view.saveImage(out2, 1000, 700, "White")
    assert os.path.getsize(out2) > 10000, os.path.getsize(out2)

    # "Convert to NURBS" on a triangle Mesh opens the mesh task panel: the preview shows the
    # cage made from the mesh and the face count; OK adds the NURBS object with that count.
    import Mesh
    from s2n_freecad import mesh_panel
    maps[0].ViewObject.Visibility = False
    nurbs.ViewObject.Visibility = False
    mesh = doc.addObject("Mesh::Feature", "PlateMesh")
    mesh.Mesh = Mesh.read(os.environ["S2N_MESH"])
    doc.recompute()
    Gui.Selection.clearSelection()
    Gui.Selection.addSelection(mesh)
    Gui.runCommand("Subd2Nurbs_Convert")
    panel = mesh_panel.ACTIVE
    assert panel is not None and Gui.Control.activeDialog(), "the mesh task panel did not open"
    panel.fields["TargetFaces"][1].setText("200")
    assert panel.preview(), panel.summary.text()
    preview = panel.logic.cage_object
    text = panel.summary.text()
    assert preview is not None and "Cage: %d quads" % preview.NumFaces in text, text
    view.viewIsometric()
    view.fitAll()
    Gui.updateGui()
    out3 = out[:-4] + "_mesh_panel.png"
    view.saveImage(out3, 1000, 700, "White")
    before = len(doc.Objects)
    assert panel.accept()
    assert mesh_panel.ACTIVE is None and not Gui.Control.activeDialog()
    made = [o for o in doc.Objects if isinstance(getattr(o, "Proxy", None), features.NurbsFeature)
            and o.Source == mesh]
    assert len(made) == 1 and len(doc.Objects) == before, [o.Name for o in doc.Objects]  # the preview cage went
    solid = made[0].Shape
    assert solid.isValid() and len(solid.Solids) == 1, (solid.isValid(), len(solid.Solids))
    assert "NURBS: %d faces" % len(solid.Faces) in text, (len(solid.Faces), text)
    App.Console.PrintMessage("gui_convert: ok, %d faces, screenshot %s\n" % (len(shape.Faces), out))


try:
    main()
    code = 0
except BaseException:
    traceback.print_exc()
    code = 1
sys.stdout.flush()
sys.stderr.flush()
os._exit(code)
