"""The workbench's parametric objects: Cage (a subdivision cage, shown as wires) and NURBS (the
B-rep converted from a Cage or a Mesh::Feature), as Part::FeaturePython proxies, plus their
view providers. The conversion is subd2nurbs's (the same code as the command line); the
B-rep reaches FreeCAD as BREP text (Part.Shape.importBrepFromString)."""

import contextlib
import os

import FreeCAD as App
import numpy as np

import subd2nurbs

ICONS = os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "Resources", "icons")


def _default_first(option, default):
    """The converter's names of a cage option (subd2nurbs.CAGE_OPTIONS), the default first (a new
    enumeration property starts at its first choice)."""
    return [default] + [n for n in subd2nurbs.CAGE_OPTIONS[option] if n != default]


#: The Cage object's subdivision options: the converter's names, which its rules check.
BOUNDARY = _default_first("boundary", "edge-and-corner")
CREASE_METHOD = _default_first("crease_method", "uniform")
TRIANGLES = _default_first("triangles", "catmark")
#: The NURBS object's choices (names for people) and the converter's name of each: polar
#: structures as polar caps or Catmull-Clark (subd2nurbs.convert(polar="on"/"off")); the surface
#: the cage stands for, its own limit (which misses its vertices) or the limit of the cage solved
#: to pass through them (fit="interpolate"); faces, each regular region of quads as one B-spline
#: face (the default, as `subd2nurbs convert --faces packed`) or one face per coarse quad. A
#: value outside a table goes to the converter as it is, whose rule refuses it.
CONVERTER_NAMES = {
    "polar": {"Polar caps": "on", "Catmull-Clark": "off"},
    "fit": {"Approximate": "approximate", "Interpolate": "interpolate"},
    "faces": {"Packed": "packed", "PerQuad": "per-quad"},
}
POLAR = list(CONVERTER_NAMES["polar"])
FIT = list(CONVERTER_NAMES["fit"])
FACES = list(CONVERTER_NAMES["faces"])
OUTPUT = ["Solid", "Shell"]


def _add(obj, kind, name, group, doc, choices=None, read_only=False, hidden=False):
    """Adds the property unless the object has it (a document read back); `choices`: an
    enumeration's values, set only when the property is new (setting them resets the choice)."""
    if name not in obj.PropertiesList:
        obj.addProperty(kind, name, group, doc)
        if choices is not None:
            setattr(obj, name, choices)
    if read_only or hidden:
        obj.setEditorMode(name, (["ReadOnly"] if read_only else []) + (["Hidden"] if hidden else []))


def _placement_points(vertices, placement):
    if placement.isIdentity():
        return vertices
    m = placement.toMatrix()
    a = np.array([[m.A11, m.A12, m.A13], [m.A21, m.A22, m.A23], [m.A31, m.A32, m.A33]])
    t = np.array([m.A14, m.A24, m.A34])
    return vertices @ a.T + t


class _Stateless:
    """Proxies keep nothing in the saved document: everything is in properties.
    FreeCAD 0.20 pickles proxies with __getstate__ / __setstate__, 0.21+ with dumps / loads;
    both restore through restored_state()."""

    def restored_state(self):
        pass

    def __getstate__(self):
        return None

    def __setstate__(self, state):
        self.restored_state()
        return None

    def dumps(self):
        return None

    def loads(self, state):
        self.restored_state()
        return None


class _Feature(_Stateless):
    """A document object's proxy: setup() adds its properties, again when a document is read
    back (properties added since it was saved); restored_state() resets what it keeps."""

    #: (property, group, tooltip) of the link to the object this one is made from, the first
    #: property in the editor; None: no such link.
    SOURCE = None

    def __init__(self, obj):
        self.onDocumentRestored(obj)

    def onDocumentRestored(self, obj):
        obj.Proxy = self
        self.restored_state()
        if self.SOURCE:
            name, group, doc = self.SOURCE
            _add(obj, "App::PropertyLink", name, group, doc)
        self.setup(obj)

    @staticmethod
    def setup(obj):
        """Adds the object's other properties (those it has are kept)."""
        raise NotImplementedError


