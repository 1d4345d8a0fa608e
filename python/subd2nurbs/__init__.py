"""subd2nurbs: Catmull-Clark subdivision cages to bicubic NURBS patches and OCCT B-reps.

The same code as the ``subd2nurbs`` command line, from Python::

    import subd2nurbs
    cage = subd2nurbs.read_cage("part.obj")           # OBJ with OpenSubdiv 't' tags, or .glb
    cage = subd2nurbs.Cage(vertices, faces,            # or from arrays / lists
                           creases=[(0, 1, 10.0)], corners=[(3, 10.0)])
    subd2nurbs.info(cage)                              # counts, as `subd2nurbs info --json`
    fine = subd2nurbs.refine(cage, 2)                  # uniform Catmull-Clark refinement
    result = subd2nurbs.convert(cage, level=0)         # or tolerance=1e-3 [, absolute=True]
    result.patches[0]["poles"]                         # numpy (nu, nv, 3)
    result.brep_text                                   # OCCT BREP text of the checked B-rep
    result.report                                      # the quality report as a dict
    through = subd2nurbs.convert(cage, fit="interpolate")  # the limit passes through the vertices
    smooth, info = subd2nurbs.fair(cage, weight=0.1, keep="boundary")  # a faired cage
    fitted, info = subd2nurbs.fit(cage, "scan.ply")    # the limit surface fitted to a shape

Arguments' types are checked here, in Python, before the compiled part (``_subd2nurbs``) sees
them; the rules of the settings' values (ranges, what excludes what) are the converter's own, the
same as the command line's and the FreeCAD workbench's. Errors are :class:`CageError` /
:class:`SettingsError` (both ``ValueError``) and :class:`ConversionError` (a ``RuntimeError``),
naming the element or the setting at fault.
"""

import json
import math
import numbers

import numpy as np

from .errors import Cancelled, CageError, ConversionError, FitError, SettingsError, Subd2NurbsError, WriteError
from . import _subd2nurbs

#: The deviation tolerance (relative to the bounding-box diagonal) convert() uses when neither a
#: level nor a tolerance is given; the command line's default too.
DEFAULT_TOLERANCE = 1e-4

__version__ = _subd2nurbs.__version__
#: The OpenCASCADE version the module is linked with (FreeCAD must use the same one to read
#: our BREP text: see occt_compatible).
OCC_VERSION = _subd2nurbs.OCC_VERSION

__all__ = [
    "Cage", "ConversionResult", "read_cage", "read_mesh", "input_route", "read_obj", "from_triangles", "info", "refine", "convert", "fair", "fit",
    "brep_summary", "file_summary",
    "occt_compatible", "CAGE_OPTIONS", "CageError", "SettingsError", "ConversionError", "WriteError", "FitError",
    "Cancelled", "Subd2NurbsError", "OCC_VERSION", "INFINITE_SHARPNESS", "SETTINGS",
]

#: Sharpness at or above this is infinitely sharp (OpenSubdiv's convention).
INFINITE_SHARPNESS = 10.0

#: The names each cage option accepts (the converter's, in the order its rule lists them): keys
#: "boundary", "crease_method", "triangles".
CAGE_OPTIONS = {option: tuple(_subd2nurbs.setting_names(option))
                for option in ("boundary", "crease_method", "triangles")}


def _is_int(x):
    return isinstance(x, numbers.Integral) and not isinstance(x, bool)


def _is_number(x):
    return isinstance(x, numbers.Real) and not isinstance(x, bool)


def _type_error(setting, kind, value):
    return SettingsError("%s must be %s, not %r" % (setting, kind, value), setting=setting, rule="must be " + kind)


def _checked(setting, value, check, kind, convert):
    """`value` converted when `check` accepts its type; else SettingsError."""
    if not check(value):
        raise _type_error(setting, kind, value)
    return convert(value)


def _optional(setting, value, check, kind, convert):
    """None, or _checked(...)."""
    return None if value is None else _checked(setting, value, check, kind, convert)


def _sharpness(value, element, index):
    what = "%s %d" % (element, index)
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        raise CageError("%s: sharpness must be a number, not %r" % (what, value), element=element, index=index)
    value = float(value)
    if not math.isfinite(value) or value < 0:
        raise CageError("%s: sharpness must be finite and >= 0, not %r" % (what, value),
                        element=element, index=index, code="invalid-tag")
    return value


