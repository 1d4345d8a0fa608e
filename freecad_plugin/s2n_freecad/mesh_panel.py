"""The task panel of "Convert to NURBS" on a triangle Mesh (docs/meshes.md, "FreeCAD").

The panel holds the mesh path's settings (the NURBS object's properties TargetFaces, EdgeLength,
FitTolerance, FeatureAngle and Tolerance, from the settings table). "Preview" converts the mesh
and shows the cage made from it in the 3D view, with its counts, its distance to the mesh and the
NURBS object's face count, before the NURBS object enters the document; the progress indicator
runs meanwhile and Esc cancels it. OK adds the NURBS object, reusing the previewed conversion
when the settings are those of the preview (else it converts); "Keep the cage" leaves the cage
in the document as a Cage object to edit. Cancel removes the preview: the document is as it was.

MeshConversion is the panel's logic without Qt (the headless tests drive it); MeshTaskPanel is
its form.
"""

import FreeCAD as App

import subd2nurbs

from . import api, features

#: The converter's settings the panel shows, in this order (rows of the settings table).
PANEL_SETTINGS = ("target_faces", "edge_length", "fit_tolerance", "feature_angle", "tolerance")


def summary_lines(result):
    """The preview's lines for people: the cage made from the mesh, how its size was chosen, its
    distance to the mesh, the kept sharp edges, the NURBS object's faces and poles."""
    r = result.report
    lines = []
    mesh = r.get("mesh")
    if mesh:
        cage = mesh["cage"]
        vertices = max(cage["vertices"], 1)
        lines.append("Cage: %d quads, %d extraordinary vertices (%.1f %%), %d sharp edges in %d curves"
                     % (cage["faces"], cage["extraordinary_vertices"], 100.0 * cage["extraordinary_vertices"] / vertices,
                        cage["feature_edges"], cage["feature_chains_kept"]))
        size = mesh.get("size") or {}
        rounds = size.get("rounds") or []
        if size.get("rule") == "fit_tolerance":
            lines.append("Size: fit tolerance %g %s (%d round%s, round %d kept)"
                         % (size["fit_tolerance"], "met" if size["tolerance_met"] else "NOT met", len(rounds),
                            "" if len(rounds) == 1 else "s", size["kept_round"] + 1))
        after = mesh["fit"]["after"]
        lines.append("Distance to the mesh: %.3g, from it %.3g (of the diagonal)"
                     % (after["limit_to_target"]["max"], after["target_to_limit"]["max"]))
        angles = mesh.get("feature_angles") or {}
        if angles.get("samples"):
            lines.append("Sharp edges: normals within %.2g deg of the mesh's dihedral (mean %.2g)"
                         % (angles["max_difference_deg"], angles["mean_difference_deg"]))
    else:
        lines.append("The mesh pairs back into quads: it is converted as its own cage (%s)"
                     % (r.get("input") or "cage"))
    brep = r.get("brep") or {}
    if brep:
        lines.append("NURBS: %d faces%s, %d poles, %s" % (
            brep["faces"], " (%d planar)" % brep["planar_faces"] if brep.get("planar_faces") else "",
            r["faces"]["poles"], "valid" if brep["valid"] else "NOT valid"))
    for w in result.warnings:
        lines.append("Warning: %s" % w)
    return lines


class MeshConversion:
    """The panel's state: the settings (property values by property name), the last preview's
    conversion and the Cage object showing its cage."""

    def __init__(self, source):
        if not (hasattr(source, "isDerivedFrom") and source.isDerivedFrom("Mesh::Feature")):
            raise TypeError("the mesh task panel converts a Mesh::Feature")
        self.source = source
        self.doc = source.Document
        rows = {row["name"]: row for row in features.SETTING_ROWS}
        self.rows = [rows[name] for name in PANEL_SETTINGS]
        # A new NURBS object's values (features.property_default; 0 where 0 means the default).
        self.values = {row["property"]["name"]: features.property_default(row) or 0 for row in self.rows}
        self.previewed = None  # (signature, ConversionResult) of the last preview
        self.cage_object = None
        self.lines = []

    def settings(self):
        """make_nurbs's keywords: the converter's names with the properties' values."""
        return {row["name"]: self.values[row["property"]["name"]] for row in self.rows}

    def _conversion_input(self):
        cage, kwargs = features.source_and_settings(self.source, features.settings_of(self.values))
        return cage, kwargs, features.NurbsFeature.signature(cage, kwargs)

    def preview(self, progress=True):
        """Converts with the current settings and shows the cage; returns the summary lines.
        Raises (the last preview kept) when the conversion fails or is cancelled
        (subd2nurbs.Cancelled)."""
        cage, kwargs, key = self._conversion_input()
        result = features.convert_cage(cage, kwargs, progress=progress)
        self.previewed = (key, result)
        self._show_cage(result.made_cage)
        self.lines = summary_lines(result)
        return self.lines

    def _show_cage(self, cage):
        """The cage as a Cage object (replacing the last preview's); none when the mesh went the
        cage road."""
        self.remove_cage()
        if cage is None:
            return
        obj = self.doc.addObject("Part::FeaturePython", self.source.Name + "_cage")
        obj.Label = self.source.Label + " cage"
        features.CageFeature(obj)
        features.CageFeature.store(obj, cage)
        if App.GuiUp:
            features.ViewProviderCage(obj.ViewObject)
        obj.recompute()
        self.cage_object = obj

    def remove_cage(self):
        if self.cage_object is not None:
            try:
                self.doc.removeObject(self.cage_object.Name)
            except Exception:  # removed by the user meanwhile
                pass
            self.cage_object = None

    def accept(self, keep_cage=False, progress=True):
        """Adds the NURBS object (the preview's conversion reused when the settings are the
        preview's) and returns it; the cage stays as a Cage object when keep_cage (and it was
        previewed with these settings), else it is removed. Raises (document as before, the
        preview kept) when the conversion fails or is cancelled."""
        _, _, key = self._conversion_input()
        reuse = self.previewed if self.previewed and self.previewed[0] == key else None
        obj = api.make_nurbs(self.source, progress=progress, previewed=reuse, **self.settings())
        if not (keep_cage and reuse):
            self.remove_cage()
        elif self.cage_object is not None and App.GuiUp:
            self.cage_object.ViewObject.Visibility = False
        self.cage_object = None
        return obj

    def reject(self):
        """Removes the preview: the document is as it was."""
        self.remove_cage()
        self.previewed = None