class CageFeature(_Feature):
    """Proxy of a Cage object: the cage's arrays as properties (coordinates in double
    precision), its shape the cage's edges."""

    TYPE = "Subd2Nurbs::Cage"

    @staticmethod
    def setup(obj):
        g = "Cage"
        _add(obj, "App::PropertyFloatList", "Coordinates", g, "Vertex coordinates x0 y0 z0 x1 ...", hidden=True)
        _add(obj, "App::PropertyIntegerList", "FaceSizes", g, "Vertices per face", hidden=True)
        _add(obj, "App::PropertyIntegerList", "FaceIndices", g, "Vertex indices of the faces, face after face",
             hidden=True)
        _add(obj, "App::PropertyIntegerList", "CreaseVertices", g, "Crease edges as vertex pairs", hidden=True)
        _add(obj, "App::PropertyFloatList", "CreaseSharpness", g, "Sharpness per crease edge (10 = infinite)",
             hidden=True)
        _add(obj, "App::PropertyIntegerList", "CornerVertices", g, "Corner vertices", hidden=True)
        _add(obj, "App::PropertyFloatList", "CornerSharpness", g, "Sharpness per corner vertex", hidden=True)
        _add(obj, "App::PropertyIntegerList", "Holes", g, "Faces that produce no surface", hidden=True)
        _add(obj, "App::PropertyInteger", "NumVertices", g, "Vertices of the cage", read_only=True)
        _add(obj, "App::PropertyInteger", "NumFaces", g, "Faces of the cage", read_only=True)
        _add(obj, "App::PropertyInteger", "NumCreases", g, "Tagged crease edges", read_only=True)
        _add(obj, "App::PropertyString", "SourceFile", g, "The file the cage was read from", read_only=True)
        _add(obj, "App::PropertyInteger", "RecoveredQuads", g,
             "Quads recovered from triangle pairs (glTF sources), -1 if not a triangle source", read_only=True)
        s = "Subdivision"
        _add(obj, "App::PropertyEnumeration", "Boundary", s, "Boundary interpolation", choices=BOUNDARY)
        _add(obj, "App::PropertyEnumeration", "CreaseMethod", s, "Semi-sharp crease decay", choices=CREASE_METHOD)
        _add(obj, "App::PropertyEnumeration", "TriangleRule", s, "Edge rule next to triangles", choices=TRIANGLES)

    @staticmethod
    def store(obj, cage, path=""):
        obj.Coordinates = [float(x) for x in cage.vertices.reshape(-1)]
        obj.FaceSizes = [int(x) for x in cage.face_sizes]
        obj.FaceIndices = [int(x) for x in cage.face_indices]
        obj.CreaseVertices = [int(v) for a, b, s in cage.creases for v in (a, b)]
        obj.CreaseSharpness = [float(s) for a, b, s in cage.creases]
        obj.CornerVertices = [int(v) for v, s in cage.corners]
        obj.CornerSharpness = [float(s) for v, s in cage.corners]
        obj.Holes = [int(h) for h in cage.holes]
        obj.Boundary = cage.options["boundary"]
        obj.CreaseMethod = cage.options["crease_method"]
        obj.TriangleRule = cage.options["triangles"]
        obj.NumVertices = cage.num_vertices
        obj.NumFaces = cage.num_faces
        obj.NumCreases = len(cage.creases)
        obj.SourceFile = path
        obj.RecoveredQuads = cage.quad_recovery["quads"] if cage.quad_recovery else -1

    @staticmethod
    def cage(obj, placed=True):
        """The subd2nurbs.Cage of a Cage object (in global coordinates when placed)."""
        v = np.array(obj.Coordinates, dtype=np.float64).reshape(-1, 3)
        if placed:
            v = _placement_points(v, obj.Placement)
        sizes = list(obj.FaceSizes)
        idx = list(obj.FaceIndices)
        faces, o = [], 0
        for n in sizes:
            faces.append(idx[o:o + n])
            o += n
        cv = list(obj.CreaseVertices)
        creases = [(cv[2 * i], cv[2 * i + 1], s) for i, s in enumerate(obj.CreaseSharpness)]
        corners = list(zip(obj.CornerVertices, obj.CornerSharpness))
        with settings_named_by_property():  # the converter's rules of the options
            return subd2nurbs.Cage(v, faces, creases, corners, list(obj.Holes), obj.Boundary, obj.CreaseMethod,
                                   obj.TriangleRule, name=obj.Label)

    def execute(self, obj):
        import Part
        cage = self.cage(obj, placed=False)
        edges, seen = [], set()
        for face in cage.faces:
            for a, b in zip(face, face[1:] + face[:1]):
                key = (min(a, b), max(a, b))
                if key in seen:
                    continue
                seen.add(key)
                pa, pb = (App.Vector(*cage.vertices[k]) for k in key)
                edges.append(Part.LineSegment(pa, pb).toShape())
        placement = obj.Placement
        obj.Shape = Part.Compound(edges)
        obj.Placement = placement


