"""Exceptions of subd2nurbs. Each names what it is about (file and line, or face / vertex /
crease index) in its message and as attributes."""


class Subd2NurbsError(Exception):
    """Base class of every subd2nurbs error."""

    def __init__(self, message, **attributes):
        super().__init__(message)
        self.message = message
        for key, value in attributes.items():
            setattr(self, key, value)


class CageError(Subd2NurbsError, ValueError):
    """The cage is not valid: bad arrays, an index out of range, a non-manifold edge, a bad
    tag, an unreadable or malformed file.

    Attributes (those that apply): ``element`` ("vertex", "face", "edge", "tag", "crease",
    "corner", "hole", "vertices", "faces"), ``index``, ``code`` (the core's MeshErrorCode text, e.g. "index-out-of-range"),
    ``file``, ``line``."""

    element = None
    index = None
    code = None
    file = None
    line = None


class SettingsError(Subd2NurbsError, ValueError):
    """A conversion setting that cannot be used (negative level, bad tolerance, a level too
    deep for the cage, unknown boundary rule). ``setting`` names it as the keyword argument
    spells it ("radial_steps") and ``rule`` says what it must be ("must be 1 or 2"), in the
    words the command line and the FreeCAD workbench use too; a refusal by the resource limits
    has ``code`` "resource-limit" instead."""

    setting = None
    rule = None
    code = None


class FitError(Subd2NurbsError, ValueError):
    """No cage has a limit surface through the given points (fit="interpolate"): the limit
    system is singular or badly conditioned and the points leave its range. ``vertices``
    names where (a fair fit, ``fair=W``, accepts such points)."""

    vertices = ()


class ConversionError(Subd2NurbsError, RuntimeError):
    """The conversion failed: the patch builder does not support the topology, OCCT failed,
    or the B-rep is not valid. ``stage`` and ``patch`` say where, when known."""

    stage = None
    patch = None


class WriteError(Subd2NurbsError, OSError):
    """An output file could not be written (``file``)."""

    file = None


class Cancelled(Subd2NurbsError):
    """The conversion was cancelled: its progress callable returned False. Nothing was
    returned or written."""