class Cage:
    """A subdivision cage: vertices, faces (any polygon sizes), tags.

    vertices: array-like of shape (n, 3), finite numbers.
    faces: a list of faces, each a sequence of >= 3 vertex indices (0-based, counter-clockwise
        seen from outside); or a 2D integer array (all faces the same size).
    creases: (a, b, sharpness) per tagged edge; sharpness >= 10 is infinitely sharp.
    corners: (vertex, sharpness) per tagged vertex.
    holes: faces that produce no surface.
    boundary: "edge-and-corner" (default), "edge-only" or "none".
    crease_method: "uniform" (default) or "chaikin"; triangles: "catmark" (default) or "smooth".
        Any other name raises SettingsError with the converter's rule ("boundary must be none,
        edge-only or edge-and-corner"), as every front end words it (CAGE_OPTIONS lists the names).

    Raises CageError naming the element ("face 12: vertex index 99 out of range ...").
    Topology (manifold edges and vertices, orientation) is checked by the core when the cage
    is used; call validate() to check it now.
    """

    def __init__(self, vertices, faces, creases=(), corners=(), holes=(),
                 boundary="edge-and-corner", crease_method="uniform", triangles="catmark",
                 name="cage", warnings=None):
        try:
            v = np.array(vertices, dtype=np.float64, copy=True)
        except (TypeError, ValueError) as e:
            raise CageError("vertices: not an array of numbers (%s)" % e, element="vertices") from None
        if v.ndim != 2 or v.shape[1] != 3:
            raise CageError("vertices: expected shape (n, 3), got %s" % (v.shape,), element="vertices")
        if v.shape[0] == 0:
            raise CageError("vertices: the cage has no vertices", element="vertices", code="empty-mesh")
        bad = np.argwhere(~np.isfinite(v))
        if bad.size:
            i = int(bad[0][0])
            raise CageError("vertex %d: coordinate is not finite (%s)" % (i, v[i].tolist()),
                            element="vertex", index=i, code="non-finite-coordinate")
        n = v.shape[0]

        if isinstance(faces, np.ndarray):
            if faces.ndim != 2:
                raise CageError("faces: a face array must be 2D (faces x corners), got %d dimensions"
                                % faces.ndim, element="faces")
            if not np.issubdtype(faces.dtype, np.integer):
                raise CageError("faces: face indices must be integers, got %s" % faces.dtype, element="faces")
            faces = faces.tolist()
        try:
            faces = list(faces)
        except TypeError:
            raise CageError("faces: expected a list of faces", element="faces") from None
        if not faces:
            raise CageError("faces: the cage has no faces", element="faces", code="empty-mesh")
        sizes, indices = [], []
        for f, face in enumerate(faces):
            try:
                face = list(face)
            except TypeError:
                raise CageError("face %d: expected a sequence of vertex indices, got %r" % (f, face),
                                element="face", index=f) from None
            if len(face) < 3:
                raise CageError("face %d: has %d vertices, at least 3 are needed" % (f, len(face)),
                                element="face", index=f, code="face-too-small")
            for k in face:
                if not _is_int(k):
                    raise CageError("face %d: vertex index %r is not an integer" % (f, k),
                                    element="face", index=f)
                if k < 0 or k >= n:
                    raise CageError("face %d: vertex index %d out of range (the cage has %d vertices)"
                                    % (f, k, n), element="face", index=f, code="index-out-of-range")
            if len(set(face)) != len(face):
                raise CageError("face %d: a vertex appears twice (%s)" % (f, face),
                                element="face", index=f, code="repeated-vertex-in-face")
            sizes.append(len(face))
            indices.extend(int(k) for k in face)

        crease_list = []
        for i, c in enumerate(creases):
            try:
                a, b, s = c
            except (TypeError, ValueError):
                raise CageError("crease %d: expected (vertex, vertex, sharpness), got %r" % (i, c),
                                element="crease", index=i) from None
            for x in (a, b):
                if not _is_int(x) or x < 0 or x >= n:
                    raise CageError("crease %d: vertex index %r out of range (the cage has %d vertices)"
                                    % (i, x, n), element="crease", index=i, code="invalid-tag")
            crease_list.append((int(a), int(b), _sharpness(s, "crease", i)))
        corner_list = []
        for i, c in enumerate(corners):
            try:
                a, s = c
            except (TypeError, ValueError):
                raise CageError("corner %d: expected (vertex, sharpness), got %r" % (i, c),
                                element="corner", index=i) from None
            if not _is_int(a) or a < 0 or a >= n:
                raise CageError("corner %d: vertex index %r out of range (the cage has %d vertices)"
                                % (i, a, n), element="corner", index=i, code="invalid-tag")
            corner_list.append((int(a), _sharpness(s, "corner", i)))
        hole_list = []
        for i, h in enumerate(holes):
            if not _is_int(h) or h < 0 or h >= len(sizes):
                raise CageError("hole %d: face index %r out of range (the cage has %d faces)"
                                % (i, h, len(sizes)), element="hole", index=i, code="invalid-tag")
            hole_list.append(int(h))
        options = {"boundary": boundary, "crease_method": crease_method, "triangles": triangles}
        for setting, value in options.items():
            _checked(setting, value, lambda x: isinstance(x, str), "a string", str)
        _subd2nurbs.check_options(options)  # the converter's rules

        self.vertices = v
        self.face_sizes = np.array(sizes, dtype=np.int32)
        self.face_indices = np.array(indices, dtype=np.int32)
        self.creases = crease_list
        self.corners = corner_list
        self.holes = hole_list
        self.options = options
        self.name = name
        #: Warnings from reading the file (None for a cage built from arrays: validation
        #: warnings then come from validate() and convert()).
        self.warnings = None if warnings is None else list(warnings)
        #: For a cage rebuilt from triangles (glTF, from_triangles): the counts, else None.
        self.quad_recovery = None
        self.usd = None  # what the USD reader read (read_cage of a USD file), else None

    @classmethod
    def _from_dict(cls, d, name):
        sizes = d["face_sizes"]
        offsets = np.concatenate([[0], np.cumsum(sizes)])
        idx = d["face_indices"]
        faces = [idx[offsets[f]:offsets[f + 1]].tolist() for f in range(len(sizes))]
        o = d["options"]
        return cls(d["vertices"], faces, d["creases"], d["corners"], d["holes"], o["boundary"],
                   o["crease_method"], o["triangles"], name=name, warnings=d.get("warnings"))

    # Arguments of the compiled functions.
    def _args(self):
        return (self.vertices, self.face_sizes, self.face_indices, self.creases, self.corners,
                self.holes, self.options)

    @property
    def faces(self):
        """The faces as a list of lists of vertex indices."""
        offsets = np.concatenate([[0], np.cumsum(self.face_sizes)])
        return [self.face_indices[offsets[f]:offsets[f + 1]].tolist() for f in range(len(self.face_sizes))]

    @property
    def num_vertices(self):
        return int(self.vertices.shape[0])

    @property
    def num_faces(self):
        return int(self.face_sizes.shape[0])

    def validate(self):
        """Checks the topology and tags (manifold, oriented, tags naming existing edges);
        returns the warnings (e.g. unused vertices). Raises CageError."""
        return _subd2nurbs.validate(*self._args())

    def __repr__(self):
        return "<subd2nurbs.Cage %r: %d vertices, %d faces>" % (self.name, self.num_vertices, self.num_faces)


