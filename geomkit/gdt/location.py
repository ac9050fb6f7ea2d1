"""Position (ISO 1101:2017 18.12, as understood; ASME Y14.5-2018 section 10) of an
axis, a centre point or a point, relative to a datum frame, with the maximum /
least material modifiers (ISO 2692:2021 / ASME Y14.5-2018 section 10 bonus tolerance,
as understood).

The true position is given in datum coordinates (the basic dimensions of the
drawing); the measured points are in the part coordinates of the frame.
"""

from __future__ import annotations


import numpy as np

from geomkit.errors import InvalidInputError
from geomkit.fitting import fit
from geomkit.gdt._common import (Characteristic, check_choice, check_direction,
                                 check_points, check_tol, reject)
from geomkit.gdt.datums import DatumFrame
from geomkit.validate import as_float_array

__all__ = ["position", "mmc_bonus"]

FEATURES = ("hole", "shaft", "sphere", "circle", "point")
_MATING = {"hole": "maxinscribed", "shaft": "mincircumscribed"}
_MINMAT = {"hole": "mincircumscribed", "shaft": "maxinscribed"}


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
