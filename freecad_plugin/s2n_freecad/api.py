"""Headless API of the Subd2Nurbs workbench: usable from FreeCAD's Python console, macros and
freecadcmd, with or without the GUI.

    import s2n_freecad.api as s2n
    cage = s2n.make_cage("/path/part.obj")            # parametric Cage (points, faces, tags)
    nurbs = s2n.make_nurbs(cage, level=1)             # parametric NURBS solid from the cage
    nurbs = s2n.make_nurbs(mesh_feature)              # ... or from a triangle Mesh::Feature
    report = s2n.check_quality(nurbs)                 # gap, normal jump, deviation, worst edges

Every factory checks its input before it touches the document: a bad cage raises (a
subd2nurbs.CageError naming the element) and leaves the document as it was. With the GUI
up, each factory runs inside a transaction, so one Undo removes what it added.
"""

import FreeCAD as App
import Part

import subd2nurbs

from . import features


def _document(doc):
    doc = doc or App.ActiveDocument or App.newDocument()
    return doc


class _Transaction:
    """Opens a transaction (one Undo step) and aborts it if the body raises."""

    def __init__(self, doc, name):
        self.doc, self.name = doc, name

    def __enter__(self):
        self.doc.openTransaction(self.name)
        return self

    def __exit__(self, kind, value, tb):
        if kind is None:
            self.doc.commitTransaction()
        else:
            self.doc.abortTransaction()
        return False


def _show_and_recompute(obj, view_provider, what, hide=None):
    """Gives `obj` its view provider (with the GUI; `hide` is made invisible), recomputes its
    document and raises if `obj` did not recompute, so that the caller's transaction aborts."""
    if App.GuiUp:
        view_provider(obj.ViewObject)
        if hide is not None:
            hide.ViewObject.Visibility = False
    obj.Document.recompute()
    if not obj.isValid():
        raise RuntimeError("the %s failed to recompute: %s" % (what, obj.getStatusString()))


def check_occt():
    """Raises RuntimeError unless FreeCAD's OCCT is the version subd2nurbs links (BREP text
    is exchanged between the two, see docs)."""
    import Part
    if not subd2nurbs.occt_compatible(Part.OCC_VERSION):
        raise RuntimeError("subd2nurbs is linked with OpenCASCADE %s but FreeCAD uses %s: rebuild subd2nurbs "
                           "against FreeCAD's OpenCASCADE" % (subd2nurbs.OCC_VERSION, Part.OCC_VERSION))


def read_cage(path, variant=None):
    """A subd2nurbs.Cage from a file: OBJ with quads, n-gons and OpenSubdiv crease / corner /
    hole tags (read by subd2nurbs itself; FreeCAD's OBJ reader drops 5+-gons), USD (.usd /
    .usda / .usdc / .usdz with creases, corners and holes; `variant` as subd2nurbs.read_cage),
    or glTF / GLB (quads recovered from triangles), or STL / PLY / OFF."""
    return subd2nurbs.read_cage(path, variant=variant)


def make_cage(source, doc=None, name="Cage"):
    """A parametric Cage object from a file path or a subd2nurbs.Cage, shown as wires.
    Raises subd2nurbs.CageError (document unchanged) if the cage is not valid."""
    cage = read_cage(source) if isinstance(source, str) else source
    if not isinstance(cage, subd2nurbs.Cage):
        raise TypeError("make_cage: expected a file path or a subd2nurbs.Cage")
    cage.validate()  # topology and tags, before the document is touched
    doc = _document(doc)
    with _Transaction(doc, "Import subdivision cage"):
        obj = doc.addObject("Part::FeaturePython", name)
        features.CageFeature(obj)
        features.CageFeature.store(obj, cage, source if isinstance(source, str) else "")
        _show_and_recompute(obj, features.ViewProviderCage, "cage object")
    return obj


def make_fitted_cage(cage, target, smoothing=1e-4, max_iterations=30, doc=None, name="FittedCage"):
    """A parametric FittedCage object: the Cage object `cage` (its topology and tags) with its
    vertices fitted so that its limit surface follows `target` (a Mesh::Feature, or an object
    whose shape's vertices are taken as points), as `subd2nurbs fit` does. It is a Cage (convert
    it with make_nurbs) and refits when the cage, the target, Smoothing or MaxIterations change.
    Its Iterations, Stop, DistanceBefore and DistanceAfter say how the fit went. Raises (document
    unchanged) when the fit fails."""
    if not features.is_cage(cage):
        raise TypeError("make_fitted_cage: expected a Cage object")
    if target is None or not hasattr(target, "Document"):
        raise TypeError("make_fitted_cage: expected a Mesh::Feature or a shape as the target")
    doc = doc or cage.Document
    with _Transaction(doc, "Fit cage to mesh"):
        obj = doc.addObject("Part::FeaturePython", name)
        try:
            features.FittedCageFeature(obj)
            obj.Source = cage
            obj.Target = target
            obj.Smoothing = float(smoothing)
            obj.MaxIterations = int(max_iterations)
            _show_and_recompute(obj, features.ViewProviderCage, "fitted cage", hide=cage)
        except Exception:
            doc.removeObject(obj.Name)  # also without undo (headless): the document as it was
            doc.recompute()
            raise
    return obj