def is_cage(obj):
    return isinstance(getattr(obj, "Proxy", None), CageFeature)


def cage_of(source):
    """The subd2nurbs.Cage of a Cage object or a Mesh::Feature (quads recovered)."""
    if is_cage(source):
        return CageFeature.cage(source)
    if hasattr(source, "isDerivedFrom") and source.isDerivedFrom("Mesh::Feature"):
        points, facets = source.Mesh.Topology
        if not facets:
            raise subd2nurbs.CageError("%s: the mesh has no facets" % source.Label, element="faces")
        # Topology's points already carry the feature's placement.
        v = np.array([[p.x, p.y, p.z] for p in points], dtype=np.float64)
        cage = subd2nurbs.from_triangles(v, [list(f) for f in facets])
        cage.name = source.Label
        return cage
    raise TypeError("%s is neither a subdivision Cage nor a Mesh::Feature" % getattr(source, "Label", source))


class _Progress:
    """FreeCAD's progress indicator (status bar in the GUI, nothing visible headless) driven by
    subd2nurbs's progress callback."""

    STEPS = 100

    def __init__(self, title):
        self.indicator = App.Base.ProgressIndicator()
        self.indicator.start(title, self.STEPS)
        self.done = 0

    def __call__(self, stage, fraction):
        target = {"patches": 10, "deviation": 20, "continuity": 30}.get(stage.key, None)
        if stage.key == "brep":
            target = 30 + int(70 * fraction)
        if target is not None:
            while self.done < min(target, self.STEPS):
                self.indicator.next()
                self.done += 1
        if App.GuiUp:
            import FreeCADGui
            FreeCADGui.updateGui()

    def stop(self):
        self.indicator.stop()


#: The property of each converter setting (subd2nurbs.SettingsError.setting) on a NURBS or
#: ColorMap object: the converter's rules name it so.
PROPERTY_OF_SETTING = {"level": "Level", "tolerance": "Tolerance", "polar": "PolarHandling", "fit": "Fit",
                       "fair": "FairWeight", "faces": "Faces", "max_faces": "MaxFaces", "max_memory": "MaxMemoryMiB",
                       "preview": "Coloring", "preview_samples": "Samples", "boundary": "Boundary",
                       "crease_method": "CreaseMethod", "triangles": "TriangleRule"}


