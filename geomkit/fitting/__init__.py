"""Geometric feature fitting for CMM data (ISO 10360-6 style).

``fit(points, kind, method)`` fits a plane, line, circle, sphere, cylinder or cone to
(n, 3) points by least squares (``"lsq"``), minimum zone (``"minzone"``, Chebyshev)
or, for circle / sphere / cylinder, the minimum circumscribed or maximum inscribed
feature.  See ``docs/guide_fits.md`` for conventions and optimality statements.
"""

from __future__ import annotations

from geomkit.fitting import _geom as G
from geomkit.fitting._geom import frame as orthonormal_frame
from geomkit.fitting.lsq import lsq_model, make_result
from geomkit.fitting.result import FitResult

__all__ = ["fit", "FitResult", "orthonormal_frame"]


def fit(points, kind, method="lsq"):
    """Fit a geometric feature to points.

    Parameters
    ----------
    points : (n, 3) float
        Measured points (finite).  At least 3 for a plane, 2 for a line, 3 for a
        circle, 4 for a sphere, 5 for a cylinder, 6 for a cone.
    kind : {"plane", "line", "circle", "sphere", "cylinder", "cone"}
        The feature.  A circle is fitted in its least-squares plane.
    method : {"lsq", "minzone", "mincircumscribed", "maxinscribed"}
        Gaussian least squares of orthogonal distances; minimum zone (Chebyshev);
        minimum circumscribed / maximum inscribed (circle, sphere, cylinder only).

    Returns
    -------
    FitResult
        Geometry, signed residuals, form error, contacts and an optimality report.

    Raises
    ------
    InvalidInputError
        Unknown kind or method, a method not defined for the kind, wrong shape,
        non-finite coordinates, too few points.
    DegenerateGeometryError
        Collinear points (plane, circle), coplanar points (sphere), points on a
        line (cylinder, cone), coincident points.

    Examples
    --------
    >>> import numpy as np
    >>> t = np.linspace(0, 2 * np.pi, 8, endpoint=False)
    >>> pts = np.column_stack([np.cos(t), np.sin(t), np.zeros_like(t)])
    >>> r = fit(pts, "circle")
    >>> round(r.radius, 12), r.normal.tolist()
    (1.0, [0.0, 0.0, 1.0])
    """
    P = G.check_request(points, kind, method)
    c0, X, s, Vt = G.centre(P)
    G.check_degenerate(kind, s)
    L = float(s[0] / max(P.shape[0], 1) ** 0.5) or 1.0
    model, ctx, info = lsq_model(kind, X, s, Vt, L)
    contacts = None
    if method != "lsq":
        from geomkit.fitting.minzone import chebyshev_fit
        model, contacts, info = chebyshev_fit(kind, method, model, X, ctx, L)
    return make_result(kind, method, P, c0, X, model, ctx, contacts, info)
