"""Input validation helpers shared by the types and the public functions.

Each helper converts its argument to a C-contiguous float64 (or int) array and raises
an :class:`~geomkit.errors.InvalidInputError` subclass naming the field when the value
is unusable.
"""

from __future__ import annotations

import math
import numbers

import numpy as np

from geomkit.errors import InvalidInputError


def as_int(value, field, minimum=None, error=InvalidInputError) -> int:
    if isinstance(value, bool) or not isinstance(value, (numbers.Integral, np.integer)):
        if isinstance(value, (float, np.floating)) and float(value).is_integer():
            value = int(value)
        else:
            raise error(f"expected an integer, got {value!r}", field)
    value = int(value)
    if minimum is not None and value < minimum:
        raise error(f"must be >= {minimum}, got {value}", field)
    return value


def as_float_array(value, field, shape=None, error=InvalidInputError) -> np.ndarray:
    """Convert to a finite float64 array; ``shape`` may contain ``None`` wildcards."""
    try:
        arr = np.array(value, dtype=np.float64, order="C")
    except (TypeError, ValueError) as exc:
        raise error(f"expected numbers, could not convert ({exc})", field) from None
    if shape is not None:
        ok = arr.ndim == len(shape) and all(
            want is None or want == got for want, got in zip(shape, arr.shape)
        )
        if not ok:
            want = "(" + ", ".join("n" if s is None else str(s) for s in shape) + \
                ("," if len(shape) == 1 else "") + ")"
            raise error(f"expected shape {want}, got {arr.shape}", field)
    bad = ~np.isfinite(arr)
    if bad.any():
        idx = tuple(int(i) for i in np.argwhere(bad)[0])
        raise error(f"non-finite value {float(arr[idx])!r} at index {idx}", field)
    return arr


def as_points(value, dim, field) -> tuple[np.ndarray, tuple]:
    """Accept (..., dim) points; return a (n, dim) array and the leading shape."""
    arr = as_float_array(value, field)
    if arr.ndim == 0 or arr.shape[-1] != dim:
        raise InvalidInputError(f"expected an array of shape (..., {dim}), got {arr.shape}", field)
    lead = arr.shape[:-1]
    return np.ascontiguousarray(arr.reshape(-1, dim)), lead


_SHORT_KNOTS = 64
"""Knot vectors up to this length are first checked in plain Python (a reader builds
thousands of short ones; numpy's per-call cost is then most of the check)."""


def clamped_knots_ok(U: list, degree: int, count: int) -> bool:
    """Whether the knots ``U`` (a list of floats) are clamped and pass every check of
    :func:`check_knots` for ``count`` control points of ``degree``, checked in plain
    Python (short vectors only; False for anything else)."""
    return (len(U) == count + degree + 1 <= _SHORT_KNOTS and math.isfinite(sum(U))
            and U[0] == U[degree] and U[-1] == U[-degree - 1]
            and _plain_knots(U, degree, count))


def _plain_knots(U: list, degree: int, count: int) -> bool:
    """Whether the (finite, right-length) knots ``U`` pass every check of
    :func:`check_knots`; False sends them to its checks, which name the fault."""
    lo, hi = U[degree], U[count]
    if not hi > lo:
        return False
    run, prev = 0, None
    for j, x in enumerate(U):
        if prev is not None and x < prev:
            return False
        run = run + 1 if x == prev else 1
        prev = x
        if run > degree + 1 or (run > degree and lo < x < hi):
            return False
    return True


def check_knots(knots, degree, count, field, error) -> np.ndarray:
    """Validate a full knot vector for ``count`` control points of ``degree``.

    Checks length (count + degree + 1), finiteness, non-decreasing order, interior
    multiplicity <= degree and a non-empty domain.  Unclamped ends are allowed here.
    """
    U = as_float_array(knots, field, shape=(None,), error=error)
    need = count + degree + 1
    if U.shape[0] != need:
        raise error(
            f"length {U.shape[0]} but must be n + p + 1 = {count} + {degree} + 1 = {need} "
            f"({count} control points, degree {degree})",
            field,
        )
    if need <= _SHORT_KNOTS and _plain_knots(U.tolist(), degree, count):
        return U
    dec = np.nonzero(np.diff(U) < 0)[0]
    if dec.size:
        i = int(dec[0])
        raise error(f"knots must be non-decreasing, but knot[{i + 1}] = {float(U[i + 1])!r} < "
                    f"knot[{i}] = {float(U[i])!r}", field)
    lo, hi = float(U[degree]), float(U[count])
    if not hi > lo:
        raise error(f"empty parameter domain [{lo!r}, {hi!r}] (knot[p] must be < knot[n])",
                    field)
    # U is non-decreasing: each distinct knot is one run, its length the multiplicity
    starts = np.concatenate(([0], np.flatnonzero(np.diff(U) != 0) + 1))
    mult = np.diff(np.append(starts, U.shape[0]))
    for end, r in (("first", 0), ("last", -1)):
        if mult[r] > degree + 1:
            raise error(f"the {end} knot {float(U[starts[r]])!r} has multiplicity "
                        f"{int(mult[r])}; at most degree + 1 = {degree + 1} (a basis "
                        "function would vanish)", field)
    vals = U[starts]
    bad = np.flatnonzero((vals > lo) & (vals < hi) & (mult > degree))
    if bad.size:
        k = int(bad[0])
        raise error(f"interior knot {float(vals[k])!r} has multiplicity {int(mult[k])} > "
                    f"degree {degree} (the surface would be discontinuous)", field)
    return U


def as_mesh_arrays(mesh, field="mesh"):
    """``(vertices (n, 3) float, faces (m, 3) int64, face tags or None)`` of a
    geomkit.Mesh, a trimesh.Trimesh or a (vertices, faces) pair, validated."""
    tags = None
    if hasattr(mesh, "vertices") and hasattr(mesh, "faces"):
        V, F = mesh.vertices, mesh.faces
        tags = getattr(mesh, "face_surface", None)
    elif isinstance(mesh, (tuple, list)) and len(mesh) == 2:
        V, F = mesh
    else:
        raise InvalidInputError("expected a geomkit.Mesh, a trimesh.Trimesh or a "
                                f"(vertices, faces) pair, got {type(mesh).__name__}", field)
    V = as_float_array(V, f"{field}.vertices", shape=(None, 3))
    try:
        Fa = np.asarray(F)
    except Exception as exc:  # pragma: no cover - exotic inputs
        raise InvalidInputError(f"could not read faces ({exc})", f"{field}.faces") from None
    if Fa.ndim != 2 or Fa.shape[1] != 3 or Fa.shape[0] == 0:
        raise InvalidInputError(f"expected shape (m, 3) with m >= 1, got {Fa.shape}",
                                f"{field}.faces")
    if not np.issubdtype(Fa.dtype, np.integer):
        raise InvalidInputError(f"expected integer indices, got dtype {Fa.dtype}",
                                f"{field}.faces")
    Fa = np.ascontiguousarray(Fa, dtype=np.int64)
    if Fa.min() < 0 or Fa.max() >= V.shape[0]:
        raise InvalidInputError(f"indices must be in [0, {V.shape[0]}), got "
                                f"[{Fa.min()}, {Fa.max()}]", f"{field}.faces")
    return V, Fa, tags