def make_nurbs(source, shell=False, doc=None, name="NURBS", progress=True, previewed=None, **settings):
    """A parametric NURBS object (Part::FeaturePython) converted from a Cage object or a
    Mesh::Feature. A Mesh takes the road of docs/meshes.md: a triangulated cage gets its quads back
    (triangle pairs; fans around high-valence vertices are kept; the object's RecoveredQuads says
    how many), a mesh to reproduce is remeshed into a quad cage fitted to it (target_faces,
    edge_length, feature_angle; the object's InputRoute, CageFaces, FeatureEdges, MeshDistance).

    settings: the NURBS object's conversion settings by the converter's names, with the values of
    their properties (features.SETTING_ROWS, docs/settings.md): level=1 (Level), tolerance=1e-3
    (Tolerance; > 0 chooses the levels for this deviation), polar="Catmull-Clark" (PolarHandling,
    default "Polar caps"), fit="Interpolate" (Fit), fair=0.1 (FairWeight, with Interpolate),
    faces="PerQuad" (Faces, default "Packed"), max_faces, max_memory (MaxMemoryMiB). shell: a shell
    instead of a solid. It recomputes when the source or one of its properties changes. Raises
    (document unchanged) when the conversion fails, or subd2nurbs.Cancelled when the user
    cancels it (Esc in the GUI's progress indicator; progress: True, False or a callable as
    subd2nurbs.convert takes). previewed: a (signature, result) pair of an earlier conversion
    (the mesh task panel's preview), used instead of converting again when its signature is
    this source's and settings' (features.NurbsFeature.signature)."""
    check_occt()
    if source is None or not hasattr(source, "Document"):
        raise TypeError("make_nurbs: expected a Cage object or a Mesh::Feature")
    prop = {row["name"]: row["property"]["name"] for row in features.SETTING_ROWS}
    for key in settings:
        if key not in prop:
            raise TypeError("make_nurbs: unknown setting '%s' (the NURBS object's settings: %s)"
                            % (key, ", ".join(prop)))
    values = {prop[key]: value for key, value in settings.items()}
    doc = doc or source.Document
    # Convert before touching the document (errors leave it as it was); the first recompute
    # reuses the result.
    cage, kwargs = features.source_and_settings(source, features.settings_of(values))
    if previewed is not None and previewed[0] == features.NurbsFeature.signature(cage, kwargs):
        result = previewed[1]
    else:
        result = features.convert_cage(cage, kwargs, progress=progress)
    with _Transaction(doc, "Convert to NURBS"):
        obj = doc.addObject("Part::FeaturePython", name)
        proxy = features.NurbsFeature(obj)
        for property_name, value in values.items():
            setattr(obj, property_name, value)
        proxy.prepare(features.NurbsFeature.signature(*features.source_and_settings(source, features.object_settings(obj))),
                      result)
        obj.Source = source
        obj.OutputType = "Shell" if shell else "Solid"
        obj.ShowProgress = bool(progress)
        _show_and_recompute(obj, features.ViewProviderNurbs, "NURBS object", hide=source)
    return obj


def _faces_at(shape, point, tolerance):
    """The names ("FaceN") of the faces of `shape` passing through `point`."""
    vertex = Part.Vertex(App.Vector(*point))
    names = []
    for i, face in enumerate(shape.Faces):
        box = face.BoundBox
        box.enlarge(tolerance)
        if box.isInside(vertex.Point) and face.distToShape(vertex)[0] <= tolerance:
            names.append("Face%d" % (i + 1))
    return names


def _radius(entry):
    if not entry:
        return None
    return {"radius": entry["radius"], "point": tuple(entry["point"]), "u": entry["u"], "v": entry["v"]}


def _point_text(p):
    return "(%.4g, %.4g, %.4g)" % tuple(p)