def read_cage(path, variant=None, input="auto"):
    """Reads and validates a cage: OBJ with OpenSubdiv 't' tags (crease, corner, hole,
    interpolateboundary, ...; see docs/formats.md), errors naming the file and line; USD
    (.usd / .usda / .usdc / .usdz: Mesh prims with their creases, corners and holes; the cage's
    ``usd`` says what was read); or glTF / GLB triangles, whose quads are recovered (the cage's
    ``quad_recovery`` says how many); or STL / PLY / OFF.

    ``variant``: USD variant selections, as {"set": "name"} or "set=name" or a list of those
    (default: the file's selection, else each set's first variant).

    A mesh to reproduce (docs/meshes.md: by the rule, or input="mesh") keeps its faces as in
    the file; convert() remeshes it into a quad cage fitted to it. The result's ``route`` dict
    says which: kind ("mesh" or "cage") and reason."""
    if variant is None:
        selections = []
    elif isinstance(variant, dict):
        selections = ["%s=%s" % (k, v) for k, v in variant.items()]
    elif isinstance(variant, str):
        selections = [variant]
    else:
        selections = list(variant)
    for s in selections:
        if not isinstance(s, str):
            raise TypeError("variant: expected 'set=name' strings, got %r" % (s,))
    d = _subd2nurbs.read_cage(str(path), _checked("input", input, lambda x: isinstance(x, str), "a string", str),
                              selections)
    cage = Cage._from_dict(d, str(path))
    cage.quad_recovery = d["quad_recovery"]
    cage.route = d["route"]
    cage.usd = d["usd"]
    return cage