def convert_cage(cage, level, tolerance, polar, progress=True, fit="Approximate", fair_weight=0.0, faces="Packed",
                 **options):
    """subd2nurbs.convert with the NURBS object's settings (and further convert options).
    fit: "Approximate" or "Interpolate"; fair_weight != 0 (> 0, with "Interpolate"): a fair fit;
    faces: "Packed" or "PerQuad" (CONVERTER_NAMES). The converter's rules check the values; a
    SettingsError names the property (PROPERTY_OF_SETTING)."""
    if polar == "Polar caps" and not getattr(subd2nurbs, "HAS_POLAR", False):
        raise subd2nurbs.SettingsError("polar caps are not available in this subd2nurbs build: use Catmull-Clark")
    # Tolerance > 0 chooses the levels; else a nonzero Level pins them (a negative one is
    # refused by the converter); else (both 0) the default tolerance, as the command line and
    # the Python module do.
    if tolerance and tolerance > 0:
        kwargs = {"tolerance": tolerance}
    elif level:
        kwargs = {"level": int(level)}
    else:
        kwargs = {}
    for setting, value in (("polar", polar), ("fit", fit), ("faces", faces)):
        kwargs[setting] = CONVERTER_NAMES[setting].get(value, value)
    if fair_weight:
        kwargs["fair"] = float(fair_weight)
    kwargs.update(options)
    indicator = _Progress("Converting %s to NURBS" % cage.name) if progress else None
    try:
        with settings_named_by_property():
            return subd2nurbs.convert(cage, progress=indicator, **kwargs)
    finally:
        if indicator:
            indicator.stop()


@contextlib.contextmanager
def settings_named_by_property():
    """A context in which a subd2nurbs.SettingsError about a setting a NURBS or ColorMap object
    has a property for is raised again naming the property (PROPERTY_OF_SETTING), with the
    converter's rule text."""
    try:
        yield
    except subd2nurbs.SettingsError as e:
        if e.setting not in PROPERTY_OF_SETTING:
            raise
        raise subd2nurbs.SettingsError("%s %s" % (PROPERTY_OF_SETTING[e.setting], e.rule), setting=e.setting,
                                       rule=e.rule) from None


