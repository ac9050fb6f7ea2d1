"""Constructed parts with known datum frames and characteristics for tests/gdt.

Builders return points in a nominal frame (the datum frame of the drawing); ``pose``
and ``place`` move them rigidly anywhere, as a part set on a CMM table.
"""

from __future__ import annotations

import itertools

import numpy as np
from scipy.spatial.transform import Rotation


def pose(seed, offset=500.0):
    """Random rotation matrix and translation of length ``offset``."""
    rng = np.random.default_rng(seed)
    R = Rotation.random(random_state=seed).as_matrix()
    t = rng.normal(size=3)
    return R, offset * t / np.linalg.norm(t)


def place(P, R, t):
    return np.asarray(P, float) @ R.T + t


def grid(nu, nv, a, b):
    u, v = np.meshgrid(np.linspace(0, a, nu), np.linspace(0, b, nv), indexing="ij")
    return u.ravel(), v.ravel()


def box_faces(a=100.0, b=60.0, c=40.0, low=0.3):
    """Points on the faces z = 0 (A), x = 0 (B), y = 0 (C) of the box [0,a]x[0,b]x[0,c]
    with one point pushed ``low`` into the material per face (interior: the
    tangent planes stay the faces).  Outward normals -z, -x, -y.  The datum frame of
    A|B|C has origin 0 and axes x = -X, y = +Y, z = -Z (rows)."""
    u, v = grid(6, 5, a, b)
    A = np.column_stack([u, v, np.zeros_like(u)])
    A = np.vstack([A, [[a / 2, b / 2, low]]])
    u, v = grid(5, 4, b, c)
    B = np.column_stack([np.zeros_like(u), u, v])
    B = np.vstack([B, [[low, b / 2, c / 2]]])
    u, v = grid(5, 3, a, c)
    C = np.column_stack([u, np.zeros_like(u), v])
    C = np.vstack([C, [[a / 2, low, c / 2]]])
    axes = np.array([[-1.0, 0, 0], [0, 1.0, 0], [0, 0, -1.0]])
    return A, B, C, axes


def cylinder(r, z0, z1, n_theta=12, n_z=4, center=(0.0, 0.0), dev=None, phase=0.0):
    """Points on the cylinder x^2 + y^2 = r^2 (+ radial ``dev`` per point)."""
    th = phase + np.linspace(0, 2 * np.pi, n_theta, endpoint=False)
    T, Z = np.meshgrid(th, np.linspace(z0, z1, n_z), indexing="ij")
    T, Z = T.ravel(), Z.ravel()
    rr = r + (0.0 if dev is None else dev(T, Z))
    return np.column_stack([center[0] + rr * np.cos(T), center[1] + rr * np.sin(T), Z])


def alternating(h, k=4):
    """Radial deviation +h / -h alternating around a ring of 2k points."""
    return lambda T, Z: h * np.cos(k * T).round()


def octa_cube(R, h):
    """Sphere points: +h at the 6 octahedron directions, -h at the 8 cube ones, 0
    at 12 edge directions.  Minimum-zone sphericity 2h (any centre shift raises a
    +h point or lowers a -h point)."""
    octa = np.vstack([np.eye(3), -np.eye(3)])
    cube = np.array(list(itertools.product([-1, 1], repeat=3))) / np.sqrt(3)
    edge = np.array([v for v in itertools.product([-1, 0, 1], repeat=3)
                     if sum(map(abs, v)) == 2], float) / np.sqrt(2)
    P = np.vstack([(R + h) * octa, (R - h) * cube, R * edge])
    dev = np.concatenate([np.full(6, h), np.full(8, -h), np.zeros(len(edge))])
    return P, dev


def brute_tangent_width(P, nominal, max_angle_deg=30.0):
    """Oracle: the least max-distance of a plane with every point on its inner side
    (normal within ``max_angle_deg`` of ``nominal``), over planes through 3 points
    and 2 + 2 configurations."""
    best = np.inf
    cosmax = np.cos(np.radians(max_angle_deg))
    n_pts = len(P)
    normals = []
    for i, j, k in itertools.combinations(range(n_pts), 3):
        normals.append(np.cross(P[j] - P[i], P[k] - P[i]))
    for (i, j), (k, m) in itertools.combinations(itertools.combinations(range(n_pts), 2), 2):
        normals.append(np.cross(P[j] - P[i], P[m] - P[k]))
    for n in normals:
        nn = np.linalg.norm(n)
        if nn < 1e-12:
            continue
        n = n / nn
        n = n if n @ nominal > 0 else -n
        if n @ nominal < cosmax:
            continue
        s = P @ n
        best = min(best, s.max() - s.min())
    return best


def brute_width_2d(Q):
    """Oracle: minimum width of 2-D points over lines through two of them."""
    best = np.inf
    for i, j in itertools.combinations(range(len(Q)), 2):
        e = Q[j] - Q[i]
        if np.linalg.norm(e) < 1e-12:
            continue
        u = np.array([e[1], -e[0]]) / np.linalg.norm(e)
        s = Q @ u
        best = min(best, s.max() - s.min())
    return best
