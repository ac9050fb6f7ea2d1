"""Reading and writing surfaces: ``geomkit-case/1`` JSON and geomdl JSON (and reading
IGES / STEP models by suffix).

``geomkit-case/1``::

    {"format": "geomkit-case/1", "name": ..., "description": ..., "units": "mm",
     "surfaces": [{"degree_u", "degree_v", "knots_u", "knots_v",
                   "control_points": [nu][nv][3], "weights": [nu][nv] (optional),
                   "trim": [loop, ...] (optional, outer first)}],
     "truth": {...}}

``units`` (optional) names the length unit of the coordinates (see
:mod:`geomkit.units`); without it the units are unknown ("model units").

geomdl JSON is what ``geomdl.exchange.export_json`` writes (``{"shape": {"type":
"surface", "data": [...]}}``, control points flattened with v varying fastest).

IGES and STEP files are read by :func:`load` / :func:`load_case` too (by suffix,
through :mod:`geomkit.cad.iges.reader` / :mod:`geomkit.cad.step`).  Files are only read by :func:`load`; :func:`save` writes a temporary file beside the
target and renames it into place, and refuses to replace an existing file unless
``overwrite=True``.
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from geomkit.errors import FileFormatError, InvalidInputError, InvalidSurfaceError
from geomkit.mesh.mesh import MESH_FORMATS, export_mesh
from geomkit.nurbs import serial
from geomkit.nurbs.surface import Surface, as_surfaces
from geomkit.outputs import atomic_write, check_target

__all__ = ["Case", "load", "load_case", "save", "surface_to_dict", "surface_from_dict",
           "to_geomdl", "from_geomdl", "export_mesh", "CASE_FORMAT", "MESH_FORMATS"]


CASE_FORMAT = "geomkit-case/1"


@dataclass
class Case:
    """A loaded case file: its surfaces plus the optional analytic truth.

    ``units``: the length unit of the coordinates (``"mm"``, ``"in"``, ...; see
    :mod:`geomkit.units`), None when the file does not say ("model units")."""

    name: str
    surfaces: list
    truth: dict = field(default_factory=dict)
    description: str = ""
    units: str | None = None
    skipped: list = field(default_factory=list)
    """Faces left out of a CAD read (``skip_unsupported``): ``(id, reason)`` pairs."""
    gap: float | None = None
    """The model's edge gap (faces sharing an edge meet within it), measured on the
    file's topology (STEP); None when the file gives none.  Sections join curve ends
    across it (:func:`geomkit.plane_section`'s ``gap``)."""
    duplicates: dict = field(default_factory=dict)
    """Loose faces lying on a solid's face (STEP): position -> the solid faces'
    positions (:mod:`geomkit.cad.loose`); jobs that need one boundary leave them out."""
    entities: list | None = None
    """CAD reads: the file's face (STEP) or entity (IGES) index of each surface, as
    ``IgesResult.entities``; what PMI face indices refer to."""


# --------------------------------------------------------------------- dicts
def surface_to_dict(s: Surface) -> dict:
    """The ``geomkit-case/1`` form of ``s`` (same as ``s.to_dict()``)."""
    return serial.surface_to_dict(s)


def _prefixed(exc: InvalidInputError, prefix: str) -> InvalidInputError:
    field_ = f"{prefix}.{exc.field}" if exc.field else prefix
    msg = str(exc)
    if exc.field and msg.startswith(exc.field + ": "):
        msg = msg[len(exc.field) + 2:]
    return type(exc)(msg, field_)


def surface_from_dict(d: dict, where: str = "surface") -> Surface:
    if not isinstance(d, dict):
        raise FileFormatError(f"{where}: expected an object, got {type(d).__name__}")
    missing = [k for k in ("degree_u", "degree_v", "knots_u", "knots_v", "control_points")
               if k not in d]
    if missing:
        raise FileFormatError(f"{where}: missing field(s) {', '.join(missing)}")
    try:
        return Surface(d["degree_u"], d["degree_v"], d["knots_u"], d["knots_v"],
                       d["control_points"], d.get("weights"), d.get("trim"),
                       name=d.get("name"), approx_error=d.get("approx_error", 0.0))
    except InvalidInputError as exc:
        raise _prefixed(exc, where) from None


# -------------------------------------------------------------------- geomdl
def to_geomdl(s: Surface):
    """A geomdl ``BSpline.Surface`` or ``NURBS.Surface`` (trims are not carried)."""
    return serial.surface_to_geomdl(s)


def from_geomdl(g) -> Surface:
    """Build a :class:`Surface` from a geomdl surface object."""
    return Surface.from_geomdl(g)


def _from_geomdl_json(doc: dict, where: str) -> list[Surface]:
    shape = doc["shape"]
    if not isinstance(shape, dict):
        raise FileFormatError(f"{where}: geomdl 'shape' must be an object, got "
                              f"{type(shape).__name__}")
    if shape.get("type") != "surface":
        raise FileFormatError(f"{where}: geomdl shape type {shape.get('type')!r}, "
                              "only 'surface' is supported")
    data = shape.get("data")
    if not isinstance(data, list) or not data:
        raise FileFormatError(f"{where}: geomdl 'shape.data' must be a non-empty list")
    out = []
    for k, d in enumerate(data):
        w = f"{where}: shape.data[{k}]"
        if not isinstance(d, dict):
            raise FileFormatError(f"{w}: expected an object, got {type(d).__name__}")
        try:
            nu, nv = int(d["size_u"]), int(d["size_v"])
            cp = d["control_points"]
            P = np.asarray(cp["points"], dtype=float)
            if P.ndim != 2 or P.shape[0] != nu * nv or P.shape[1] != 3:
                raise FileFormatError(f"{w}.control_points.points: expected {nu * nv} points "
                                      f"of 3 coordinates, got shape {P.shape}")
            weights = cp.get("weights")
            if weights is not None:
                weights = np.asarray(weights, dtype=float).reshape(nu, nv)
            out.append(Surface(d["degree_u"], d["degree_v"], d["knotvector_u"],
                               d["knotvector_v"], P.reshape(nu, nv, 3), weights,
                               name=d.get("name")))
        except KeyError as exc:
            raise FileFormatError(f"{w}: missing field {exc.args[0]!r}") from None
        except (TypeError, ValueError, AttributeError) as exc:
            if isinstance(exc, InvalidInputError):
                raise _prefixed(exc, w) from None
            raise FileFormatError(f"{w}: {exc}") from None
    return out


# ---------------------------------------------------------------------- read
def _read_json(path) -> dict:
    p = Path(path)
    try:
        if not p.exists():
            raise FileFormatError(f"{p}: no such file")
        if p.is_dir():
            raise FileFormatError(f"{p}: is a directory, expected a JSON file")
        text = p.read_text(encoding="utf-8")
    except UnicodeDecodeError:
        raise FileFormatError(f"{p}: not a text file (expected JSON)") from None
    except OSError as exc:
        raise FileFormatError(f"{p}: cannot read ({exc.strerror or exc})") from None
    try:
        return json.loads(text)
    except json.JSONDecodeError as exc:
        raise FileFormatError(f"{p}: invalid JSON at line {exc.lineno}, column {exc.colno}: "
                              f"{exc.msg}") from None


def case_from_doc(doc, where: str = "case") -> Case:
    """Parse a ``geomkit-case/1`` or geomdl JSON document (already decoded)."""
    if not isinstance(doc, dict):
        raise FileFormatError(f"{where}: expected a JSON object at the top level")
    if "shape" in doc:
        return Case(doc.get("name", ""), _from_geomdl_json(doc, where))
    fmt = doc.get("format", CASE_FORMAT)
    if fmt != CASE_FORMAT:
        raise FileFormatError(f"{where}: unknown format {fmt!r} (expected {CASE_FORMAT!r} "
                              "or geomdl JSON)")
    if "surfaces" not in doc:
        raise FileFormatError(f"{where}: no 'surfaces' list (not a {CASE_FORMAT} or geomdl "
                              "JSON file)")
    surfs = doc["surfaces"]
    if not isinstance(surfs, list) or not surfs:
        raise FileFormatError(f"{where}: 'surfaces' must be a non-empty list")
    out = [surface_from_dict(d, f"{where}: surfaces[{k}]") for k, d in enumerate(surfs)]
    truth = doc.get("truth") or {}
    return Case(doc.get("name", ""), out, truth, doc.get("description", ""),
                _units_from_doc(doc, where))


def _units_from_doc(doc: dict, where: str):
    from geomkit.units import canonical_units

    u = doc.get("units")
    if u is None:
        return None
    if not isinstance(u, str):
        raise FileFormatError(f"{where}: 'units' must be a string such as \"mm\", got "
                              f"{type(u).__name__}")
    try:
        return canonical_units(u)
    except InvalidInputError as exc:
        raise FileFormatError(f"{where}: {exc}") from None


CAD_SUFFIXES = (".igs", ".iges", ".stp", ".step")


def load_case(path, *, skip_invalid: bool = False, skip_unsupported: bool = False) -> Case:
    """Read a model file as a :class:`Case`: JSON (``geomkit-case/1`` with its truth
    block, or geomdl JSON), IGES (``.igs`` / ``.iges``, :func:`geomkit.read_iges`) or
    STEP (``.stp`` / ``.step``, :func:`geomkit.read_step`, needs Open CASCADE), told
    apart by the file's suffix.

    ``skip_invalid`` / ``skip_unsupported`` are the CAD readers' options: without them a
    face that cannot be read stops the read (every such face named); with them the
    faces left out are listed in ``case.skipped`` (never silent: an answer computed on
    part of a model is not the model's).  A JSON case is read whole: they do not apply.
    """
    p = Path(path)
    if p.suffix.lower() in CAD_SUFFIXES:
        return _cad_case(p, skip_invalid, skip_unsupported)
    case = case_from_doc(_read_json(p), str(path))
    if not case.name:
        case.name = p.stem
    return case


def _cad_case(p: Path, skip_invalid: bool, skip_unsupported: bool) -> Case:
    if p.suffix.lower() in (".igs", ".iges"):
        from geomkit.cad.iges.reader import read_iges as read
    else:
        from geomkit.cad.step import read_step as read
    res = read(p, skip_invalid=skip_invalid, skip_unsupported=skip_unsupported)
    return Case(p.stem, res.surfaces, units=_reader_units(getattr(res, "units", None)),
                skipped=list(res.skipped), gap=getattr(res, "edge_gap", None),
                duplicates=dict(getattr(res, "duplicates", None) or {}),
                entities=None if getattr(res, "entities", None) is None
                else list(res.entities))


def _reader_units(units):
    """A CAD reader's unit name in canonical form (``"MM"`` -> ``"mm"``); a name
    geomkit does not know is kept as the file states it."""
    from geomkit.units import canonical_units

    if not units:
        return None
    try:
        return canonical_units(units)
    except InvalidInputError:
        return str(units)


def load(path, *, skip_invalid: bool = False, skip_unsupported: bool = False
         ) -> list[Surface]:
    """Read the surfaces of a model file: ``geomkit-case/1`` or geomdl JSON, IGES or
    STEP (by suffix; see :func:`load_case`, whose ``skipped`` list says which faces a
    ``skip_unsupported`` / ``skip_invalid`` read left out).

    Raises
    ------
    FileFormatError
        Missing file, invalid JSON, unknown format or missing fields (the message
        names the file and the field); a CAD file with faces that cannot be read
        (each named) unless skipped.
    InvalidSurfaceError
        A surface that fails validation (the field path names the surface).
    MissingDependencyError
        A STEP file without Open CASCADE installed.
    """
    return load_case(path, skip_invalid=skip_invalid,
                     skip_unsupported=skip_unsupported).surfaces


# --------------------------------------------------------------------- write
def save(path, surfaces, truth: dict | None = None, name: str | None = None,
         format: str = "geomkit-case/1", overwrite: bool = False,
         units: str | None = None) -> Path:
    """Write surfaces as ``geomkit-case/1`` (default) or ``"geomdl"`` JSON.

    ``units`` (e.g. ``"mm"``) is written as the case's top-level ``units`` field
    (geomdl JSON has no place for it: refused there).  The file is written to a temporary name and renamed into place, so a failure
    never leaves a half-written file; an existing file is kept unless
    ``overwrite=True``.  geomdl JSON cannot hold trims: trimmed surfaces are refused.
    """
    surfaces = as_surfaces(surfaces)
    p = check_target(path, overwrite)
    if units is not None:
        from geomkit.units import canonical_units

        units = canonical_units(units)
    if format == CASE_FORMAT:
        doc = {"format": CASE_FORMAT, "name": name or p.stem,
               "surfaces": [surface_to_dict(s) for s in surfaces], "truth": truth or {}}
        if units is not None:
            doc["units"] = units
    elif format == "geomdl":
        if units is not None:
            raise InvalidInputError("geomdl JSON cannot store units; use "
                                    f"format={CASE_FORMAT!r}", "units")
        if any(s.trim for s in surfaces):
            raise InvalidSurfaceError("geomdl JSON cannot store trim loops; use "
                                      f"format={CASE_FORMAT!r}", "trim")
        data = []
        for s in surfaces:
            nu, nv = s.shape
            cp = {"points": s.control_points.reshape(-1, 3).tolist()}
            if s.is_rational:
                cp["weights"] = s.weights.reshape(-1).tolist()
            data.append({"type": "spline", "rational": s.is_rational, "dimension": 3,
                         "degree_u": s.degree_u, "degree_v": s.degree_v,
                         "knotvector_u": s.knots_u.tolist(),
                         "knotvector_v": s.knots_v.tolist(),
                         "size_u": nu, "size_v": nv, "control_points": cp})
        doc = {"shape": {"type": "surface", "count": len(data), "data": data}}
    else:
        raise InvalidInputError(f"unknown format {format!r}; use {CASE_FORMAT!r} or 'geomdl'",
                                "format")
    return atomic_write(p, lambda fh: fh.write(json.dumps(doc, indent=1).encode("utf-8")))
