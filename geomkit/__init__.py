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

from geomkit import errors, samples, tolerances
from geomkit.nurbs.bezier import bezier_patches
from geomkit import report
from geomkit.collision.collide import (Body, Contact, Contacts, Distance, collide, collide_many,
                                       min_distance)
from geomkit.errors import (DegenerateGeometryError, FileFormatError, GeomkitError,
                            InvalidInputError, InvalidSurfaceError, InvalidTrimError,
                            MissingDependencyError)
from geomkit.jobs.deviation import DeviationReport, align_rigid, deviation
from geomkit.query.distance import surface_distance
from geomkit.nurbs.evaluation import derivatives, evaluate, normals
from geomkit.cad.iges.reader import IgesResult, read_iges
from geomkit.jobs.clearance import Clearance, Stylus, probe_clearance
from geomkit.collision.motion import FirstContact, ProbePath, first_contact, probe_path
from geomkit.exchange.cases import Case, load, load_case, save
from geomkit.exchange.points import PointSet, read_points
from geomkit.fitting import FitResult, fit
from geomkit import gdt
from geomkit.gdt import Characteristic, DatumFrame, datum_frame
from geomkit.cad.steppmi import Pmi, read_pmi
from geomkit.jobs.inspect import Inspection, inspect_part
from geomkit.jobs.sample import SampledPoints, sample_faces
from geomkit.query.projection import Projector
from geomkit.query.projection_part import PartProjector, project_points
from geomkit.query.results import MeshNearest, Projection, SurfaceDistance
from geomkit.collision.scene import (CoherentPair, Scene, SceneCollisions, SceneDistances,
                                     SweepAndPrune, fit_exclusions)
from geomkit.section.plane import Section, plane_section
from geomkit.cad.step import read_step
from geomkit.mesh.tessellate import tessellate
from geomkit.nurbs.trimming import INSIDE, ON_BOUNDARY, OUTSIDE, classify_uv
from geomkit.nurbs.surface import BezierPatches, Surface, TrimCurve, TrimLoop
from geomkit.mesh.mesh import Mesh
from geomkit.query.voxel import VoxelGrid, nearest_triangles

from geomkit.version import __version__  # noqa: F401 (public)
from geomkit import _moved

_moved.install()

__all__ = [
    "Surface", "TrimCurve", "TrimLoop", "BezierPatches", "Case", "Mesh", "tessellate",
    "load", "load_case", "save", "samples",
    "evaluate", "derivatives", "normals", "classify_uv", "bezier_patches",
    "INSIDE", "OUTSIDE", "ON_BOUNDARY",
    "errors", "tolerances", "GeomkitError", "InvalidInputError", "InvalidSurfaceError",
    "InvalidTrimError", "DegenerateGeometryError", "FileFormatError",
    "MissingDependencyError",
    "project_points", "Projector", "PartProjector", "Projection", "VoxelGrid", "nearest_triangles",
    "MeshNearest", "surface_distance", "SurfaceDistance",
    "plane_section", "Section",
    "deviation", "DeviationReport", "align_rigid", "read_points", "PointSet", "read_iges",
    "IgesResult", "read_step", "report",
    "first_contact", "probe_path", "FirstContact", "ProbePath", "Scene", "SceneCollisions",
    "probe_clearance", "Stylus", "Clearance",
    "SceneDistances", "SweepAndPrune", "CoherentPair", "fit_exclusions",
    "Body", "Contact", "Contacts", "Distance", "collide", "collide_many", "min_distance",
    "fit", "FitResult", "gdt", "datum_frame", "DatumFrame", "Characteristic",
    "read_pmi", "Pmi", "sample_faces", "SampledPoints", "inspect_part", "Inspection",
]
