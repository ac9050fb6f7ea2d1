"""Position (ISO 1101:2017 18.12, as understood; ASME Y14.5-2018 section 10) of an
axis, a centre point or a point, relative to a datum frame, with the maximum /
least material modifiers (ISO 2692:2021 / ASME Y14.5-2018 section 10 bonus tolerance,
as understood).

The true position is given in datum coordinates (the basic dimensions of the
drawing); the measured points are in the part coordinates of the frame.
"""

from __future__ import annotations


import numpy as np
from scipy.optimize import linprog
from scipy.spatial.transform import Rotation

from geomkit.errors import InvalidInputError
from geomkit.fitting import fit
from geomkit.gdt._common import (Characteristic, check_choice, check_direction,
                                 check_points, check_tol, perp_basis, reject)
from geomkit.gdt.datums import DatumFrame
from geomkit.validate import as_float_array

__all__ = ["position", "mmc_bonus", "float_pattern"]

FEATURES = ("hole", "shaft", "sphere", "circle", "point")
_MATING = {"hole": "maxinscribed", "shaft": "mincircumscribed"}
_MINMAT = {"hole": "mincircumscribed", "shaft": "maxinscribed"}
#: float_pattern: linear programmes solved at most, and the largest rotation of one.
MAX_FLOAT_ITER, ROT_STEP = 8, 0.05


def mmc_bonus(feature, material, actual, size_limits):
    """Bonus tolerance of a size feature.

    Parameters
    ----------
    feature : {"hole", "shaft"}
    material : {"MMC", "LMC"}
    actual : float
        MMC: the actual mating size (hole: largest inscribed diameter, shaft:
        smallest circumscribed); LMC: the actual minimum material size (hole:
        smallest circumscribed, shaft: largest inscribed).
    size_limits : (2,) float
        (smallest, largest) permitted diameter.

    Returns
    -------
    bonus : float
        |actual - MMC size| (MMC) or |actual - LMC size| (LMC) when the actual size
        is on the permitted side of it; negative when it violates that limit (the
        feature then fails).  MMC size: the smallest hole / the largest shaft; LMC
        size the other limit.
    """
    check_choice(feature, ("hole", "shaft"), "feature")
    check_choice(material, ("MMC", "LMC"), "material")
    lo, hi = as_float_array(size_limits, "size_limits", shape=(2,))
    if not 0.0 < lo <= hi:
        raise InvalidInputError(f"expected 0 < smallest <= largest, got ({lo}, {hi})",
                                "size_limits")
    hole = feature == "hole"
    if material == "MMC":
        return float(actual - lo) if hole else float(hi - actual)
    return float(hi - actual) if hole else float(actual - lo)


