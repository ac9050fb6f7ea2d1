"""Features with known solutions for the fit tests (and the fit benchmark's twin).

Every builder returns points in a local frame (axis / normal = +z, centre at the
origin) with outward unit normals; :func:`place` moves them rigidly anywhere.
"""

from __future__ import annotations

import numpy as np
from scipy.spatial.transform import Rotation


def pose(seed, offset=1e3):
    """A random rotation matrix and a translation of length ``offset``."""
    rng = np.random.default_rng(seed)
    R = Rotation.random(random_state=seed).as_matrix()
    t = rng.normal(size=3)
    return R, offset * t / np.linalg.norm(t)


def place(P, R, t):
    return P @ R.T + t


def plane(n, rng, size=10.0):
    xy = rng.uniform(-size, size, (n, 2))
    P = np.column_stack([xy, np.zeros(n)])
    N = np.tile([0.0, 0.0, 1.0], (n, 1))
    return P, N


def circle(n, rng, r=5.0):
    t = rng.uniform(0, 2 * np.pi, n)
    N = np.column_stack([np.cos(t), np.sin(t), np.zeros(n)])
    return r * N, N


def sphere(n, rng, r=7.0):
    N = rng.normal(size=(n, 3))
    N /= np.linalg.norm(N, axis=1)[:, None]
    return r * N, N


def cylinder(n, rng, r=20.0, half=50.0):
    t = rng.uniform(0, 2 * np.pi, n)
    N = np.column_stack([np.cos(t), np.sin(t), np.zeros(n)])
    P = r * N + np.column_stack([np.zeros((n, 2)), rng.uniform(-half, half, n)])
    return P, N


def cone(n, rng, phi=0.3, h0=10.0, h1=40.0):
    """Apex at the origin, axis +z, half-angle phi, heights h0..h1."""
    t = rng.uniform(0, 2 * np.pi, n)
    h = rng.uniform(h0, h1, n)
    c, s = np.cos(t), np.sin(t)
    P = np.column_stack([h * np.tan(phi) * c, h * np.tan(phi) * s, h])
    N = np.column_stack([np.cos(phi) * c, np.cos(phi) * s, -np.sin(phi) * np.ones(n)])
    return P, N


def line(n, rng, half=30.0):
    z = rng.uniform(-half, half, n)
    return np.column_stack([np.zeros((n, 2)), z]), None


BUILDERS = {"plane": plane, "circle": circle, "sphere": sphere, "cylinder": cylinder,
            "cone": cone, "line": line}


def symmetric(P, N, h, rng):
    """Each point twice, displaced +h and -h along its normal (LSQ = nominal)."""
    dh = h * rng.uniform(0.2, 1.0, P.shape[0])
    return np.vstack([P + dh[:, None] * N, P - dh[:, None] * N])


def truth(kind, R, t, **kw):
    """Known geometry after :func:`place` with (R, t), for the default builders."""
    z = R[:, 2]
    if kind == "plane":
        return {"point": t, "normal": z}
    if kind == "line":
        return {"point": t, "direction": z}
    if kind == "circle":
        return {"center": t, "normal": z, "radius": kw.get("r", 5.0)}
    if kind == "sphere":
        return {"center": t, "radius": kw.get("r", 7.0)}
    if kind == "cylinder":
        return {"point": t, "axis": z, "radius": kw.get("r", 20.0)}
    return {"apex": t, "axis": z, "half_angle": kw.get("phi", 0.3)}


def geometry_error(res, want, size):
    """Worst error of ``res`` against ``want``: positions and radii over ``size``,
    directions in radians (undirected unless it is a cone axis).  Axis points are
    compared as lines (distance of the wanted point to the fitted axis)."""
    worst = 0.0
    for k, v in want.items():
        got = getattr(res, k)
        if k in ("normal", "direction", "axis"):
            d = float(np.dot(got, v))
            if res.kind != "cone":
                d = abs(d)
            err = float(np.arccos(min(1.0, d))) if d < 1 - 1e-8 else \
                float(np.linalg.norm(np.cross(got, v)))
            if res.kind == "cone" and d < 0:
                err = np.pi
        elif k == "half_angle":
            err = abs(got - v)
        elif k == "point" and res.kind in ("line", "cylinder"):
            w = want.get("axis", want.get("direction"))
            q = v - got
            err = float(np.linalg.norm(q - (q @ w) * w)) / size
        elif k == "point" and res.kind == "plane":
            err = abs(float((got - v) @ want["normal"])) / size
        else:
            err = float(np.linalg.norm(np.asarray(got) - v)) / size
        worst = max(worst, err)
    return worst
