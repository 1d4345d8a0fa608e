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
OUTPUT = ["Solid", "Shell"]

#: The NURBS object's settings: the rows of the converter's settings table that have a FreeCAD
#: property (subd2nurbs.SETTINGS, docs/settings.md). setup() creates a property per row and
#: settings_of() reads them back, so that a row added to the table is a property here without
#: any other edit. A row's property "choices" are (shown, converter's name) pairs, the default
#: first: an enumeration whose words are for people; the converter's rule checks the name (a
#: value outside the table goes to the converter as it is, which refuses it).
SETTING_ROWS = tuple(row for row in subd2nurbs.SETTINGS if row["property"])

_PROPERTY_KIND = {"flag": "App::PropertyBool", "on-off": "App::PropertyBool", "integer": "App::PropertyInteger",
                  "number": "App::PropertyFloat", "size": "App::PropertyFloat", "word": "App::PropertyEnumeration"}


def _property_kind(row):
    return "App::PropertyEnumeration" if row["property"]["choices"] else _PROPERTY_KIND[row["type"]]


def _property_choices(row):
    """An enumeration's choices, the default first; None for other properties."""
    p = row["property"]
    if p["choices"]:
        return [shown for shown, name in p["choices"]]
    if row["type"] == "word":
        return [row["default"]] + [n for n in row["choices"] if n != row["default"]]
    return None


def property_default(row):
    """The value a row's number property starts at: the setting's default in the property's
    unit; None for an enumeration (its first choice) and where the property starts at 0 (0 means
    the default, or the setting has no number default)."""
    p = row["property"]
    if row["default"] is None or _property_choices(row) is not None or p["zero_is_default"]:
        return None
    return row["default"] / p["scale"] if p["scale"] != 1 else row["default"]


def add_setting_properties(obj):
    """One property per row of SETTING_ROWS (those the object has are kept); a new one starts at
    the setting's default (0 where 0 means the default)."""
    for row in SETTING_ROWS:
        p = row["property"]
        if _add(obj, _property_kind(row), p["name"], p["group"], p["tooltip"], choices=_property_choices(row)):
            value = property_default(row)
            if value is not None:
                setattr(obj, p["name"], value)


def settings_of(values):
    """subd2nurbs.convert's keywords for property values given by property name (those missing
    are left to the converter): enumerations mapped onto the converter's names, 0 left out where
    it means the default, numbers scaled (MaxMemoryMiB to bytes). Level is ignored when Tolerance
    is given (the two properties' documented meaning)."""
    kwargs = {}
    for row in SETTING_ROWS:
        p = row["property"]
        if p["name"] not in values:
            continue
        value = values[p["name"]]
        if p["choices"]:
            value = dict(p["choices"]).get(value, value)
        elif _property_kind(row) in ("App::PropertyInteger", "App::PropertyFloat"):
            if p["zero_is_default"] and value == 0:
                continue
            if p["scale"] != 1:
                value = value * p["scale"]
        kwargs[row["name"]] = value
    if "tolerance" in kwargs:
        kwargs.pop("level", None)
    return kwargs


def object_settings(obj):
    """settings_of() the NURBS object's properties."""
    return settings_of({row["property"]["name"]: getattr(obj, row["property"]["name"])
                        for row in SETTING_ROWS if hasattr(obj, row["property"]["name"])})


def _add(obj, kind, name, group, doc, choices=None, read_only=False, hidden=False):
    """Adds the property unless the object has it (a document read back); `choices`: an
    enumeration's values, set only when the property is new (setting them resets the choice).
    True when the property is new."""
    new = name not in obj.PropertiesList
    if new:
        obj.addProperty(kind, name, group, doc)
        if choices is not None:
            setattr(obj, name, choices)
    if read_only or hidden:
        obj.setEditorMode(name, (["ReadOnly"] if read_only else []) + (["Hidden"] if hidden else []))
    return new


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


