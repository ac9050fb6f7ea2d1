"""The geomkit error hierarchy.

Every error geomkit raises on bad input is a :class:`GeomkitError`; the message names
the offending field and states what was expected.  The classes also derive from the
matching built-in (``ValueError``, ``OSError``, ``ImportError``) so that generic
``except ValueError`` code keeps working.
"""

from __future__ import annotations

__all__ = [
    "GeomkitError",
    "InvalidInputError",
    "InvalidSurfaceError",
    "InvalidTrimError",
    "DegenerateGeometryError",
    "FileFormatError",
    "MissingDependencyError",
    "ToleranceNotMetWarning",
    "MeshingError",
    "FaceFailedWarning",
    "FileRecoveredWarning",
]


class GeomkitError(Exception):
    """Base class of every error geomkit raises deliberately."""


class InvalidInputError(GeomkitError, ValueError):
    """An argument has the wrong shape, type, range or value.

    Attributes
    ----------
    field : str or None
        Name (or path, e.g. ``"surfaces[0].knots_u"``) of the offending field.
    """

    def __init__(self, message: str, field: str | None = None):
        self.field = field
        super().__init__(f"{field}: {message}" if field else message)


class InvalidSurfaceError(InvalidInputError):
    """A surface definition is inconsistent (knots, degrees, control net, weights)."""


class InvalidTrimError(InvalidSurfaceError):
    """A trim loop is open, degenerate, self-inconsistent or outside the domain."""


class DegenerateGeometryError(GeomkitError, ValueError):
    """The geometry is valid but degenerate where the operation needs it not to be."""


class FileFormatError(GeomkitError, ValueError):
    """A file could not be read: unknown format, malformed content, missing fields."""


class MissingDependencyError(GeomkitError, ImportError):
    """An optional dependency needed for this operation is not installed."""


class MeshingError(GeomkitError, RuntimeError):
    """A face could not be triangulated (the message names the face and the cause)."""


class FaceFailedWarning(UserWarning):
    """One face of a model failed (e.g. its triangulation): it was answered by a
    fallback route that keeps the result's guarantee (``tessellate``: the face meshed
    from its untrimmed surface's cells, ``stats["fallback"]``) or, when that failed
    too, left out of the result (``stats["failed"]``); the stats name the face and
    why.  The other faces are unaffected."""


class ToleranceNotMetWarning(UserWarning):
    """A result could not be brought within the requested tolerance; the value it
    states (e.g. ``Mesh.max_deviation``) is the measured one, above the request."""


class FileRecoveredWarning(UserWarning):
    """A file was read only after its reader recovered from errors in it (e.g. Open
    CASCADE skipping records with syntax errors): what those records held may be
    missing from the result."""