def check_quality(obj, count=5, highlight=True):
    """The surface quality of a NURBS object: max gap between patches, max normal jump across
    smooth edges, max deviation from the limit surface, the `count` worst edges (names
    "EdgeN", normal angle in degrees, gap), the smallest radius of curvature each way (inward:
    the thickest shell / inward offset the body takes; outward: the thickest outward offset) and
    where, and the self-intersections and overlapping parts the conversion found, each with a
    point on both faces and the faces there ("FaceN"). Printed to the report view; with the
    GUI the worst edges are drawn in red and selected."""
    proxy = getattr(obj, "Proxy", None)
    if not isinstance(proxy, features.NurbsFeature):
        raise TypeError("check_quality: expected a NURBS object made by make_nurbs")
    result = proxy.result(obj)
    r = result.report
    worst = [("Edge%d" % e, angle, gap) for e, angle, gap in result.worst_edges(count)]
    report = {
        "object": obj.Name,
        "faces": r["brep"]["faces"] if r["brep"] else 0,
        "valid": bool(r["brep"] and r["brep"]["valid"]),
        "max_gap": r["continuity"]["max_gap"],
        "max_gap_relative": r["continuity"]["max_gap_relative"],
        "max_normal_angle_deg": r["continuity"]["max_normal_angle_deg"],
        "max_crease_normal_angle_deg": r["continuity"]["max_crease_normal_angle_deg"],
        "max_deviation": r["deviation"]["max"],
        "deviation_relative": r["deviation"]["relative"],
        "worst_edges": worst,
        "report": r,
    }
    radius = r["curvature_radius"]
    report["smallest_radius"] = {"inward": _radius(radius["inward"]), "outward": _radius(radius["outward"])}
    x = r["self_intersection"]
    tolerance = 1e-6 * max(r["model_size"], 1e-300)
    witnesses = []
    for kind, items in (("self", x["self"]), ("overlap", x["overlaps"])):
        for w in items[:count]:
            witnesses.append({"kind": "inside" if w.get("inside") else kind, "point": tuple(w["point"]),
                              "faces": _faces_at(obj.Shape, w["point"], tolerance)})
    report["self_intersections"] = x["crossing_face_pairs"]
    report["overlaps"] = x["overlap_face_pairs"]
    report["overlapping_parts"] = [tuple(p) for p in x["overlapping_components"]]
    report["intersection_witnesses"] = witnesses
    lines = ["Subd2Nurbs quality of %s (%d faces, %s):" % (obj.Label, report["faces"],
                                                          "valid" if report["valid"] else "NOT valid"),
             "  max gap between patches   %.3g (%.3g of the model size)" % (report["max_gap"],
                                                                          report["max_gap_relative"] or 0),
             "  max normal jump (smooth)  %.3g deg" % report["max_normal_angle_deg"],
             "  max deviation from limit  %.3g (%.3g of the model size)" % (report["max_deviation"],
                                                                          report["deviation_relative"] or 0)]
    for name, angle, gap in worst:
        lines.append("  worst: %-8s normal jump %.3g deg, gap %.3g" % (name, angle, gap))
    for side, use in (("inward", "shell / inward offset"), ("outward", "outward offset")):
        at = report["smallest_radius"][side]
        if at is None:
            lines.append("  smallest radius %-8s none (no %s limit)" % (side, use))
        else:
            lines.append("  smallest radius %-8s %.4g at %s: keep a %s thinner" % (side, at["radius"],
                                                                                 _point_text(at["point"]), use))
    if report["self_intersections"]:
        lines.append("  WARNING: the surface intersects itself: %d pair(s) of faces cross" % report["self_intersections"])
    if report["overlaps"]:
        lines.append("  WARNING: %d pair(s) of separate parts overlap (%d pair(s) of faces)"
                     % (len(report["overlapping_parts"]), report["overlaps"]))
    for w in witnesses:
        lines.append("    %s: %s at %s" % (w["kind"], " and ".join(w["faces"]) or "?", _point_text(w["point"])))
    if not witnesses:
        lines.append("  no self-intersection or overlap found")
    App.Console.PrintMessage("\n".join(lines) + "\n")
    if highlight and App.GuiUp:
        features.highlight_edges(obj, [w[0] for w in worst])
    return report


def make_color_map(nurbs, coloring="Curvature", samples=12, doc=None, name="ColorMap"):
    """A ColorMap object of a NURBS object: its patches tessellated with per-vertex colours for
    the mean curvature, the deviation from the exact limit surface, or zebra stripes: the same
    colours as `subd2nurbs convert --preview P.glb --color curvature|deviation|zebra`. The NURBS
    object is hidden in the GUI so the colours show."""
    if not isinstance(getattr(nurbs, "Proxy", None), features.NurbsFeature):
        raise TypeError("make_color_map: expected a NURBS object made by make_nurbs")
    coloring = coloring.capitalize()
    if coloring not in features.COLORINGS:
        raise ValueError("make_color_map: coloring must be one of %s" % ", ".join(features.COLORINGS))
    doc = _document(doc) if doc is not None else nurbs.Document
    with _Transaction(doc, "Subd2Nurbs color map"):
        obj = doc.addObject("App::FeaturePython", name)
        features.ColorMapFeature(obj)
        obj.Nurbs = nurbs
        obj.Coloring = coloring
        obj.Samples = int(samples)
        _show_and_recompute(obj, features.ViewProviderColorMap, "color map", hide=nurbs)
    return obj
