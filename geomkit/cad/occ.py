"""Open CASCADE (cadquery-ocp, optional): availability, shape casts and plain-array ->
Open CASCADE conversions, for the STEP reader and the benchmark oracles
(:mod:`geomkit.bench.oracles`).  Importing this module does not load Open CASCADE."""

from __future__ import annotations

import importlib.util

import numpy as np

#: True when the ``OCP`` package (cadquery-ocp) can be imported. Computed with
#: :func:`importlib.util.find_spec`, so it does not load Open CASCADE.
def find_ocp() -> bool:
    try:
        return importlib.util.find_spec("OCP") is not None
    except (ImportError, ValueError):  # e.g. sys.modules["OCP"] without a spec
        return False


HAVE_OCP: bool = find_ocp()

# Knots closer than this fraction of the knot span are treated as one knot
# (Open CASCADE rejects distinct knots closer than Epsilon(|k|)).
_KNOT_MERGE_RTOL = 1e-12


def require_ocp(feature: str = "this feature"):
    """Import and return the ``OCP`` package, or raise a helpful ImportError.

    Parameters
    ----------
    feature : str
        What needs Open CASCADE; quoted in the error message.

    Returns
    -------
    module
        The ``OCP`` package.

    Raises
    ------
    ImportError
        If cadquery-ocp is not installed.
    """
    try:
        import OCP  # noqa: F401  (lazy: heavy shared libraries)
    except ImportError as exc:  # pragma: no cover - depends on environment
        raise ImportError(
            f"Open CASCADE (cadquery-ocp) is required for {feature}; "
            "pip install 'geomkit[test]'"
        ) from exc
    return OCP


# ---------------------------------------------------------------------------
# plain array -> Open CASCADE conversion helpers
# ---------------------------------------------------------------------------


# cadquery-ocp 8.x (OCCT 8) exposes NCollection arrays as
# ``OCP.collections.Array1_double`` etc. and the TopoDS casts as ``TopoDS.Face``;
# 7.x wheels used ``TColStd_Array1OfReal`` ... and ``TopoDS.Face_s``. These two
# helpers hide the difference (only the 8.x path is exercised in CI here).
_OLD_ARRAY_NAMES = {
    "Array1_double": ("OCP.TColStd", "TColStd_Array1OfReal"),
    "Array1_int": ("OCP.TColStd", "TColStd_Array1OfInteger"),
    "Array2_double": ("OCP.TColStd", "TColStd_Array2OfReal"),
    "Array1_gp_Pnt": ("OCP.TColgp", "TColgp_Array1OfPnt"),
    "Array2_gp_Pnt": ("OCP.TColgp", "TColgp_Array2OfPnt"),
    "Array1_gp_Pnt2d": ("OCP.TColgp", "TColgp_Array1OfPnt2d"),
}


def ocp_array(name: str):
    """Open CASCADE array class by its OCP 8.x name (falls back to the TCol* name)."""
    try:
        import OCP.collections as coll

        return getattr(coll, name)
    except (ImportError, AttributeError):  # pragma: no cover - older OCP
        mod, old = _OLD_ARRAY_NAMES[name]
        return getattr(importlib.import_module(mod), old)


def cast_shape(kind: str, shape):
    """Down-cast a TopoDS_Shape: ``kind`` in {"Face", "Wire", "Edge", "Vertex"}."""
    from OCP.TopoDS import TopoDS

    fn = getattr(TopoDS, kind, None) or getattr(TopoDS, kind + "_s")
    return fn(shape)


def knots_to_occ(knots, degree: int, n_ctrl: int, name: str):
    """Convert a full clamped knot vector to (distinct knots, multiplicities).

    Parameters
    ----------
    knots : (n_ctrl + degree + 1,) array_like of float
        Full, non-decreasing, clamped knot vector.
    degree : int
        Degree ``p >= 1``.
    n_ctrl : int
        Number of control points along this direction.
    name : str
        Used in error messages (e.g. ``"knots_u"``).

    Returns
    -------
    distinct : (m,) ndarray of float
    mults : (m,) ndarray of int
        ``mults[0] == mults[-1] == degree + 1``; interior ``<= degree``.
    """
    k = np.asarray(knots, dtype=np.float64).ravel()
    if degree < 1:
        raise ValueError(f"{name}: degree must be >= 1, got {degree}")
    if k.size != n_ctrl + degree + 1:
        raise ValueError(
            f"{name}: expected n + p + 1 = {n_ctrl} + {degree} + 1 = "
            f"{n_ctrl + degree + 1} knots, got {k.size}"
        )
    if not np.all(np.isfinite(k)):
        raise ValueError(f"{name}: knots must be finite")
    if np.any(np.diff(k) < 0):
        raise ValueError(f"{name}: knots must be non-decreasing")
    span = k[-1] - k[0]
    if not span > 0:
        raise ValueError(f"{name}: knot vector has zero span")
    tol = _KNOT_MERGE_RTOL * span
    distinct = [k[0]]
    mults = [1]
    for x in k[1:]:
        if x - distinct[-1] <= tol:
            mults[-1] += 1
        else:
            distinct.append(x)
            mults.append(1)
    # the last distinct knot must be exactly the last knot (clamped end value)
    distinct[-1] = k[-1]
    if mults[0] != degree + 1 or mults[-1] != degree + 1:
        raise ValueError(
            f"{name}: knot vector must be clamped (first and last knot repeated "
            f"degree + 1 = {degree + 1} times); got end multiplicities "
            f"{mults[0]} and {mults[-1]}"
        )
    if len(mults) > 2 and max(mults[1:-1]) > degree:
        raise ValueError(
            f"{name}: interior knot multiplicity exceeds degree {degree} "
            "(discontinuous spline)"
        )
    return np.asarray(distinct), np.asarray(mults, dtype=np.int64)


def array1_double(values):
    Array1_double = ocp_array("Array1_double")
    values = np.asarray(values, dtype=np.float64).ravel()
    arr = Array1_double(1, int(values.size))
    for i, v in enumerate(values, start=1):
        arr.SetValue(i, float(v))
    return arr


def array1_int(values):
    Array1_int = ocp_array("Array1_int")
    values = np.asarray(values).ravel()
    arr = Array1_int(1, int(values.size))
    for i, v in enumerate(values, start=1):
        arr.SetValue(i, int(v))
    return arr


def gp_pnt(p):
    from OCP.gp import gp_Pnt

    p = np.asarray(p, dtype=np.float64).ravel()
    if p.size != 3:
        raise ValueError(f"expected a 3-D point, got shape {np.shape(p)}")
    return gp_Pnt(float(p[0]), float(p[1]), float(p[2]))


def xyz(p) -> np.ndarray:
    return np.array([p.X(), p.Y(), p.Z()])


def face_compound(shape):
    """The faces of an OCC shape as one compound: distances measured to it are
    distances to the surface (to a solid they are 0 inside it)."""
    from OCP.BRep import BRep_Builder
    from OCP.TopAbs import TopAbs_FACE
    from OCP.TopExp import TopExp_Explorer
    from OCP.TopoDS import TopoDS_Compound

    comp, b = TopoDS_Compound(), BRep_Builder()
    b.MakeCompound(comp)
    ex = TopExp_Explorer(shape, TopAbs_FACE)
    while ex.More():
        b.Add(comp, ex.Current())
        ex.Next()
    return comp