class NurbsFeature(_Feature):
    """Proxy of a NURBS object: converts its Source (Cage or Mesh::Feature) on recompute."""

    TYPE = "Subd2Nurbs::NURBS"
    SOURCE = ("Source", "Conversion", "The Cage or Mesh::Feature to convert")

    @staticmethod
    def setup(obj):
        g = "Conversion"
        _add(obj, "App::PropertyInteger", "Level", g,
             "If > 0: extra refinement levels at every irregular vertex (0 with Tolerance 0: the "
             "default tolerance, 1e-4 of the model size)")
        _add(obj, "App::PropertyFloat", "Tolerance", g,
             "If > 0: the deviation from the limit surface to reach (relative to the model size); "
             "each irregular vertex gets the levels it needs, and Level is ignored")
        _add(obj, "App::PropertyEnumeration", "PolarHandling", g,
             "Polar structures (triangle fans around a pole): one singular polar cap each, or "
             "Catmull-Clark patches like every other vertex", choices=POLAR)
        _add(obj, "App::PropertyEnumeration", "OutputType", g, "A solid (closed cages) or a shell", choices=OUTPUT)
        _add(obj, "App::PropertyEnumeration", "Fit", g,
             "Approximate: the cage's own limit surface (it misses the cage's vertices); Interpolate: "
             "the surface passes through every cage vertex (the cage is solved for first)", choices=FIT)
        _add(obj, "App::PropertyFloat", "FairWeight", g,
             "With Fit = Interpolate: if > 0, trade exact interpolation for fairness (least squares with "
             "the thin-plate energy weighted this much); 0: exact")
        _add(obj, "App::PropertyEnumeration", "Faces", g,
             "Packed: each regular region of quads is one B-spline face (fewer, larger faces); "
             "PerQuad: one face per coarse quad", choices=FACES)
        _add(obj, "App::PropertyBool", "ShowProgress", g, "Show a progress indicator while converting")
        lim = "Limits"
        _add(obj, "App::PropertyFloat", "MaxFaces", lim,
             "Refuse a conversion estimated to make more polynomial pieces (> 0; 0: the default, 4e6; "
             "as --max-faces)")
        _add(obj, "App::PropertyFloat", "MaxMemoryMiB", lim,
             "Refuse a conversion estimated to need more memory, in MiB (> 0; 0: the default, 3/4 of "
             "the memory available; as --max-memory)")
        r = "Result"
        _add(obj, "App::PropertyInteger", "Patches", r, "NURBS patches (= faces)", read_only=True)
        _add(obj, "App::PropertyInteger", "RecoveredQuads", r,
             "Quads recovered from triangle pairs of a Mesh source (-1 for a Cage)", read_only=True)
        _add(obj, "App::PropertyInteger", "KeptTriangles", r,
             "Triangles of a Mesh source kept as triangles (fans around poles, unpaired)", read_only=True)
        _add(obj, "App::PropertyFloat", "MaxGap", r, "Largest gap between patches (model units)", read_only=True)
        _add(obj, "App::PropertyFloat", "MaxNormalAngle", r, "Largest normal jump across smooth edges (degrees)",
             read_only=True)
        _add(obj, "App::PropertyFloat", "MaxDeviation", r, "Largest deviation from the limit surface",
             read_only=True)
        _add(obj, "App::PropertyFloat", "MaxResidual", r,
             "Fit = Interpolate: largest distance from a cage vertex to the surface's point for it", read_only=True)
        _add(obj, "App::PropertyFloat", "MaxCageMove", r,
             "Fit = Interpolate: largest move of a cage vertex by the fit (model units)", read_only=True)
        _add(obj, "App::PropertyStringList", "Warnings", r, "Conversion warnings", read_only=True)

    @staticmethod
    def signature(cage, level, tolerance, polar, fit="Approximate", fair_weight=0.0, faces="Packed", limits=None):
        """What a conversion depends on: a result can be reused while this is unchanged."""
        return (cage.vertices.tobytes(), cage.face_sizes.tobytes(), cage.face_indices.tobytes(),
                tuple(cage.creases), tuple(cage.corners), tuple(cage.holes), tuple(sorted(cage.options.items())),
                int(level), float(tolerance), polar, fit, float(fair_weight), faces,
                tuple(sorted((limits or {}).items())))

    @staticmethod
    def fit_settings(obj):
        """(Fit, FairWeight) of a NURBS object (documents saved before they existed: Approximate)."""
        return getattr(obj, "Fit", "Approximate"), float(getattr(obj, "FairWeight", 0.0))

    @staticmethod
    def faces_setting(obj):
        """Faces of a NURBS object (documents saved before the property existed: Packed)."""
        return getattr(obj, "Faces", "Packed")

    @staticmethod
    def limits(obj):
        """convert's max_faces / max_memory of a NURBS object's MaxFaces / MaxMemoryMiB (0: the default)."""
        limits = {}
        if getattr(obj, "MaxFaces", 0) != 0:
            limits["max_faces"] = obj.MaxFaces
        if getattr(obj, "MaxMemoryMiB", 0) != 0:
            limits["max_memory"] = obj.MaxMemoryMiB * 1024.0 * 1024.0
        return limits

    def prepare(self, signature, result):
        """A result computed before the object existed (make_nurbs), used by the first recompute."""
        self._cache = (signature, result)

    def conversion(self, obj):
        """(cage, subd2nurbs.ConversionResult) of the object's Source and settings as they are now.
        The last result is kept, keyed by everything it depends on (signature()), and reused while
        that is unchanged: the solid, check_quality and the colour maps share one conversion. A
        failed conversion raises and keeps the last result (which no longer matches)."""
        if obj.Source is None:
            raise ValueError("%s: no Source" % obj.Label)
        cage = cage_of(obj.Source)
        fit, fair_weight = self.fit_settings(obj)
        faces = self.faces_setting(obj)
        limits = self.limits(obj)
        key = self.signature(cage, obj.Level, obj.Tolerance, obj.PolarHandling, fit, fair_weight, faces, limits)
        cache = getattr(self, "_cache", None)
        if cache is None or cache[0] != key:
            result = convert_cage(cage, obj.Level, obj.Tolerance, obj.PolarHandling, progress=obj.ShowProgress,
                                  fit=fit, fair_weight=fair_weight, faces=faces, **limits)
            cache = self._cache = (key, result)
        return cage, cache[1]

    def execute(self, obj):
        import Part
        # Nothing is assigned before the conversion and the shape succeed: a failure leaves the
        # last valid shape and results, and FreeCAD marks the object with the error's message.
        cage, result = self.conversion(obj)
        shape = Part.Shape()
        shape.importBrepFromString(result.brep_text)
        if obj.OutputType == "Shell" and shape.Solids:
            shells = shape.Shells
            shape = shells[0] if len(shells) == 1 else Part.Compound(shells)
        placement = obj.Placement
        obj.Shape = shape
        obj.Placement = placement
        q = cage.quad_recovery
        obj.RecoveredQuads = q["quads"] if q else -1
        obj.KeptTriangles = q["triangles_kept"] if q else 0
        obj.Patches = result.num_patches
        r = result.report
        obj.MaxGap = r["continuity"]["max_gap"] or 0.0
        obj.MaxNormalAngle = r["continuity"]["max_normal_angle_deg"] or 0.0
        obj.MaxDeviation = r["deviation"]["max"] or 0.0
        f = r.get("fit") or {}
        obj.MaxResidual = (f.get("residual") or {}).get("max") or 0.0
        obj.MaxCageMove = (f.get("displacement") or {}).get("max") or 0.0
        obj.Warnings = [str(w) for w in result.warnings]
        if q:
            App.Console.PrintMessage("Subd2Nurbs: %s: %d quads recovered from %d triangles, %d triangles kept "
                                     "(%d fan vertices)\n" % (obj.Label, q["quads"], q["source_triangles"],
                                                              q["triangles_kept"], q["fan_vertices"]))
        for w in result.warnings:
            App.Console.PrintWarning("Subd2Nurbs: %s: %s\n" % (obj.Label, w))

    def result(self, obj):
        """The subd2nurbs.ConversionResult of the object as it is now (the kept one while its
        inputs are unchanged; converted again after a reload or a change)."""
        return self.conversion(obj)[1]

    def restored_state(self):
        self._cache = None


