"""Exact evaluation of NURBS surfaces: points, partial derivatives, unit normals.

Every function takes a :class:`~geomkit.Surface` and parameters ``uv`` of shape
(..., 2) and returns arrays with the same leading shape; a single (2,) parameter pair
is the n = 1 case.  Work runs in parallel numba kernels (The NURBS Book A2.1–A2.3,
A3.5, A3.6, A4.3, A4.4), called by the :class:`~geomkit.Surface` methods of the same
names.

Parameters within ``DOMAIN_TOL`` of the domain are clamped onto it; anything further
out raises :class:`~geomkit.errors.InvalidInputError` naming the first offending row.
"""

from __future__ import annotations

import numpy as np

from geomkit.nurbs import surface as _surface
from geomkit.nurbs.surface import (NORMAL_LIMIT, NORMAL_NUDGED, NORMAL_REGULAR,
                                   NORMAL_UNDEFINED, Surface, check_surface)

__all__ = ["evaluate", "derivatives", "normals", "check_uv",
           "NORMAL_REGULAR", "NORMAL_LIMIT", "NORMAL_NUDGED", "NORMAL_UNDEFINED"]


def check_uv(surface: Surface, uv, field: str = "uv") -> tuple[np.ndarray, tuple]:
    """Validate parameters: returns (n, 2) float64 clamped to the domain, leading shape."""
    return _surface.check_uv(check_surface(surface), uv, field)


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
        S(u, v), exact up to floating-point rounding (The NURBS Book A4.3 on
        homogeneous points).
    """
    return check_surface(surface).evaluate(uv)


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
    return check_surface(surface).derivatives(uv, order)


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
    return check_surface(surface).normals(uv, return_status)