class FittedCageFeature(CageFeature):
    """Proxy of a FittedCage object: a Cage whose vertices are fitted to a target (a Mesh::Feature,
    or any object with a shape whose vertices are taken as a point cloud) by subd2nurbs.fit (the
    same fit as `subd2nurbs fit`). It is a Cage: a NURBS object converts it like any other, and it
    refits when its source Cage, its target or its fit properties change."""

    TYPE = "Subd2Nurbs::FittedCage"
    SOURCE = ("Source", "Fit", "The Cage whose topology and tags are kept")

    @staticmethod
    def setup(obj):
        CageFeature.setup(obj)
        g = "Fit"
        _add(obj, "App::PropertyLink", "Target", g, "The mesh (or shape) the cage's limit surface is fitted to")
        _add(obj, "App::PropertyFloat", "Smoothing", g,
             "Weight of the thin-plate energy against the data (>= 0; as fit --smoothing)")
        _add(obj, "App::PropertyInteger", "MaxIterations", g, "Closest-point iterations at most (>= 1)")
        _add(obj, "App::PropertyInteger", "Iterations", g, "Iterations the last fit took", read_only=True)
        _add(obj, "App::PropertyString", "Stop", g, "Why the last fit stopped", read_only=True)
        _add(obj, "App::PropertyFloat", "DistanceBefore", g,
             "Two-sided max distance of the source cage's limit to the target (relative to its diagonal)",
             read_only=True)
        _add(obj, "App::PropertyFloat", "DistanceAfter", g,
             "Two-sided max distance of the fitted cage's limit to the target (relative to its diagonal)",
             read_only=True)

    @staticmethod
    def target_arrays(target):
        """(points (n, 3), triangles (m, 3) or None) of a Mesh::Feature or a shape's vertices."""
        if target.isDerivedFrom("Mesh::Feature"):
            points, facets = target.Mesh.Topology
            return (np.array([[p.x, p.y, p.z] for p in points], dtype=np.float64),
                    np.array([list(f) for f in facets], dtype=np.int64) if facets else None)
        shape = getattr(target, "Shape", None)
        if shape is None or not shape.Vertexes:
            raise TypeError("%s is neither a Mesh nor a shape with vertices" % target.Label)
        return np.array([[v.X, v.Y, v.Z] for v in shape.Vertexes], dtype=np.float64), None

    def execute(self, obj):
        if obj.Source is None or obj.Target is None:
            raise ValueError("%s: a Source cage and a Target are needed" % obj.Label)
        source = cage_of(obj.Source)
        points, triangles = self.target_arrays(obj.Target)
        indicator = _FitProgress("Fitting %s to %s" % (obj.Source.Label, obj.Target.Label), obj.MaxIterations)
        try:
            with settings_named_by_property():
                fitted, info = subd2nurbs.fit(source, points, triangles=triangles, smoothing=obj.Smoothing,
                                              max_iterations=obj.MaxIterations, progress=indicator)
        finally:
            indicator.stop()
        CageFeature.store(obj, fitted, getattr(obj.Source, "SourceFile", ""))
        obj.Iterations = int(info["iterations"])
        obj.Stop = str(info["stop"])
        two_sided = lambda d: max(d["limit_to_target"]["max"], d["target_to_limit"]["max"])
        obj.DistanceBefore = float(two_sided(info["before"]))
        obj.DistanceAfter = float(two_sided(info["after"]))
        obj.Placement = App.Placement()  # the fitted coordinates are global (the source's placement applied)
        CageFeature.execute(self, obj)


def is_cage(obj):
    return isinstance(getattr(obj, "Proxy", None), CageFeature)


