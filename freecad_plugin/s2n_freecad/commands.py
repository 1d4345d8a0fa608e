"""GUI commands of the Subd2Nurbs workbench. Each runs the headless API (api.py) inside a
transaction: one Undo reverts it, and a failure is reported (report view and a message box)
with the document left as it was."""

import os

import FreeCAD as App
import FreeCADGui as Gui

from . import api, features


def _report_failure(title, error):
    App.Console.PrintError("Subd2Nurbs: %s failed: %s\n" % (title, error))
    try:
        from PySide import QtGui
        QtGui.QMessageBox.critical(Gui.getMainWindow(), "Subd2Nurbs: " + title, str(error))
    except Exception:  # no Qt (headless): the report view line is enough
        pass


def _selected_sources():
    sel = Gui.Selection.getSelection()
    return [o for o in sel if features.is_cage(o) or o.isDerivedFrom("Mesh::Feature")]


class ImportCage:
    def GetResources(self):
        return {"Pixmap": os.path.join(features.ICONS, "Subd2Nurbs_Cage.svg"),
                "MenuText": "Import subdivision cage...",
                "ToolTip": "Read an OBJ cage (quads, n-gons, OpenSubdiv crease / corner / hole tags) or a "
                           "glTF / GLB mesh (quads recovered) as a parametric Cage"}

    def IsActive(self):
        return True

    def Activated(self):
        from PySide import QtGui
        path, _ = QtGui.QFileDialog.getOpenFileName(Gui.getMainWindow(), "Import subdivision cage", "",
                                                    "Subdivision cages (*.obj *.usd *.usda *.usdc *.usdz *.glb *.gltf *.stl *.ply *.off);;"
                                                    "USD (*.usd *.usda *.usdc *.usdz);;All files (*)")
        if not path:
            return
        doc = App.ActiveDocument or App.newDocument()
        try:
            obj = api.make_cage(path, doc=doc, name=os.path.splitext(os.path.basename(path))[0] or "Cage")
        except Exception as e:
            _report_failure("Import subdivision cage", e)
            return
        Gui.SendMsgToActiveView("ViewFit")
        App.Console.PrintMessage("Subd2Nurbs: imported %s: %d vertices, %d faces, %d creases\n"
                                 % (path, obj.NumVertices, obj.NumFaces, obj.NumCreases))


class ConvertToNurbs:
    def GetResources(self):
        return {"Pixmap": os.path.join(features.ICONS, "Subd2Nurbs_Convert.svg"),
                "MenuText": "Convert to NURBS",
                "ToolTip": "Convert the selected subdivision Cage or triangle Mesh into a parametric NURBS "
                           "solid (recomputed when the source or its properties change)"}

    def IsActive(self):
        return App.ActiveDocument is not None and bool(_selected_sources())

    def Activated(self):
        sources = _selected_sources()
        if len(sources) == 1 and self._open_mesh_panel(sources[0]):
            return
        made = []
        for source in sources:
            try:
                obj = api.make_nurbs(source, name=source.Label + "_NURBS")
            except Exception as e:
                _report_failure("Convert to NURBS (%s)" % source.Label, e)
                continue
            made.append(obj)
            msg = "Subd2Nurbs: %s: %d NURBS faces" % (obj.Label, obj.Patches)
            if obj.RecoveredQuads >= 0:
                msg += ", %d quads recovered from the mesh's triangles, %d triangles kept" % (
                    obj.RecoveredQuads, obj.KeptTriangles)
            App.Console.PrintMessage(msg + "\n")
        if made:
            Gui.Selection.clearSelection()
            Gui.Selection.addSelection(made[-1])


    @staticmethod
    def _open_mesh_panel(source):
        """One Mesh to reproduce (docs/meshes.md) opens the mesh task panel (mesh_panel.py):
        settings, a preview of the cage and the face count, progress and cancel. True if it
        opened."""
        if not source.isDerivedFrom("Mesh::Feature"):
            return False
        try:
            if features.cage_of(source).route["kind"] != "mesh":
                return False
        except Exception as e:
            _report_failure("Convert to NURBS (%s)" % source.Label, e)
            return True
        if Gui.Control.activeDialog():
            _report_failure("Convert to NURBS", "another task panel is open: close it first")
            return True
        from . import mesh_panel
        Gui.Control.showDialog(mesh_panel.MeshTaskPanel(source))
        return True