def input_route(cage, input="auto"):
    """Which road convert() takes with `cage` (docs/meshes.md "Which path"): a dict with kind
    ("mesh": remeshed into a quad cage fitted to it, or "cage") and reason (one sentence)."""
    cage = _cage(cage)
    return _subd2nurbs.input_route(*cage._args(), cage.name,
                                   _checked("input", input, lambda x: isinstance(x, str), "a string", str))


def read_mesh(path):
    """Reads a mesh to reproduce (STL, PLY, OFF, OBJ, glTF): its faces as in the file, welded and
    repaired, not paired into quads; convert() remeshes it (read_cage(path, input="mesh"))."""
    return read_cage(path, input="mesh")


read_obj = read_cage


def from_triangles(vertices, triangles):
    """A cage from a triangle mesh (e.g. FreeCAD's Mesh.Topology): triangle pairs that form
    reasonable quads (convex, nearly planar and rectangular) become quads, triangle fans
    around high-valence vertices stay triangles (polar-structure candidates).

    Returns the Cage; its ``quad_recovery`` dict holds source_triangles, quads,
    triangles_kept, fan_vertices, fan_triangles, other_faces, and ``sources`` lists the
    input faces of each cage face."""
    tri = Cage(vertices, triangles, name="triangles")
    d, counts, sources = _subd2nurbs.recover_quads(*tri._args())
    cage = Cage._from_dict(d, "recovered quads")
    cage.quad_recovery = counts
    cage.sources = sources
    return cage


def _cage(cage):
    if not isinstance(cage, Cage):
        raise TypeError("expected a subd2nurbs.Cage (see subd2nurbs.Cage and subd2nurbs.read_obj), got %s"
                        % type(cage).__name__)
    return cage


def info(cage):
    """Counts of a cage, as `subd2nurbs info --json`: vertices, faces, edges, face_sizes,
    valences, boundary, creases, components, euler_characteristic, closed, bounds, warnings."""
    return _subd2nurbs.info(*_cage(cage)._args())


def _limits(max_faces, max_memory):
    """(max_faces, max_memory) for the C++ side, which checks their values: None (the default),
    max_faces a number, max_memory a number of bytes or a string such as "8G" / "512MiB"."""
    faces = _optional("max_faces", max_faces, _is_number, "a number", float)
    if max_memory is None or isinstance(max_memory, str):
        return faces, max_memory
    return faces, _optional("max_memory", max_memory, _is_number, "a number of bytes or a size string", float)


def refine(cage, levels=1, max_faces=None, max_memory=None):
    """Refines a cage uniformly `levels` times (Catmull-Clark, tags honoured); returns the last
    level's vertices and faces as a new Cage. Unlike `subd2nurbs refine`, the refined level's
    (decayed) crease and corner sharpness is not carried over: the returned Cage has no tags.

    max_faces, max_memory: refuse (SettingsError) when the output faces (exact) or the
    estimated memory exceed them, as refine --max-faces / --max-memory (defaults 2e7 faces,
    3/4 of the memory available)."""
    cage = _cage(cage)
    levels = _checked("levels", levels, _is_int, "an integer", int)
    faces, memory = _limits(max_faces, max_memory)
    vertices, sizes, indices = _subd2nurbs.refine(*cage._args(), levels, faces, memory)
    offsets = np.concatenate([[0], np.cumsum(sizes)])
    faces = [indices[offsets[f]:offsets[f + 1]].tolist() for f in range(len(sizes))]
    return Cage(vertices, faces, name="%s (level %d)" % (cage.name, levels))


