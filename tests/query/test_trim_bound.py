"""The candidate mesh's bounds near trim curves (projection of points onto several
trimmed faces).

A real part (the AS1 assembly, CAx-IF's STEP test model) gave a wrong nearest face:
a point under a disk face sitting above a plate's round hole projected onto the
hole's edge (1.614) instead of the disk (1.590, an interior foot).  The plate's mesh
triangles along the hole end at the trim polyline, whose chords cut into the hole:
their ``d(x, t) + e_t`` (measured on the parametric gap) was taken as an upper bound
of the distance to the plate and pruned the disk's triangles.  The boundary
triangles now carry the trim polyline's 3-D chord error too.  Rebuilt here from
closed forms (planes and exact circles), with the per-face minimum as the oracle.
"""

from __future__ import annotations

import numpy as np

import geomkit

C = np.array([132.5, 88.0])  # centre of the hole and of the disk above it


def _plane(x0, x1, y0, y1, z, trim=None, name=None):
    P = [[[x0, y0, z], [x0, y1, z]], [[x1, y0, z], [x1, y1, z]]]
    return geomkit.Surface(1, 1, [x0, x0, x1, x1], [y0, y0, y1, y1], P, trim=trim,
                           name=name)


def _circle(r, clockwise=False):
    """Exact circle of radius ``r`` about ``C`` in (u, v) = (x, y): rational quadratic,
    nine control points."""
    s = np.sqrt(0.5)
    d = np.array([[1, 0], [1, 1], [0, 1], [-1, 1], [-1, 0], [-1, -1], [0, -1], [1, -1],
                  [1, 0]], float)
    w = [1, s, 1, s, 1, s, 1, s, 1]
    if clockwise:
        d, w = d[::-1], w[::-1]
    return {"degree": 2, "knots": [0, 0, 0, 1, 1, 2, 2, 3, 3, 4, 4, 4],
            "control_points": (C + r * d).tolist(), "weights": list(w)}


def _scene(hole=5.0, disk=7.5):
    floor = _plane(0, 180, 0, 150, 20, name="floor")  # makes the model (and mesh tol) large
    x0, x1, y0, y1 = 122.5, 165, 25, 125
    box = [[x0, y0], [x1, y0], [x1, y1], [x0, y1], [x0, y0]]
    plate = _plane(x0, x1, y0, y1, 30, trim=[box, _circle(hole, clockwise=True)],
                   name="plate")
    top = _plane(C[0] - disk, C[0] + disk, C[1] - disk, C[1] + disk, 33,
                 trim=[_circle(disk)], name="disk")
    return [floor, plate, top]


def _per_face_min(surfaces, P):
    return np.min([geomkit.project_points(s, P).distance for s in surfaces], axis=0)


def test_disk_above_a_hole_is_the_nearest_face():
    S = _scene()
    P = np.array([[C[0] - 4.17, C[1] - 0.64, 31.41]])  # under the disk, over the hole
    pr = geomkit.project_points(S, P)
    assert pr.surface[0] == 2 and pr.status[0] == geomkit.query.results.INTERIOR
    assert abs(pr.distance[0] - 1.59) < 1e-12
    assert pr.lower_bound[0] <= pr.distance[0]


def test_points_around_trim_curves_match_the_per_face_minimum():
    """Points between the plate and the disk, around the hole's rim and the disk's
    edge: the multi-face answer equals the per-face minimum, and every lower bound
    holds."""
    S = _scene()
    rng = np.random.default_rng(7)
    n = 600
    r = rng.uniform(0, 10, n)
    a = rng.uniform(0, 2 * np.pi, n)
    P = np.column_stack([C[0] + r * np.cos(a), C[1] + r * np.sin(a), rng.uniform(28, 35, n)])
    pr = geomkit.project_points(S, P)
    ref = _per_face_min(S, P)
    assert np.abs(pr.distance - ref).max() < 1e-9
    assert np.all(pr.lower_bound <= pr.distance + 1e-12)