def cage_of(source, input="auto"):
    """The subd2nurbs.Cage of a Cage object or a Mesh::Feature. A Mesh goes the road of
    subd2nurbs.input_route (docs/meshes.md): a mesh to reproduce stays triangles (its `route`
    says so; convert() remeshes it), a triangulated cage gets its quads back."""
    if is_cage(source):
        return CageFeature.cage(source)
    if hasattr(source, "isDerivedFrom") and source.isDerivedFrom("Mesh::Feature"):
        points, facets = source.Mesh.Topology
        if not facets:
            raise subd2nurbs.CageError("%s: the mesh has no facets" % source.Label, element="faces")
        # Topology's points already carry the feature's placement.
        v = np.array([[p.x, p.y, p.z] for p in points], dtype=np.float64)
        triangles = subd2nurbs.Cage(v, [list(f) for f in facets], name=source.Label)
        route = subd2nurbs.input_route(triangles, input)
        if route["kind"] == "mesh":
            triangles.route = route
            triangles.quad_recovery = None
            return triangles
        cage = subd2nurbs.from_triangles(v, [list(f) for f in facets])
        cage.name = source.Label
        cage.route = route
        return cage
    raise TypeError("%s is neither a subdivision Cage nor a Mesh::Feature" % getattr(source, "Label", source))


def source_and_settings(source, settings):
    """(subd2nurbs.Cage, convert()'s keywords) of a NURBS object's Source and settings: a Mesh
    source takes the road cage_of() decides (settings["input"] is then fixed to it, whatever the
    Mesh's label looks like)."""
    settings = dict(settings)
    cage = cage_of(source, settings.get("input", "auto"))
    if getattr(cage, "route", None) and cage.route["kind"] == "mesh":
        settings["input"] = "mesh"
    return cage, settings


def mesh_note(label, report):
    """A console line about a remeshed Mesh source (report["mesh"]), or ""."""
    mesh = report.get("mesh")
    if not mesh:
        return ""
    after = mesh["fit"]["after"]
    return ("Subd2Nurbs: %s: the mesh (%d triangles, %d feature edges) became a cage of %d quads (%d feature edges "
            "kept); surface to mesh max %.3g, mesh to surface max %.3g of the diagonal\n"
            % (label, mesh["input_triangles"], mesh["features"]["edges"], mesh["cage"]["faces"],
               mesh["cage"]["feature_edges"], after["limit_to_target"]["max"], after["target_to_limit"]["max"]))


class _Progress:
    """FreeCAD's progress indicator (status bar in the GUI, nothing visible headless) driven by
    subd2nurbs's progress callback. In the GUI, Esc cancels: the callback then returns False
    and subd2nurbs.convert raises subd2nurbs.Cancelled."""

    STEPS = 100

    def __init__(self, title):
        self.indicator = App.Base.ProgressIndicator()
        self.indicator.start(title, self.STEPS)
        self.done = 0

    def __call__(self, stage, fraction):
        # A mesh's remesh and fit (each size round from 0 to 1) take most of a mesh's conversion.
        target = {"patches": 55, "deviation": 60, "continuity": 65}.get(stage.key, None)
        if stage.key == "mesh":
            target = 5 + int(45 * fraction)
        elif stage.key == "brep":
            target = 65 + int(35 * fraction)
        try:
            while target is not None and self.done < min(target, self.STEPS):
                self.indicator.next(True)  # raises once the user has pressed cancel
                self.done += 1
        except Exception:
            return False
        if App.GuiUp:
            import FreeCADGui
            FreeCADGui.updateGui()
        return None

    def stop(self):
        self.indicator.stop()


class _FitProgress:
    """FreeCAD's progress indicator for a fit: one step per closest-point iteration (of at most
    `steps`), with a cancel button in the GUI; a cancel stops the fit after its current solve
    (subd2nurbs.fit's progress returns False: stop "cancelled", the last solved cage is kept).
    `cancel_after` (tests) cancels by itself after that many iterations."""

    cancel_after = None

    def __init__(self, title, steps):
        self.indicator = App.Base.ProgressIndicator()
        self.indicator.start(title, max(int(steps), 1))
        self.calls = 0

    def __call__(self, iteration, max_iterations, objective):
        self.calls += 1
        if self.cancel_after is not None and self.calls > self.cancel_after:
            return False
        try:
            self.indicator.next(True)  # raises once the user has pressed cancel
        except Exception:
            return False
        if App.GuiUp:
            import FreeCADGui
            FreeCADGui.updateGui()
        return True

    def stop(self):
        try:
            self.indicator.stop()
        except Exception:
            pass