class ConversionResult:
    """What convert() returns.

    patches: one dict per NURBS patch (one B-rep face): degree_u, degree_v, knots_u, mults_u,
        knots_v, mults_v (distinct knots and their multiplicities, numpy), poles (numpy
        (nu, nv, 3)), weights (numpy (nu, nv), or None when all are 1), base_faces (cage faces it
        comes from), cells (a packed face: numpy (quads, 5) rows base_face, coarse_face, u, v,
        rotation, its domain one unit per quad; None for a patch of one quad or a polar cap).
    brep_text: OCCT BREP text of the B-rep (None with brep=False); FreeCAD reads it with
        Part.Shape().importBrepFromString(text). Made from the shape on first use.
    brep: the B-rep's counts and validity (faces, edges, vertices, solids, shells, is_solid,
        valid, check_message, tolerance), or None.
    report: the quality report (subd2nurbs-report v1, docs/formats.md) as a dict.
    report_json: the same as JSON text.
    curve_measures: per shared curve, numpy arrays: curve, claimed (0 boundary, 1 C0, 2 G1,
        3 C1, 4 C2), gap, normal_angle_deg, edge (1-based index into the shape's edges, i.e.
        FreeCAD's "EdgeN", 0 if none).
    warnings: list of text: the cage's warnings, then the conversion's, one line each as the
        command line prints them ("subd2nurbs: note: vertex 5 (valence 4) is not a polar structure, ...").
    diagnostics: the conversion's warnings and notes as dicts: severity ("note" or "warning"),
        code (a stable name, e.g. "pole_not_polar", "tolerance_not_met"), message (no program or
        option names), element (the cage vertex it is about, or -1), remedy (the keyword argument
        that may mend it, a name of SETTINGS, or None).
    preview: convert(preview=...): the coloured tessellation (see convert), else None;
        make_preview() makes one later from the same patches.

    The result keeps the converter's own result (the compiled module's Conversion: the patches,
    the cage they came from and the B-rep as an OCCT shape), so write() and make_preview() need
    no second conversion.
    """

    def __init__(self, conversion):
        self._conversion = conversion
        self._brep_text = None
        self.patches = conversion.patches()
        self.brep = conversion.brep
        self.report_json = conversion.report_json
        self.report = json.loads(self.report_json)
        self.curve_measures = conversion.curve_measures
        self.warnings = conversion.warnings
        self.diagnostics = conversion.diagnostics
        self.model_size = conversion.model_size
        self.closed = conversion.closed
        self.preview = conversion.preview  # convert(preview=...): the coloured tessellation, else None
        #: The cage that was converted (numpy (n, 3)): the input's vertices, or with
        #: fit="interpolate" the cage whose limit passes through them.
        self.cage_vertices = conversion.cage_vertices
        made = conversion.made_cage
        #: A mesh input (docs/meshes.md): the quad cage made from it, fitted (a Cage), else None;
        #: report["mesh"] says how it was made.
        self.made_cage = None if made is None else Cage._from_dict(made, "cage of the mesh")

    @property
    def brep_text(self):
        if self._brep_text is None:
            self._brep_text = self._conversion.brep_text
        return self._brep_text

    def write(self, path, schema="ap214"):
        """Writes the B-rep as STEP (.step/.stp, schema "ap214" or "ap242"), IGES (.iges/.igs)
        or BREP (.brep), atomically, with the CLI's writer, from the shape the conversion made.
        Raises WriteError naming the file."""
        if self.brep is None:
            raise ConversionError("no B-rep to write: converted with brep=False")
        self._conversion.write(str(path), schema)

    def make_preview(self, color="curvature", samples=16):
        """The patches tessellated with per-vertex colours, as convert(preview=color,
        preview_samples=samples) makes them (the same dict as `preview`), without converting
        again."""
        _checked("preview", color, lambda x: isinstance(x, str), "a string", str)
        samples = _checked("preview_samples", samples, _is_int, "an integer", int)
        return self._conversion.make_preview(color, samples)

    @property
    def num_patches(self):
        return len(self.patches)

    def worst_edges(self, count=5):
        """The B-rep edges (1-based "EdgeN" indices) of the `count` shared smooth curves with
        the largest normal angle, as (edge, normal_angle_deg, gap), worst first."""
        m = self.curve_measures
        smooth = np.nonzero((m["claimed"] >= 2) & (m["edge"] > 0))[0]
        order = smooth[np.argsort(-m["normal_angle_deg"][smooth], kind="stable")]
        return [(int(m["edge"][i]), float(m["normal_angle_deg"][i]), float(m["gap"][i]))
                for i in order[:count]]

    def __repr__(self):
        b = self.brep
        return "<subd2nurbs.ConversionResult: %d patches%s>" % (
            self.num_patches,
            "" if b is None else ", %s, %d faces, %s" % ("solid" if b["is_solid"] else "shell", b["faces"],
                                                        "valid" if b["valid"] else "NOT valid"))