class _OnSelectedNurbs:
    """A command run on every selected NURBS object; failures are reported per object."""

    TITLE = ""

    def IsActive(self):
        return any(isinstance(getattr(o, "Proxy", None), features.NurbsFeature)
                   for o in Gui.Selection.getSelection())

    def Activated(self):
        for obj in Gui.Selection.getSelection():
            if isinstance(getattr(obj, "Proxy", None), features.NurbsFeature):
                try:
                    self.run(obj)
                except Exception as e:
                    _report_failure("%s (%s)" % (self.TITLE, obj.Label), e)


class CheckQuality(_OnSelectedNurbs):
    TITLE = "Check surface quality"

    def GetResources(self):
        return {"Pixmap": os.path.join(features.ICONS, "Subd2Nurbs_Check.svg"),
                "MenuText": self.TITLE,
                "ToolTip": "Report gaps, normal jumps, the deviation from the limit surface, the smallest radius "
                           "of curvature (the thickest shell or offset) and self-intersecting or overlapping "
                           "faces of the selected NURBS object in the report view, and highlight its worst edges"}

    def run(self, obj):
        api.check_quality(obj)


class ColorMap(_OnSelectedNurbs):
    TITLE = "Colour map"

    def GetResources(self):
        return {"Pixmap": os.path.join(features.ICONS, "Subd2Nurbs_Check.svg"),
                "MenuText": "Colour map (curvature)",
                "ToolTip": "Show the selected NURBS object's mean curvature as per-vertex colours (a ColorMap "
                           "object: change its Coloring to Deviation or Zebra), the colours of "
                           "subd2nurbs convert --preview"}

    def run(self, obj):
        api.make_color_map(obj)


class FitCageToMesh:
    def GetResources(self):
        return {"Pixmap": os.path.join(features.ICONS, "Subd2Nurbs_Cage.svg"),
                "MenuText": "Fit cage to mesh",
                "ToolTip": "Select a Cage and a Mesh (or a shape): a parametric FittedCage whose limit surface "
                           "follows the mesh, with the cage's topology and tags (refits when either changes)"}

    @staticmethod
    def _selection():
        sel = Gui.Selection.getSelection()
        cages = [o for o in sel if features.is_cage(o)]
        targets = [o for o in sel if not features.is_cage(o)]
        return (cages[0], targets[0]) if len(cages) == 1 and len(targets) == 1 else None

    def IsActive(self):
        return App.ActiveDocument is not None and self._selection() is not None

    def Activated(self):
        cage, target = self._selection()
        try:
            obj = api.make_fitted_cage(cage, target, name=cage.Label + "_fitted")
        except Exception as e:
            _report_failure("Fit cage to mesh", e)
            return
        App.Console.PrintMessage("Subd2Nurbs: %s: %d iterations (%s), two-sided distance %.3g -> %.3g of the "
                                 "target's size\n" % (obj.Label, obj.Iterations, obj.Stop, obj.DistanceBefore,
                                                      obj.DistanceAfter))


COMMANDS = {
    "Subd2Nurbs_ImportCage": ImportCage(),
    "Subd2Nurbs_FitCage": FitCageToMesh(),
    "Subd2Nurbs_Convert": ConvertToNurbs(),
    "Subd2Nurbs_CheckQuality": CheckQuality(),
    "Subd2Nurbs_ColorMap": ColorMap(),
}

for _name, _command in COMMANDS.items():
    Gui.addCommand(_name, _command)
