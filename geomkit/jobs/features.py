"""Nominal features of a part's faces: which faces are planes, cylinders, spheres or
cones (and with what geometry), and which faces make one feature.

A CAD file does not say "this is a hole"; a tolerance names faces.  Each face is
sampled exactly (:func:`geomkit.jobs.sample.sample_faces`, outward normals by the
ray vote) and recognised by fitting: a face whose samples lie on a plane, sphere,
cylinder or cone within ``REL_FORM`` x its size is that kind (the exact surface, so
the fit residual is rounding); anything else is ``"freeform"``.  Faces of the same
kind and geometry (coplanar faces with the same outward side, the two halves of a
bore, ...) are one :class:`Feature`.  A cylinder is a ``hole`` when its outward
normals point at its axis, else a ``shaft``; a plane is oriented by its outward
normal.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from geomkit.errors import GeomkitError
from geomkit.fitting import fit
from geomkit.jobs.sample import sample_faces

__all__ = ["Feature", "FaceShape", "face_shapes", "group_features", "REL_FORM"]

#: A face is of a kind when its exact samples fit it within this x the face size.
REL_FORM = 1e-7
#: Geometry agreement for faces to join one feature (x the part size; radians).
REL_SAME, ANG_SAME = 1e-6, 1e-6
#: Exact samples taken on each face for recognition.
SAMPLES = 48


@dataclass
class FaceShape:
    """What one face is: ``kind`` and its geometry (CAD coordinates)."""

    face: int
    kind: str                      # plane, cylinder, sphere, cone, freeform
    points: np.ndarray = field(repr=False)
    normals: np.ndarray = field(repr=False)
    point: np.ndarray | None = None        # plane / cylinder axis point / sphere centre
    direction: np.ndarray | None = None    # plane outward normal / axis
    radius: float | None = None
    half_angle: float | None = None
    internal: bool | None = None           # hole (True) / shaft (False)


@dataclass
class Feature:
    """Faces that make one feature (the same plane, cylinder, sphere or cone)."""

    kind: str
    faces: list
    point: np.ndarray | None = None
    direction: np.ndarray | None = None
    radius: float | None = None
    half_angle: float | None = None
    internal: bool | None = None
    points: np.ndarray = field(default=None, repr=False)   # nominal samples
    normals: np.ndarray = field(default=None, repr=False)

    @property
    def diameter(self):
        return None if self.radius is None else 2.0 * self.radius

    def describe(self) -> str:
        if self.kind == "cylinder":
            return f"{'hole' if self.internal else 'shaft'} d{2 * self.radius:.6g}"
        if self.kind == "sphere":
            return f"sphere d{2 * self.radius:.6g}"
        return self.kind


def _recognise(i, P, N) -> FaceShape:
    L = float(np.linalg.norm(P.max(axis=0) - P.min(axis=0))) or 1.0
    tol = REL_FORM * L
    for kind in ("plane", "sphere", "cylinder", "cone"):
        try:
            r = fit(P, kind)
        except GeomkitError:
            continue
        if not r.form_error <= tol:
            continue
        if kind == "plane":
            n = r.normal if float(N.mean(axis=0) @ r.normal) >= 0 else -r.normal
            return FaceShape(i, kind, P, N, r.point, n)
        if kind == "sphere":
            inside = float(np.mean(np.sum((P - r.center) * N, axis=1))) < 0
            return FaceShape(i, kind, P, N, r.center, None, r.radius, internal=inside)
        if kind == "cylinder":
            rad = (P - r.point) - ((P - r.point) @ r.axis)[:, None] * r.axis
            inside = float(np.mean(np.sum(rad * N, axis=1))) < 0
            return FaceShape(i, kind, P, N, r.point, r.axis, r.radius, internal=inside)
        return FaceShape(i, kind, P, N, r.apex, r.axis, half_angle=r.half_angle)
    return FaceShape(i, "freeform", P, N)


def face_shapes(surfaces, faces, samples: int = SAMPLES, seed: int = 0,
                sampled=None) -> dict:
    """``{face: FaceShape}`` for the given face indices (exact samples, outward
    normals from the whole part; ``sampled``: a :class:`SampledPoints` of these
    faces to use instead of sampling them)."""
    faces = sorted({int(f) for f in faces})
    if not faces:
        return {}
    res = sampled if sampled is not None else sample_faces(surfaces, samples,
                                                           faces=faces, seed=seed)
    out = {}
    for f in faces:
        m = res.face == f
        if m.sum() < 6:
            out[f] = FaceShape(f, "freeform", res.nominal[m], res.normals[m])
            continue
        out[f] = _recognise(f, res.nominal[m], res.normals[m])
    return out


def _same(a: FaceShape, b: FaceShape, L) -> bool:
    if a.kind != b.kind or a.kind == "freeform":
        return False
    tol = REL_SAME * L
    if a.kind == "plane":
        return (float(a.direction @ b.direction) >= math.cos(ANG_SAME)
                and abs(float((b.point - a.point) @ a.direction)) <= tol)
    if a.kind == "sphere":
        return (float(np.linalg.norm(a.point - b.point)) <= tol
                and abs(a.radius - b.radius) <= tol and a.internal == b.internal)
    if abs(float(a.direction @ b.direction)) < math.cos(ANG_SAME):
        return False
    d = b.point - a.point
    off = float(np.linalg.norm(d - (d @ a.direction) * a.direction))
    if a.kind == "cylinder":
        return off <= tol and abs(a.radius - b.radius) <= tol and a.internal == b.internal
    return (float(np.linalg.norm(a.point - b.point)) <= tol
            and abs(a.half_angle - b.half_angle) <= ANG_SAME)


def group_features(shapes: dict, faces, size: float) -> list:
    """The faces (indices into ``shapes``) as features: faces of one kind and the same
    geometry join, in the order of their first face."""
    groups: list = []
    for f in faces:
        s = shapes[f]
        for g in groups:
            if _same(shapes[g[0]], s, size):
                g.append(f)
                break
        else:
            groups.append([f])
    out = []
    for g in groups:
        s = shapes[g[0]]
        P = np.vstack([shapes[f].points for f in g])
        N = np.vstack([shapes[f].normals for f in g])
        point, direction = s.point, s.direction
        if len(g) > 1 and s.kind in ("plane", "cylinder", "sphere", "cone"):
            r = fit(P, s.kind)          # one geometry for the joined faces
            if s.kind == "plane":
                point = r.point
                direction = r.normal if float(r.normal @ s.direction) >= 0 else -r.normal
            elif s.kind == "cylinder":
                point, direction = r.point, r.axis
            elif s.kind == "sphere":
                point = r.center
        out.append(Feature(s.kind, list(g), point, direction, s.radius, s.half_angle,
                           s.internal, P, N))
    return out
