"""Trim curves: evaluation and inside/outside classification of UV points.

Classification is exact away from the trim curves: the winding number of a UV point
around each loop is computed against the exact rational curves by adaptive
subdivision near the point (see :mod:`geomkit._kernels.trim`).  Only points proven to
lie within ``tol`` of a trim curve are reported as ``ON_BOUNDARY``; the default
``tol`` is ``TRIM_TOL`` (1e-9) times the larger side of the parameter domain.
"""

from __future__ import annotations

import numpy as np

from geomkit._kernels.trim import BOUNDARY, INSIDE, OUTSIDE
from geomkit.nurbs.surface import Surface, check_surface
from geomkit.nurbs.trims import evaluate_trim_curve

__all__ = ["classify_uv", "evaluate_trim_curve", "OUTSIDE", "INSIDE", "ON_BOUNDARY",
           "BOUNDARY"]

ON_BOUNDARY = BOUNDARY


def classify_uv(surface: Surface, uv, tol: float | None = None) -> np.ndarray:
    """Classify parameter points against the trimmed face.

    Parameters
    ----------
    surface : Surface
    uv : (..., 2) float
        Parameter points (may lie outside the domain).
    tol : float, optional
        Boundary band width in UV units; default ``TRIM_TOL * max(domain sides)``.

    Returns
    -------
    (...,) int8
        ``INSIDE`` (1), ``OUTSIDE`` (0) or ``ON_BOUNDARY`` (2).  ``ON_BOUNDARY`` means
        proven within ``tol`` of a trim curve or of the domain edge; ``INSIDE`` and
        ``OUTSIDE`` are exact for every other point.  An untrimmed surface is its
        whole domain.
    """
    return check_surface(surface).classify_uv(uv, tol)