COLORINGS = ["Curvature", "Deviation", "Zebra"]


class ColorMapFeature(_Feature):
    """Proxy of a ColorMap object: the NURBS object's patches tessellated with per-vertex
    colours, exactly as `subd2nurbs convert --preview P.glb --color ...` makes them (mean
    curvature, deviation from the exact limit surface, or zebra stripes), from the NURBS
    object's last conversion (NurbsFeature.conversion)."""

    TYPE = "Subd2Nurbs::ColorMap"
    SOURCE = ("Nurbs", "Color map", "The NURBS object to colour")

    def __init__(self, obj):
        super().__init__(obj)
        obj.Samples = 12

    @staticmethod
    def setup(obj):
        g = "Color map"
        _add(obj, "App::PropertyEnumeration", "Coloring", g,
             "Mean curvature (blue negative, red positive), deviation from the exact limit surface "
             "(blue 0 .. red max) or zebra stripes of the normal", choices=COLORINGS)
        _add(obj, "App::PropertyInteger", "Samples", g, "Grid points per patch side (2 .. 64)")
        r = "Result"
        _add(obj, "App::PropertyVectorList", "Points", r, "Tessellation vertices", read_only=True, hidden=True)
        _add(obj, "App::PropertyIntegerList", "Triangles", r, "Vertex indices, three per triangle",
             read_only=True, hidden=True)
        _add(obj, "App::PropertyColorList", "Colors", r, "One colour per vertex", read_only=True, hidden=True)
        _add(obj, "App::PropertyFloat", "ValueMin", r, "Value at the low end of the colour scale", read_only=True)
        _add(obj, "App::PropertyFloat", "ValueMax", r, "Value at the high end of the colour scale", read_only=True)

    def execute(self, obj):
        nurbs = obj.Nurbs
        if nurbs is None or not isinstance(getattr(nurbs, "Proxy", None), NurbsFeature):
            raise ValueError("%s: Nurbs must be a NURBS object made by the workbench" % obj.Label)
        # The NURBS object's own conversion (kept by its proxy), coloured: no second conversion.
        result = nurbs.Proxy.result(nurbs)
        with settings_named_by_property():
            p = result.make_preview(obj.Coloring.lower(), obj.Samples)
        obj.Points = [App.Vector(*map(float, q)) for q in p["positions"]]
        obj.Triangles = [int(i) for i in p["triangles"].reshape(-1)]
        obj.Colors = [tuple(float(c) for c in q) for q in p["colors"]]
        obj.ValueMin = float(p["value_min"])
        obj.ValueMax = float(p["value_max"])