#: The property of each converter setting (subd2nurbs.SettingsError.setting) on a NURBS object
#: (the settings table), a ColorMap object (its colouring and samples), a Cage object (its
#: subdivision options) or a FittedCage (its fit's): the converter's rules name it so.
PROPERTY_OF_SETTING = dict({row["name"]: row["property"]["name"] for row in SETTING_ROWS},
                           preview="Coloring", preview_samples="Samples", boundary="Boundary",
                           crease_method="CreaseMethod", triangles="TriangleRule", smoothing="Smoothing",
                           max_iterations="MaxIterations")


def convert_cage(cage, settings, progress=True):
    """subd2nurbs.convert of `cage` with `settings` (its keywords, as settings_of() makes them);
    the converter's rules check the values, and a SettingsError names the property
    (PROPERTY_OF_SETTING). progress: True (FreeCAD's progress indicator, Esc cancels), False, or
    a callable as subd2nurbs.convert takes; a cancel raises subd2nurbs.Cancelled."""
    if callable(progress):
        with settings_named_by_property():
            return subd2nurbs.convert(cage, progress=progress, **settings)
    indicator = _Progress("Converting %s to NURBS" % cage.name) if progress else None
    try:
        with settings_named_by_property():
            return subd2nurbs.convert(cage, progress=indicator, **settings)
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
        add_setting_properties(obj)  # Level, Tolerance, PolarHandling, Fit, ... (the settings table)
        g = "Conversion"
        _add(obj, "App::PropertyEnumeration", "OutputType", g, "A solid (closed cages) or a shell", choices=OUTPUT)
        _add(obj, "App::PropertyBool", "ShowProgress", g, "Show a progress indicator while converting")
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
        m = "Mesh"
        _add(obj, "App::PropertyString", "InputRoute", m, "Which road the Source took: mesh (remeshed into a quad cage "
             "fitted to it) or cage, and why", read_only=True)
        _add(obj, "App::PropertyInteger", "CageFaces", m, "A Mesh source remeshed: quads of the cage made from it",
             read_only=True)
        _add(obj, "App::PropertyInteger", "FeatureEdges", m, "A Mesh source remeshed: cage edges kept sharp",
             read_only=True)
        _add(obj, "App::PropertyFloat", "MeshDistance", m, "A Mesh source remeshed: largest two-sided distance "
             "between the surface and the mesh (model units)", read_only=True)

    @staticmethod
    def signature(cage, settings):
        """What a conversion depends on: a result can be reused while this is unchanged."""
        return (cage.vertices.tobytes(), cage.face_sizes.tobytes(), cage.face_indices.tobytes(),
                tuple(cage.creases), tuple(cage.corners), tuple(cage.holes), tuple(sorted(cage.options.items())),
                tuple(sorted(settings.items())))

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
        cage, settings = source_and_settings(obj.Source, object_settings(obj))
        key = self.signature(cage, settings)
        cache = getattr(self, "_cache", None)
        if cache is None or cache[0] != key:
            result = convert_cage(cage, settings, progress=obj.ShowProgress)
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
        route = getattr(cage, "route", None)
        if hasattr(obj, "InputRoute"):  # objects saved before the mesh path have no such properties
            obj.InputRoute = "%s: %s" % (route["kind"], route["reason"]) if route else "cage"
            mesh = r.get("mesh")
            if mesh:
                after = mesh["fit"]["after"]
                obj.CageFaces = mesh["cage"]["faces"]
                obj.FeatureEdges = mesh["cage"]["feature_edges"]
                obj.MeshDistance = max(after["limit_to_target"]["max"], after["target_to_limit"]["max"]) * after["diagonal"]
            else:
                obj.CageFaces, obj.FeatureEdges, obj.MeshDistance = -1, 0, 0.0
        if mesh_note(obj.Label, r):
            App.Console.PrintMessage(mesh_note(obj.Label, r))
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