def position(points, tol, frame, nominal, feature="hole", axis=(0.0, 0.0, 1.0),
             zone=None, material=None, size_limits=None, method=None) -> Characteristic:
    """Position of a feature relative to its true position in a datum frame.

    Parameters
    ----------
    points : (n, 3) float
        Points on the feature, part coordinates of ``frame`` (one point for
        ``feature="point"``).
    tol : float > 0, or (2,) float
        Zone size; a pair (tx, ty) gives a rectangular zone: tx along the datum
        x axis, ty along y (the true axis must be the datum z axis).
    frame : DatumFrame
    nominal : (3,) float
        A point of the true-position axis (or the true point), datum coordinates.
    feature : {"hole", "shaft", "sphere", "circle", "point"}
        hole / shaft: the axis of a cylinder fit over the feature's length;
        sphere: the centre of a sphere fit; circle: the centre of a circle fit of
        the points projected on the plane normal to ``axis``; point: the point.
    axis : (3,) float
        Direction of the true-position axis, datum coordinates (default datum z).
    zone : {None, "cylindrical", "spherical", "circular", "rectangular"}
        Default: cylindrical for hole / shaft (the zone a cylinder of diameter
        ``tol`` about the true axis over the feature length), circular for
        circle, spherical for sphere / point, rectangular for a pair ``tol``.
    material : {None, "MMC", "LMC"}
        Material modifier (hole / shaft); needs ``size_limits``.
    size_limits : (2,) float
        (smallest, largest) permitted diameter.
    method : str, optional
        The feature fit: default the actual mating envelope (hole: maximum
        inscribed, shaft: minimum circumscribed cylinder; ASME); ``"lsq"`` the
        least-squares (ISO default derived feature).  sphere / circle: default
        ``"lsq"``.

    Returns
    -------
    Characteristic
        ``measured``: 2 x the largest distance of the axis end points (hole /
        shaft, cylindrical), of the centre (circular: in the plane normal to
        ``axis``; spherical: in 3-D) from the true position; a pair (2 max|dx|,
        2 max|dy|) for a rectangular zone.  ``tolerance``: zone, shape, material,
        bonus, total.  ``details``: deviations in datum coordinates, the fit,
        actual sizes.
    """
    check_choice(feature, FEATURES, "feature")
    if not isinstance(frame, DatumFrame):
        raise InvalidInputError(f"expected a DatumFrame, got {type(frame).__name__}",
                                "frame")
    if np.ndim(tol) == 1:
        tx, ty = (check_tol(v, f"tol[{i}]") for i, v in enumerate(
            as_float_array(tol, "tol", shape=(2,))))
        t = (tx, ty)
        zone = zone or "rectangular"
        if zone != "rectangular":
            raise InvalidInputError("a pair of tolerances needs zone='rectangular'", "zone")
    else:
        t = check_tol(tol)
        if zone == "rectangular":
            raise InvalidInputError("a rectangular zone needs tol=(tx, ty)", "tol")
    default = {"hole": "cylindrical", "shaft": "cylindrical", "circle": "circular",
               "sphere": "spherical", "point": "spherical"}[feature]
    zone = check_choice(zone or default,
                        ("cylindrical", "spherical", "circular", "rectangular"), "zone")
    N = as_float_array(nominal, "nominal", shape=(3,))
    a = check_direction(axis, "axis")
    if material is not None:
        check_choice(material, ("MMC", "LMC"), "material")
        if feature not in ("hole", "shaft"):
            raise InvalidInputError("a material modifier needs a hole or a shaft",
                                    "material")
        if size_limits is None:
            raise InvalidInputError(f"{material} needs size_limits=(smallest, largest)",
                                    "size_limits")
    need = {"hole": 5, "shaft": 5, "sphere": 4, "circle": 3, "point": 1}[feature]
    if feature == "point":
        P = as_float_array(points, "points")
        P = P[None, :] if P.shape == (3,) else P
        if P.shape != (1, 3):
            raise InvalidInputError(f"a point feature takes one point (3,), got shape "
                                    f"{P.shape}", "points")
    P = check_points(points if feature != "point" else P, need, f"position of a {feature}")
    Q = frame.to_datum(P)
    details, deciding = {}, np.arange(P.shape[0])
    if feature in ("hole", "shaft"):
        m = method or _MATING[feature]
        r = fit(Q, "cylinder", m)
        s = (Q - r.point) @ r.axis
        i, j = int(np.argmin(s)), int(np.argmax(s))
        X = np.array([r.point + s[i] * r.axis, r.point + s[j] * r.axis])
        deciding = np.unique(np.concatenate([[i, j], r.contacts]))
        details.update(fit=r, axis_ends=X, diameter=2.0 * r.radius)
    elif feature in ("sphere", "circle"):
        m = method or "lsq"
        r = fit(Q, "sphere", m) if feature == "sphere" else fit(reject(Q, a), "circle", m)
        X = r.center[None, :]
        if feature == "circle":
            X = X + float(np.mean(Q @ a)) * a          # back in the section's plane
        deciding = np.asarray(r.contacts)
        details.update(fit=r, center=X[0], diameter=2.0 * r.radius)
    else:
        m = None
        X = Q
    dev = X - N
    tolerance = {"zone": t, "shape": zone, "material": material}
    if zone == "rectangular":
        if abs(abs(float(a[2])) - 1.0) > 1e-12:
            raise InvalidInputError("a rectangular zone needs the true axis along the "
                                    "datum z axis", "axis")
        dxy = np.abs(dev[:, :2]).max(axis=0)
        measured = (2.0 * float(dxy[0]), 2.0 * float(dxy[1]))
    elif zone == "spherical":
        measured = 2.0 * float(np.linalg.norm(dev, axis=1).max())
    else:
        measured = 2.0 * float(np.linalg.norm(reject(dev, a), axis=1).max())
    details.update(deviation=dev, method=m, true_position=N, true_axis=a)
    bonus = 0.0
    size_ok = True
    if material is not None:
        act = details["diameter"] if m == _MATING[feature] and material == "MMC" else None
        if act is None:
            want = _MATING[feature] if material == "MMC" else _MINMAT[feature]
            act = 2.0 * fit(Q, "cylinder", want).radius
        bonus = mmc_bonus(feature, material, act, size_limits)
        size_ok = bonus >= 0.0
        details.update(actual_size=act, size_ok=size_ok)
        tolerance.update(size_limits=tuple(float(v) for v in size_limits),
                         bonus=bonus)
    eff = (tuple(v + max(bonus, 0.0) for v in t) if isinstance(t, tuple)
           else t + max(bonus, 0.0))
    tolerance["total"] = eff
    if isinstance(t, tuple):
        ok = all(mv <= ev for mv, ev in zip(measured, eff))
    else:
        ok = measured <= eff
    return Characteristic("position", measured, tolerance, frame.labels, bool(ok and size_ok),
                          P.shape[0], deciding, details)