def highlight_edges(obj, names, color=(1.0, 0.0, 0.0)):
    """Draws the named edges ("EdgeN") of obj in `color`, thicker, and selects them."""
    import FreeCADGui as Gui
    vobj = obj.ViewObject
    base = tuple(vobj.LineColor[:3])
    indices = {int(n[4:]) - 1 for n in names}
    vobj.LineColorArray = [color if i in indices else base for i in range(len(obj.Shape.Edges))]
    vobj.LineWidth = max(vobj.LineWidth, 3.0)
    Gui.Selection.clearSelection()
    for n in names:
        Gui.Selection.addSelection(obj.Document.Name, obj.Name, n)


class _ViewProvider(_Stateless):
    ICON = "Subd2Nurbs.svg"

    def __init__(self, vobj):
        vobj.Proxy = self

    def attach(self, vobj):
        self.Object = vobj.Object

    def getIcon(self):
        return os.path.join(ICONS, self.ICON)



class ViewProviderCage(_ViewProvider):
    ICON = "Subd2Nurbs_Cage.svg"

    def __init__(self, vobj):
        super().__init__(vobj)
        vobj.LineColor = (0.2, 0.4, 0.9)
        vobj.PointColor = (0.2, 0.4, 0.9)
        vobj.PointSize = 4.0


class ViewProviderNurbs(_ViewProvider):
    ICON = "Subd2Nurbs_Convert.svg"

    def claimChildren(self):
        source = getattr(self, "Object", None) and self.Object.Source
        return [source] if source is not None else []


class ViewProviderColorMap(_ViewProvider):
    """Draws the colour map with Coin: vertices, per-vertex colours, triangles."""

    ICON = "Subd2Nurbs_Check.svg"

    def attach(self, vobj):
        super().attach(vobj)
        from pivy import coin
        self.coords = coin.SoCoordinate3()
        self.material = coin.SoMaterial()
        binding = coin.SoMaterialBinding()
        binding.value = coin.SoMaterialBinding.PER_VERTEX_INDEXED
        hints = coin.SoShapeHints()
        hints.vertexOrdering = coin.SoShapeHints.COUNTERCLOCKWISE
        self.faces = coin.SoIndexedFaceSet()
        root = coin.SoSeparator()
        for node in (hints, self.coords, self.material, binding, self.faces):
            root.addChild(node)
        vobj.addDisplayMode(root, "Colors")
        self.updateData(vobj.Object, "Colors")

    def getDisplayModes(self, vobj):
        return ["Colors"]

    def getDefaultDisplayMode(self):
        return "Colors"

    def setDisplayMode(self, mode):
        return mode

    def updateData(self, obj, prop):
        if prop not in ("Points", "Triangles", "Colors") or not hasattr(self, "faces"):
            return
        points = [(p.x, p.y, p.z) for p in obj.Points]
        colors = [tuple(c[:3]) for c in obj.Colors]
        if not points or len(colors) != len(points):
            return
        self.coords.point.setValues(0, len(points), points)
        self.coords.point.setNum(len(points))
        self.material.diffuseColor.setValues(0, len(colors), colors)
        self.material.diffuseColor.setNum(len(colors))
        index = []
        t = list(obj.Triangles)
        for k in range(0, len(t) - 2, 3):
            index += [t[k], t[k + 1], t[k + 2], -1]
        self.faces.coordIndex.setValues(0, len(index), index)
        self.faces.coordIndex.setNum(len(index))
        self.faces.materialIndex.setValues(0, len(index), index)
        self.faces.materialIndex.setNum(len(index))