#: The open panel (the GUI test reaches it here); None when no panel is open.
ACTIVE = None


class MeshTaskPanel:
    """The task panel's form around a MeshConversion."""

    def __init__(self, source):
        from PySide import QtGui

        global ACTIVE
        self.logic = MeshConversion(source)
        self.form = QtGui.QWidget()
        self.form.setWindowTitle("Convert %s to NURBS" % source.Label)
        layout = QtGui.QFormLayout(self.form)
        self.fields = {}
        for row in self.logic.rows:
            p = row["property"]
            field = QtGui.QLineEdit(self.form)
            field.setText(repr(self.logic.values[p["name"]]))
            field.setToolTip(p["tooltip"])
            layout.addRow(p["name"], field)
            self.fields[p["name"]] = (row, field)
        self.keep_cage = QtGui.QCheckBox("Keep the cage in the document", self.form)
        layout.addRow(self.keep_cage)
        self.preview_button = QtGui.QPushButton("Preview (Esc cancels)", self.form)
        self.preview_button.clicked.connect(self.preview)
        layout.addRow(self.preview_button)
        self.summary = QtGui.QLabel("Preview: the cage made from the mesh and the NURBS face count, "
                                    "before the NURBS object is added.", self.form)
        self.summary.setWordWrap(True)
        layout.addRow(self.summary)
        ACTIVE = self

    def _read_fields(self):
        """The fields into the settings; a SettingsError names the property whose text is not a
        number (the converter's rules check the numbers)."""
        for name, (row, field) in self.fields.items():
            text = field.text().strip()
            try:
                value = int(text) if row["type"] == "integer" else float(text)
            except ValueError:
                raise subd2nurbs.SettingsError("%s must be a number, not %r" % (name, text), setting=row["name"],
                                               rule="must be a number") from None
            self.logic.values[name] = value

    def preview(self):
        try:
            self._read_fields()
            lines = self.logic.preview()
        except subd2nurbs.Cancelled:
            self.summary.setText("Preview cancelled.")
            return False
        except Exception as e:
            self.summary.setText("Preview failed: %s" % e)
            App.Console.PrintError("Subd2Nurbs: preview of %s failed: %s\n" % (self.logic.source.Label, e))
            return False
        self.summary.setText("\n".join(lines))
        App.Console.PrintMessage("Subd2Nurbs: preview of %s:\n  %s\n" % (self.logic.source.Label, "\n  ".join(lines)))
        return True

    def accept(self):
        import FreeCADGui as Gui
        global ACTIVE
        try:
            self._read_fields()
            obj = self.logic.accept(keep_cage=self.keep_cage.isChecked())
        except subd2nurbs.Cancelled:
            self.summary.setText("Conversion cancelled: nothing was added.")
            return False
        except Exception as e:
            from .commands import _report_failure
            _report_failure("Convert to NURBS (%s)" % self.logic.source.Label, e)
            return False
        App.Console.PrintMessage("Subd2Nurbs: %s: %d NURBS faces\n" % (obj.Label, len(obj.Shape.Faces)))
        Gui.Control.closeDialog()
        ACTIVE = None
        Gui.Selection.clearSelection()
        Gui.Selection.addSelection(obj)
        return True

    def reject(self):
        import FreeCADGui as Gui
        global ACTIVE
        self.logic.reject()
        Gui.Control.closeDialog()
        ACTIVE = None
        return True

    def getStandardButtons(self):
        from PySide import QtGui
        return int(QtGui.QDialogButtonBox.Ok | QtGui.QDialogButtonBox.Cancel)
