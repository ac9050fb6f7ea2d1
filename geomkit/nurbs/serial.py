"""Plain-data forms of a surface: the ``geomkit-case/1`` dict and geomdl objects.

These functions read a surface's attributes and build plain data, or read plain data
and return the keyword arguments of :class:`~geomkit.Surface`; they hold no reference
to the class (it calls them), so the import graph stays one-way.
"""

from __future__ import annotations

import numpy as np

from geomkit.errors import InvalidInputError

__all__ = ["surface_to_dict", "surface_to_geomdl", "geomdl_kwargs"]


def surface_to_dict(s) -> dict:
    """The ``geomkit-case/1`` form of surface ``s``."""
    d = {"degree_u": s.degree_u, "degree_v": s.degree_v,
         "knots_u": s.knots_u.tolist(), "knots_v": s.knots_v.tolist(),
         "control_points": s.control_points.tolist()}
    if s.weights is not None:
        d["weights"] = s.weights.tolist()
    if s.trim:
        d["trim"] = [loop.to_case() for loop in s.trim]
    if s.name:
        d["name"] = s.name
    if s.approx_error:
        d["approx_error"] = s.approx_error
    return d


def surface_to_geomdl(s):
    """A geomdl ``BSpline.Surface`` or ``NURBS.Surface`` for ``s`` (trims are not carried)."""
    from geomdl import BSpline, NURBS  # optional at import time: geomdl is slow to import

    nu, nv = s.shape
    g = NURBS.Surface() if s.is_rational else BSpline.Surface()
    g.degree_u = s.degree_u
    g.degree_v = s.degree_v
    g.ctrlpts_size_u = nu
    g.ctrlpts_size_v = nv
    g.ctrlpts = s.control_points.reshape(-1, 3).tolist()
    if s.is_rational:
        g.weights = s.weights.reshape(-1).tolist()
    g.knotvector_u = s.knots_u.tolist()
    g.knotvector_v = s.knots_v.tolist()
    return g


def geomdl_kwargs(g) -> dict:
    """The :class:`~geomkit.Surface` arguments of a geomdl surface object."""
    try:
        nu, nv = g.ctrlpts_size_u, g.ctrlpts_size_v
        P = np.asarray(g.ctrlpts, dtype=float).reshape(nu, nv, -1)
        w = getattr(g, "weights", None)
        degrees = (g.degree_u, g.degree_v)
        knots = (list(g.knotvector_u), list(g.knotvector_v))
    except Exception as exc:  # geomdl raises many kinds
        raise InvalidInputError(f"not a geomdl surface ({exc})", "geomdl") from None
    if P.shape[2] != 3:
        raise InvalidInputError(f"expected 3-D control points, got {P.shape[2]}-D", "geomdl")
    weights = np.asarray(w, float).reshape(nu, nv) if w else None
    return {"degree_u": degrees[0], "degree_v": degrees[1], "knots_u": knots[0],
            "knots_v": knots[1], "control_points": P, "weights": weights}