def float_pattern(ends, nominals, axes, limits, free, sides=64):
    """The best placement of a pattern's zones that may move together (a composite
    position's lower segment: its datums fix orientation only), as understood from
    ASME Y14.5-2018 10.5.1 / ISO 5458.

    Each feature i has its measured axis end points ``ends[i]`` (k, 3) and its true
    axis (``nominals[i]`` a point, ``axes[i]`` a unit direction), datum coordinates;
    the zones (cylinders of diameter ``limits[i]`` about the true axes) move together
    by a small rotation (about the datum axes named in ``free``, ``"rx"`` ...) and a
    translation (``"tx"`` ...).  Minimises max_i 2 |d_ij| / limits[i] over the motion,
    d_ij the distance of end j from the moved axis: a linear programme with each
    circle replaced by its circumscribed ``sides``-gon, then evaluated exactly at the
    motion found (the rotation exact, not linearised), re-linearised at the new
    placement while that improves (at most :data:`MAX_FLOAT_ITER` programmes, steps of
    at most :data:`ROT_STEP` rad).  The polygons make it at most a factor
    ``1 / cos(pi / sides)`` (0.12 % for 64) above the optimum of each programme; the
    ``measured`` values are exact for the placement reported, never below the
    optimum.

    Returns
    -------
    measured : (m,) float
        2 x the largest distance of each feature's ends from its moved true axis.
    motion : dict
        ``rotation`` (3, 3), ``translation`` (3,) applied to the zones.
    """
    cols = [n for n in ("rx", "ry", "rz", "tx", "ty", "tz") if n in free]
    k = len(cols)
    ang = 2.0 * np.pi * np.arange(sides) / sides
    L = max(1.0, max(float(np.abs(np.asarray(X)).max()) for X in ends))
    R, t = np.eye(3), np.zeros(3)

    def exact(R, t):
        out = []
        for X, N, a in zip(ends, nominals, axes):
            Nm, am = R @ N + t, R @ a
            out.append(2.0 * float(np.linalg.norm(reject(X - Nm, am), axis=1).max()))
        return np.array(out)

    best = exact(R, t)
    best_motion = (R, t)
    for _ in range(MAX_FLOAT_ITER):
        rows, rhs = [], []
        for X, N, a, lim in zip(ends, nominals, axes, limits):
            Nm, am = R @ N + t, R @ a
            e1, e2 = perp_basis(am)
            for x in X:
                r0 = x - Nm
                s_ = float(r0 @ am)
                for th in ang:
                    m = np.cos(th) * e1 + np.sin(th) * e2
                    # offset of x from the moved axis, to first order in the extra
                    # motion (w about the origin, dt): m.r0 - m.(w x Nm + dt)
                    #   - s m.(w x am)
                    g = []
                    for name in cols:
                        e = np.eye(3)["xyz".index(name[1])]
                        if name[0] == "r":
                            g.append(-float(m @ np.cross(e, Nm))
                                     - s_ * float(m @ np.cross(e, am)))
                        else:
                            g.append(-float(m @ e))
                    rows.append(np.concatenate([2.0 * np.array(g), [-lim]]))
                    rhs.append(-2.0 * float(m @ r0))
        c = np.zeros(k + 1)
        c[-1] = 1.0
        bounds = [(-ROT_STEP, ROT_STEP) if n[0] == "r" else (-ROT_STEP * L, ROT_STEP * L)
                  for n in cols] + [(None, None)]
        res = linprog(c, A_ub=np.array(rows), b_ub=np.array(rhs), bounds=bounds,
                      method="highs")
        if res.status != 0:
            break
        w, dt = np.zeros(3), np.zeros(3)
        for v, name in zip(res.x[:k], cols):
            (w if name[0] == "r" else dt)["xyz".index(name[1])] += v
        dR = Rotation.from_rotvec(w).as_matrix()
        R, t = dR @ R, dR @ t + dt
        got = exact(R, t)
        score = lambda v: float(max(g / lim for g, lim in zip(v, limits)))  # noqa: E731
        if score(got) < score(best) - 1e-15 * L:
            best, best_motion = got, (R, t)
        else:
            break
    return best, {"rotation": best_motion[0], "translation": best_motion[1]}
