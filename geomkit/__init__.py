"""geomkit: exact NURBS surface geometry with stated error bounds.

Public API (users' scripts depend on these names):

* :class:`Surface` — B-spline / NURBS surfaces with trims; ``evaluate``,
  ``derivatives``, ``normals``, ``classify_uv``, ``bezier_patches``.
* :func:`tessellate` -> :class:`Mesh` — triangles within a chord tolerance that holds.
* :func:`project_points` -> :class:`Projection` — exact feet of points (CMM deviation);
  :class:`VoxelGrid`, :func:`nearest_triangles` (Paper 1).
* :func:`surface_distance` -> :class:`SurfaceDistance` — certified minimum distance
  between surfaces or scenes (Bézier branch and bound + Newton).
* :func:`probe_clearance`, :class:`Stylus` — probe safety: certified stylus clearance
  along a path past exact NURBS parts
* :func:`first_contact`, :func:`probe_path`, :class:`Scene` — motion, probe paths, sweep
  and prune (Papers 3, 4, 5).
* :func:`plane_section` -> :class:`Section` — plane sections (Paper 2), exact points,
  fit and CSV / DXF / JSON export.
* :func:`load`, :func:`save`, :func:`load_case` — ``geomkit-case/1`` and geomdl JSON.
* :mod:`geomkit.samples` — the bundled canonical cases.
* :class:`Body`, :func:`collide`, :func:`collide_many`, :func:`min_distance` — OBB /
  14-DOP / AABB trees and exact triangle tests (Papers 3, 5).
* :mod:`geomkit.errors` — the :class:`GeomkitError` hierarchy.
"""

from . import errors, samples, tolerances
from .bezier import bezier_patches
from . import report
from .collision import Body, Contact, Contacts, Distance, collide, collide_many, min_distance
from .errors import (DegenerateGeometryError, FileFormatError, GeomkitError,
                     InvalidInputError, InvalidSurfaceError, InvalidTrimError,
                     MissingDependencyError)
from .deviation import DeviationReport, align_rigid, deviation
from .distance import surface_distance
from .evaluation import derivatives, evaluate, normals
from .iges import IgesResult, read_iges
from .clearance import Clearance, Stylus, probe_clearance
from .motion import FirstContact, ProbePath, first_contact, probe_path
from .io import Case, load, load_case, save
from .points_io import PointSet, read_points
from .projection import Projector, project_points
from .results import MeshNearest, Projection, SurfaceDistance
from .scene import (CoherentPair, Scene, SceneCollisions, SceneDistances, SweepAndPrune,
                    fit_exclusions)
from .section import Section, plane_section
from .step import read_step
from .tessellate import tessellate
from .trimming import INSIDE, ON_BOUNDARY, OUTSIDE, classify_uv
from .types import BezierPatches, Mesh, Surface, TrimCurve, TrimLoop
from .voxel import VoxelGrid, nearest_triangles

__version__ = "0.1.0"

__all__ = [
    "Surface", "TrimCurve", "TrimLoop", "BezierPatches", "Case", "Mesh", "tessellate",
    "load", "load_case", "save", "samples",
    "evaluate", "derivatives", "normals", "classify_uv", "bezier_patches",
    "INSIDE", "OUTSIDE", "ON_BOUNDARY",
    "errors", "tolerances", "GeomkitError", "InvalidInputError", "InvalidSurfaceError",
    "InvalidTrimError", "DegenerateGeometryError", "FileFormatError",
    "MissingDependencyError",
    "project_points", "Projector", "Projection", "VoxelGrid", "nearest_triangles",
    "MeshNearest", "surface_distance", "SurfaceDistance",
    "plane_section", "Section",
    "deviation", "DeviationReport", "align_rigid", "read_points", "PointSet", "read_iges",
    "IgesResult", "read_step", "report",
    "first_contact", "probe_path", "FirstContact", "ProbePath", "Scene", "SceneCollisions",
    "probe_clearance", "Stylus", "Clearance",
    "SceneDistances", "SweepAndPrune", "CoherentPair", "fit_exclusions",
    "Body", "Contact", "Contacts", "Distance", "collide", "collide_many", "min_distance",
]
