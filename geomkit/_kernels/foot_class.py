"""Class of a projection foot on its trimmed face (INSIDE / OUTSIDE / BOUNDARY), and
the cheap proof that a foot is INSIDE (a deep cell of the surface's parameter grid,
:func:`geomkit.projection_trim.cert_boxes`) that spares the classification."""

from __future__ import annotations

import numpy as np

from .numba_ext.policy import jit
from .trim import BOUNDARY, INSIDE, OUTSIDE, classify_point


@jit
def _foot_class(tseg, tdeg, tloop, toff, ttol, dom, s, u, v, winding, stack, depths, left,
                right):
    """INSIDE / OUTSIDE / BOUNDARY of the foot (u, v) on trimmed surface ``s``: the
    domain rectangle, then the trim loops (:func:`geomkit._kernels.trim.classify_point`)
    — the same answer as :func:`geomkit.trimming.classify_uv` with its default band
    ``ttol[s]``."""
    tol = ttol[s]
    dd = min(min(u - dom[s, 0], dom[s, 1] - u), min(v - dom[s, 2], dom[s, 3] - v))
    if dd < -tol:
        return OUTSIDE
    out = BOUNDARY if dd <= tol else INSIDE
    o = toff[s, 0]
    n = toff[s, 1]
    if n == 0:
        return out
    res = classify_point(tseg[o:o + n], tdeg[o:o + n], tloop[o:o + n], toff[s, 2], u, v,
                         tol, winding, stack, depths, left, right)
    if res == OUTSIDE:
        return OUTSIDE
    if res == BOUNDARY:
        return BOUNDARY
    return out


@jit
def _deep_cell(gdeep, goff, dom, s, u, v):
    """(u, v) lies in a deep cell of trimmed surface ``s``'s grid (``goff[s]`` =
    (offset into ``gdeep``, cells per direction), 0 cells: none): inside the face
    beyond the classification band (:func:`geomkit.projection_trim._deep_cells`)."""
    G = goff[s, 1]
    if G == 0:
        return False
    fu = (u - dom[s, 0]) / (dom[s, 1] - dom[s, 0]) * G
    fv = (v - dom[s, 2]) / (dom[s, 3] - dom[s, 2]) * G
    if not (fu >= 0.0 and fu < G and fv >= 0.0 and fv < G):
        return False
    return gdeep[goff[s, 0] + np.int64(fu) * G + np.int64(fv)] != 0