class StageText(str):
    """A progress line (str) of convert(), with the stage's stable name as ``key``."""

    def __new__(cls, text, key):
        self = super().__new__(cls, text)
        self.key = key
        return self


#: The settings of convert(), one per row of the converter's settings table (docs/settings.md),
#: each a dict: name, type ("flag", "on-off", "integer", "number", "word", "size"), default (None:
#: optional, default_text says what leaving it out means), help, choices (a word's names), cli
#: (the command line's flag or None), property (the FreeCAD workbench's property: name, group,
#: tooltip, choices as (shown, converter's name) pairs, zero_is_default, scale; or None).
SETTINGS = tuple(row for row in _subd2nurbs.settings_table() if row["python"])
_SETTING = {row["name"]: row for row in SETTINGS}

#: The Python types each type of setting takes: (check, what it must be, conversion).
_VALUE_TYPES = {
    "integer": (_is_int, "an integer", int),
    "number": (_is_number, "a number", float),
    "word": (lambda x: isinstance(x, str), "a string", str),
    "size": (lambda x: isinstance(x, str) or _is_number(x), "a number of bytes or a size string",
             lambda x: x if isinstance(x, str) else float(x)),
}


def _setting_value(row, value):
    """A keyword's value with its type checked (SettingsError naming the setting); the converter
    checks the value itself by its rules."""
    kind = row["type"]
    if kind == "flag":
        return bool(value)
    if kind == "on-off":  # True / False, or the command line's words "on" / "off"
        return value if isinstance(value, str) else bool(value)
    check, what, conversion = _VALUE_TYPES[kind]
    if row["default"] is None:  # optional: None leaves it to the converter
        if value is None:
            return None
        if kind == "word":
            what = "None or a string"
    return _checked(row["name"], value, check, what, conversion)


def _settings_doc():
    lines = []
    for row in SETTINGS:
        default = row["default_text"] if row["default"] is None else repr(row["default"])
        cli = ", as %s" % row["cli"] if row["cli"] else ""
        lines.append("    %s: %s (default: %s%s)." % (row["name"], row["help"], default, cli))
    return "\n".join(lines)


def convert(cage, progress=None, allow_invalid=False, fit_to=None, **settings):
    cage = _cage(cage)
    if fit_to is not None:
        if settings.get("fit", "approximate") != "approximate":
            raise SettingsError("fit_to excludes fit=%r: the fit to a target already decides the cage"
                                % settings["fit"], setting="fit_to", rule="excludes the interpolating fit")
        if settings.get("input") == "mesh":
            raise SettingsError("fit_to fits a cage; input='mesh' is fitted to itself", setting="fit_to",
                                rule="excludes input='mesh'")
        cage, _ = fit(cage, fit_to)
    given = {}
    for name, value in settings.items():
        if name not in _SETTING:
            raise TypeError("convert() got an unexpected keyword argument '%s'" % name)
        given[name] = _setting_value(_SETTING[name], value)
    if progress is not None and not callable(progress):
        raise TypeError("progress must be callable(stage, fraction)")
    on_stage = None if progress is None else lambda text, fraction, key: progress(StageText(text, key), fraction)
    built = _subd2nurbs.Settings(**given)
    result = ConversionResult(_subd2nurbs.convert(*cage._args(), settings=built, name=cage.name,
                                                  warnings=cage.warnings, progress=on_stage))
    if built.brep and not allow_invalid and not result.brep["valid"]:
        raise ConversionError("the B-rep is not valid:\n" + result.brep["check_message"].strip(), stage="check")
    return result


