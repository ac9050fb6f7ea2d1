"""Loose faces: faces of a STEP file outside its solids (an ``OPEN_SHELL`` of a
surface model beside a ``CLOSED_SHELL``), and which of them duplicate a solid's face.

CAD systems export construction or reference surfaces beside the solid, and some lie
exactly on one of its faces (NIST CTC-05's face 208 on face 2).  Such a duplicate
doubles the material boundary: it is crossed twice by a ray, it ties with the solid's
face for the nearest foot, and a section through it yields the same curve twice.  The
reader lists loose faces (``IgesResult.loose``) and their duplicates
(``IgesResult.duplicates``: loose face -> the solid faces it lies on); jobs that
need one boundary leave the duplicates out.

A loose face duplicates the solid when every one of its sample points (a UV grid
inside its trim, and the ends of its outer loop's pieces) lies within ``tol`` of the
solid's faces.  Only the solid faces whose control nets' boxes (which hold their
surfaces) come within ``tol`` of a loose face's samples are looked at: first by
Gauss-Newton on each of them from the nearest of a grid of its points, which shows a
sample within ``tol`` by a point of the face (inside its trim) that near; what that
does not show is projected exactly (:func:`geomkit.project_points`), which also
decides that a face is no duplicate.
"""

from __future__ import annotations

import numpy as np

from geomkit.cad.edgeproj import SurfaceInverse
from geomkit.nurbs.trimming import BOUNDARY, INSIDE
from geomkit.query.projection_part import project_points

__all__ = ["duplicate_faces", "GRID"]

#: UV grid per direction sampled on a loose face.
GRID = 12


def _samples(s) -> np.ndarray:
    """Points of a face: a UV grid inside its trim and the ends of its outer loop's
    pieces (on the loop: the trim curves are clamped)."""
    (u0, u1), (v0, v1) = s.domain
    g = (np.arange(GRID) + 0.5) / GRID
    U, V = np.meshgrid(u0 + g * (u1 - u0), v0 + g * (v1 - v0), indexing="ij")
    uv = np.column_stack([U.ravel(), V.ravel()])
    if s.trim:
        uv = uv[np.asarray(s.classify_uv(uv)) == INSIDE]
        ends = [np.asarray(c.control_points)[0, :2] for c in s.trim[0].pieces]
        if ends:
            uv = np.vstack([uv, np.array(ends)])
    if uv.shape[0] == 0:
        return np.zeros((0, 3))
    return s.evaluate(uv)


def duplicate_faces(surfaces, loose, tol) -> dict:
    """``{loose position: [solid positions]}`` for the loose faces (positions in
    ``surfaces``) whose samples all lie within ``tol`` of the other (solid) faces."""
    loose = [int(i) for i in loose]
    solid = [i for i in range(len(surfaces)) if i not in set(loose)]
    if not loose or not solid:
        return {}
    boxes = np.array([surfaces[i].bounds for i in solid])  # the control nets' boxes
    lo, hi = boxes[:, 0], boxes[:, 1]
    out = {}
    for i in loose:
        X = _samples(surfaces[i])
        if X.shape[0] == 0:
            continue
        # every sample must be within tol of some solid face: the faces whose boxes
        # are that near the samples' box are the only candidates
        near = np.all((lo <= X.max(axis=0) + tol) & (hi >= X.min(axis=0) - tol), axis=1)
        cand = np.nonzero(near)[0]
        if not cand.size:
            continue
        faces = [surfaces[solid[k]] for k in cand]
        on = _shown_on(faces, X, tol)
        if on is not None:
            out[i] = sorted({solid[int(cand[k])] for k in on})
            continue
        pr = project_points(faces, X, max_distance=10.0 * tol)
        d = pr.distance
        if np.all(np.isfinite(d)) and float(d.max()) <= tol:
            out[i] = sorted({solid[int(cand[k])] for k in np.unique(pr.surface) if k >= 0})
    return out


def _shown_on(faces, X, tol):
    """The positions in ``faces`` of the faces that hold, each, a point within ``tol``
    of some of the points ``X``, every point being so shown (a Gauss-Newton foot
    inside the face's trim: its distance bounds the true one from above), else None
    (the exact projection decides)."""
    left = np.arange(len(X))
    on = []
    for k, s in enumerate(faces):
        uv, d = SurfaceInverse(s).newton(X[left])
        near = d <= tol
        if s.trim and near.any():
            cls = np.asarray(s.classify_uv(uv[near]))
            near[np.flatnonzero(near)[(cls != INSIDE) & (cls != BOUNDARY)]] = False
        if near.any():
            on.append(k)
            left = left[~near]
            if not left.size:
                return on
    return None
