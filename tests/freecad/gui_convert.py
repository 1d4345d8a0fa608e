# GUI test of the Subd2Nurbs workbench (label freecad), run by run_gui_test.sh as
# `freecad gui_convert.py` under Xvfb with the workbench installed in $HOME's Mod folder:
# FreeCAD must have loaded the workbench from there; "Convert to NURBS" on an imported cage must
# give one valid solid with one face per cage quad; "Check surface quality" must run; the view
# is saved as a PNG (S2N_SCREENSHOT); "Colour map" must draw the curvature colours, saved as a
# second PNG next to it (..._colormap.png). Exits through os._exit (0 = pass) so the GUI closes.
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
    assert shape.isValid() and len(shape.Solids) == 1 and len(shape.Faces) == quads, \
        (shape.isValid(), len(shape.Solids), len(shape.Faces), quads)
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