convert.__doc__ = """Converts a cage to bicubic NURBS patches and (brep=True) a B-rep checked by OCCT.

Keyword arguments: every setting of the converter's settings table (SETTINGS, docs/settings.md),
each as the command line's option of the same name; the converter's rules check the values and
a SettingsError names the setting at fault:

%s

    With neither level nor tolerance the deviation tolerance is DEFAULT_TOLERANCE (1e-4), as on
    the command line. fit="interpolate" solves for the cage whose exact limit surface passes
    through every vertex; the result's cage_vertices is that cage and report["fit"] says how well
    (FitError names the vertices when no cage interpolates). preview: the result's `preview` is
    then a dict of numpy arrays (positions, normals, colors, values, triangles) and the colour
    map's value_min / value_max (result.make_preview() makes another later). faces="packed":
    a packed face lists its quads in its "cells" (base_face, coarse_face, u, v, rotation).

progress: a callable(stage: str, fraction: float) called as the stages run; `stage` is a line
    for people ("building patches (2 extra levels)") whose `key` attribute names the stage:
    "mesh" (mesh input: the remesh and the fit, with their fractions), "fit", "patches",
    "deviation", "packing", "continuity", "brep" or (with preview) "preview". Returning False
    (not None) cancels the conversion at that call: Cancelled is raised, nothing is returned.
allow_invalid: return a B-rep that BRepCheck rejects instead of raising ConversionError.
fit_to: a target shape (anything fit() takes): the cage is fitted to it first with fit()'s
    defaults, then converted (as the command line's convert --fit-to); excludes fit="interpolate".
Mesh input (docs/meshes.md): a Cage of triangles that do not pair back into quads (read_mesh(),
    read_cage() of an STL, or input="mesh") is a shape to reproduce: its sharp features are
    detected (feature_angle), an all-quad cage of about target_faces quads (by default: sized until
    the fit meets fit_tolerance) is made and fitted to it, and that cage is converted;
    result.made_cage is the cage, report["mesh"] the numbers (report["mesh"]["size"]: the rounds).
""" % _settings_doc()


def fair(cage, weight=1.0, keep=(), levels=2, membrane=0.0):
    """Fairs a cage (as `subd2nurbs fair`): moves its free vertices to minimise the thin-plate
    (+ membrane) energy of the limit surface while keeping the limit points close to where they
    were. keep: any of "boundary", "creases", "tagged" (those vertices stay fixed, bit for bit).
    Returns (Cage with the same faces and tags, info dict: energy_before, energy_after,
    limit_moved_max, limit_moved_mean, cage_moved_max, kept, free)."""
    cage = _cage(cage)
    weight = _checked("weight", weight, _is_number, "a number", float)
    if isinstance(keep, str):
        keep = (keep,)
    for k in keep:
        _checked("keep", k, lambda x: isinstance(x, str), "a string", str)
    levels = _checked("levels", levels, _is_int, "an integer", int)
    membrane = _checked("membrane", membrane, _is_number, "a number", float)
    d = _subd2nurbs.fair(*cage._args(), weight, list(keep), levels, membrane)
    o = cage.options
    out = Cage(d.pop("vertices"), cage.faces, cage.creases, cage.corners, cage.holes, o["boundary"],
               o["crease_method"], o["triangles"], name="%s (faired)" % cage.name)
    return out, d


def _target(target, triangles):
    """(name, points (n, 3), face_sizes, face_indices) of fit()'s target."""
    if isinstance(target, Cage):
        if triangles is not None:
            raise _type_error("triangles", "None when the target is a Cage", triangles)
        return target.name, target.vertices, target.face_sizes, target.face_indices
    if isinstance(target, (str, bytes)) or hasattr(target, "__fspath__"):
        if triangles is not None:
            raise _type_error("triangles", "None when the target is a file", triangles)
        name = str(target.decode() if isinstance(target, bytes) else target)
        points, tris = _subd2nurbs.read_target(name)
    elif isinstance(target, np.ndarray):
        name, points, tris = "points", target, triangles
    else:
        raise _type_error("target", "a path, a Cage or a numpy array of shape (n, 3)", target)
    try:
        points = np.array(points, dtype=np.float64)
    except (TypeError, ValueError):
        raise _type_error("target", "an array of numbers of shape (n, 3)", target) from None
    if points.ndim != 2 or points.shape[1] != 3 or points.shape[0] == 0 or not np.all(np.isfinite(points)):
        raise _type_error("target", "a non-empty array of finite numbers of shape (n, 3)", target)
    if tris is None:
        tris = np.zeros((0, 3), dtype=np.int32)
    try:
        tris = np.array(tris)
    except (TypeError, ValueError):
        raise _type_error("triangles", "an integer array of shape (m, 3)", triangles) from None
    if tris.size == 0:
        tris = np.zeros((0, 3), dtype=np.int32)
    if tris.ndim != 2 or tris.shape[1] != 3 or not np.issubdtype(tris.dtype, np.integer):
        raise _type_error("triangles", "an integer array of shape (m, 3)", triangles)
    if tris.size and (tris.min() < 0 or tris.max() >= points.shape[0]):
        raise SettingsError("triangles: vertex index out of range (0 .. %d)" % (points.shape[0] - 1),
                            setting="triangles", rule="must index the target's points")
    tris = tris.astype(np.int32)
    return name, points, np.full(tris.shape[0], 3, dtype=np.int32), tris.reshape(-1)


