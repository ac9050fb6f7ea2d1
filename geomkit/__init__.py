"""geomkit: exact NURBS surface geometry with stated error bounds.

Public API (users' scripts depend on these names):

* :class:`Surface` — B-spline / NURBS surfaces with trims; ``evaluate``,
  ``derivatives``, ``normals``, ``classify_uv``, ``bezier_patches``.
* :func:`tessellate` -> :class:`Mesh` — triangles within a chord tolerance that holds.
* :func:`load`, :func:`save`, :func:`load_case` — ``geomkit-case/1`` and geomdl JSON.
* :mod:`geomkit.samples` — the bundled canonical cases.
* :class:`Body`, :func:`collide`, :func:`collide_many`, :func:`min_distance` — OBB /
  14-DOP / AABB trees and exact triangle tests (Papers 3, 5).
* :mod:`geomkit.errors` — the :class:`GeomkitError` hierarchy.
"""

from . import errors, samples, tolerances
from .bezier import bezier_patches
from .collision import Body, Contact, Contacts, Distance, collide, collide_many, min_distance
from .errors import (DegenerateGeometryError, FileFormatError, GeomkitError,
                     InvalidInputError, InvalidSurfaceError, InvalidTrimError,
                     MissingDependencyError)
from .evaluation import derivatives, evaluate, normals
from .io import Case, load, load_case, save
from .tessellate import tessellate
from .trimming import INSIDE, ON_BOUNDARY, OUTSIDE, classify_uv
from .types import BezierPatches, Mesh, Surface, TrimCurve, TrimLoop

__version__ = "0.1.0"

__all__ = [
    "Surface", "TrimCurve", "TrimLoop", "BezierPatches", "Case", "Mesh", "tessellate",
    "load", "load_case", "save", "samples",
    "evaluate", "derivatives", "normals", "classify_uv", "bezier_patches",
    "INSIDE", "OUTSIDE", "ON_BOUNDARY",
    "errors", "tolerances", "GeomkitError", "InvalidInputError", "InvalidSurfaceError",
    "InvalidTrimError", "DegenerateGeometryError", "FileFormatError",
    "MissingDependencyError",
    "Body", "Contact", "Contacts", "Distance", "collide", "collide_many", "min_distance",
]
