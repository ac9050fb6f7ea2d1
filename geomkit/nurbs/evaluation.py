"""Exact evaluation of NURBS surfaces: points, partial derivatives, unit normals.

Every function takes a :class:`~geomkit.Surface` and parameters ``uv`` of shape
(..., 2) and returns arrays with the same leading shape; a single (2,) parameter pair
is the n = 1 case.  Work runs in parallel numba kernels (The NURBS Book A2.1–A2.3,
A3.5, A3.6, A4.3, A4.4).

Parameters within ``DOMAIN_TOL`` of the domain are clamped onto it; anything further
out raises :class:`~geomkit.errors.InvalidInputError` naming the first offending row.
"""

from __future__ import annotations

import numpy as np

from geomkit import tolerances as tols
from geomkit._kernels import surface as K
from geomkit.validate import as_int, as_points
from geomkit.errors import InvalidInputError
from geomkit.nurbs.surface import Surface

__all__ = ["evaluate", "derivatives", "normals", "check_uv", "DEGENERATE_REL"]

DEGENERATE_REL = 1e-12
"""``|Su x Sv| <= DEGENERATE_REL * max(|Su|, |Sv|)**2`` marks a degenerate point (pole)."""

NORMAL_REGULAR, NORMAL_LIMIT, NORMAL_NUDGED, NORMAL_UNDEFINED = 0, 1, 2, 3


def check_uv(surface: Surface, uv, field: str = "uv") -> tuple[np.ndarray, tuple]:
    """Validate parameters: returns (n, 2) float64 clamped to the domain, leading shape."""
    if not isinstance(surface, Surface):
        raise InvalidInputError(f"expected a geomkit.Surface, got {type(surface).__name__}",
                                "surface")
    arr, lead = as_points(uv, 2, field)
    (u0, u1), (v0, v1) = surface.domain
    eu = tols.DOMAIN_TOL * (u1 - u0)
    ev = tols.DOMAIN_TOL * (v1 - v0)
    bad = ((arr[:, 0] < u0 - eu) | (arr[:, 0] > u1 + eu)
           | (arr[:, 1] < v0 - ev) | (arr[:, 1] > v1 + ev))
    if bad.any():
        i = int(np.argmax(bad))
        raise InvalidInputError(
            f"row {i} = ({arr[i, 0]!r}, {arr[i, 1]!r}) is outside the parameter domain "
            f"[{u0}, {u1}] x [{v0}, {v1}] ({int(bad.sum())} row(s) outside)", field)
    np.clip(arr[:, 0], u0, u1, out=arr[:, 0])
    np.clip(arr[:, 1], v0, v1, out=arr[:, 1])
    return arr, lead


def evaluate(surface: Surface, uv) -> np.ndarray:
    """Surface points.

    Parameters
    ----------
    surface : Surface
    uv : (..., 2) float
        Parameters in the surface domain.

    Returns
    -------
    (..., 3) float
        S(u, v), exact up to floating-point rounding (A4.3 on homogeneous points).
    """
    arr, lead = check_uv(surface, uv)
    out = np.empty((arr.shape[0], 3))
    if arr.shape[0]:
        K.surface_points(surface.homogeneous, surface.degree_u, surface.degree_v,
                         surface.knots_u, surface.knots_v, arr, out)
    return out.reshape(lead + (3,))


def derivatives(surface: Surface, uv, order: int = 1) -> np.ndarray:
    """Partial derivatives up to ``order`` in each parameter.

    Returns
    -------
    (..., order+1, order+1, 3) float
        ``D[..., k, l, :]`` = d^(k+l) S / du^k dv^l at each parameter pair, for every
        ``0 <= k, l <= order`` (so ``D[..., 0, 0]`` is the point, ``D[..., 1, 0]`` is
        S_u, ``D[..., 1, 1]`` is S_uv).  Rational surfaces use the quotient rule
        (The NURBS Book A4.4).  On a knot the derivative is the one from the right
        (the left one at the upper domain end); across a C0 knot (a crease) the two
        one-sided derivatives differ.
    """
    order = as_int(order, "order", minimum=0)
    if order > 8:
        raise InvalidInputError(f"order must be <= 8, got {order}", "order")
    arr, lead = check_uv(surface, uv)
    out = np.empty((arr.shape[0], order + 1, order + 1, 3))
    if arr.shape[0]:
        K.surface_derivatives(surface.homogeneous, surface.degree_u, surface.degree_v,
                              surface.knots_u, surface.knots_v, arr, order, out)
    return out.reshape(lead + (order + 1, order + 1, 3))


def normals(surface: Surface, uv, return_status: bool = False):
    """Unit normals ``S_u x S_v / |S_u x S_v|``.

    At degenerate points (a pole, where a collapsed control row makes ``S_u`` or
    ``S_v`` vanish) the normal is the limit from inside the domain, computed from the
    mixed derivative (``S_u ~ h S_uv`` as the distance ``h`` to the collapsed row goes
    to 0).  If that is degenerate too, the normal is taken at parameters nudged toward
    the domain centre by at most 1e-9 ... 1e+2 relative steps.

    Parameters
    ----------
    surface : Surface
    uv : (..., 2) float
    return_status : bool
        Also return a (...,) int8 array: 0 regular, 1 limit normal at a degenerate
        point, 2 normal from nudged parameters, 3 undefined (the normal is then 0,
        which only happens on a surface that collapses to a curve or point).

    Returns
    -------
    (..., 3) float, unit vectors (and the status array when asked).
    """
    arr, lead = check_uv(surface, uv)
    out = np.empty((arr.shape[0], 3))
    status = np.zeros(arr.shape[0], dtype=np.int8)
    (u0, u1), (v0, v1) = surface.domain
    if arr.shape[0]:
        K.surface_normals(surface.homogeneous, surface.degree_u, surface.degree_v,
                          surface.knots_u, surface.knots_v, arr, u0, u1, v0, v1,
                          DEGENERATE_REL, out, status)
    out = out.reshape(lead + (3,))
    if return_status:
        return out, status.reshape(lead)
    return out