def fit(cage, target, smoothing=None, levels=3, max_iterations=None, tolerance=None, triangles=None, progress=None,
        min_gain=0.02, exact_target=False):
    """Fits a cage to a target shape (as `subd2nurbs fit`): moves its vertices so that the exact
    limit surface fits the target, from the cage's own positions (docs/fitting.md).

    target: a path (STL, PLY, OFF, OBJ, glTF triangles; a point cloud as .xyz or a PLY / OBJ
    with vertices only), a Cage (its faces fan-triangulated), or a numpy (n, 3) array of points,
    with triangles=(m, 3) vertex indices for a triangle mesh.
    Returns (Cage with the same faces and tags, info dict: iterations, stop, samples, before and
    after (the two-sided distance of the input and the fitted limit surface to the target:
    diagonal, limit_to_target and target_to_limit, each max / rms / p95 relative to the target's
    diagonal), history, fit_ms, measure_ms).
    smoothing, max_iterations, tolerance: None for the defaults (1e-4, 30, 1e-7; with exact_target
    0, 100, 1e-8). min_gain: stop when an iteration improves the two-sided RMS distance by less
    than this fraction (0: off). exact_target=True: the target lies on a subdivision surface (a
    dense, noise-free sampling of an exact limit): the weights that recover it, as
    `subd2nurbs fit --exact-target` (docs/fitting.md).
    progress: None, or a callable progress(iteration, max_iterations, objective) called after each
    closest-point pairing; returning False cancels the fit (stop "cancelled", the cage of the last
    solve is returned)."""
    if progress is not None and not callable(progress):
        raise SettingsError("progress must be callable or None, not %r" % (progress,), setting="progress",
                            rule="must be callable or None")
    cage = _cage(cage)
    if smoothing is not None:
        smoothing = _checked("smoothing", smoothing, _is_number, "a number", float)
    levels = _checked("levels", levels, _is_int, "an integer", int)
    if max_iterations is not None:
        max_iterations = _checked("max_iterations", max_iterations, _is_int, "an integer", int)
    if tolerance is not None:
        tolerance = _checked("tolerance", tolerance, _is_number, "a number", float)
    min_gain = _checked("min_gain", min_gain, _is_number, "a number", float)
    if not isinstance(exact_target, bool):
        raise SettingsError("exact_target must be True or False, not %r" % (exact_target,), setting="exact_target",
                            rule="must be True or False")
    name, points, sizes, indices = _target(target, triangles)
    d = _subd2nurbs.fit(*cage._args(), points, sizes, indices, name, smoothing, levels, max_iterations, tolerance,
                        min_gain, exact_target, progress)
    info = json.loads(d["report"])
    for key in ("format", "version", "input", "output"):
        info.pop(key, None)
    o = cage.options
    out = Cage(d["vertices"], cage.faces, cage.creases, cage.corners, cage.holes, o["boundary"],
               o["crease_method"], o["triangles"], name="%s (fitted)" % cage.name)
    return out, info


def brep_summary(text):
    """OCCT's own measurement of BREP text: solids, shells, faces, edges, free_edges, valid,
    area, volume, max_gap, max_normal_angle_deg."""
    if not isinstance(text, str):
        raise TypeError("expected BREP text (str)")
    return _subd2nurbs.brep_summary(text)


def file_summary(path):
    """OCCT's measurement of a STEP / IGES / BREP file (as brep_summary)."""
    return _subd2nurbs.file_summary(str(path))


def occt_compatible(version):
    """True if an OCCT version string (e.g. FreeCAD's Part.OCC_VERSION) is the one this module
    links: BREP text is only exchanged between identical OCCT versions."""
    return str(version).split(".")[:3] == OCC_VERSION.split(".")[:3]
