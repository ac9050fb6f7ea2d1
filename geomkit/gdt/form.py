"""Form tolerances (ISO 1101:2017 clauses 18.1-18.4 as understood; ASME Y14.5-2018
section 8): flatness, straightness, circularity (roundness), cylindricity,
sphericity.

The ISO default association is the minimum zone (Chebyshev,
:func:`geomkit.fitting.fit` with ``method="minzone"``); ``method="lsq"`` takes the
zone about the least-squares feature instead (its width is then >= the minimum
zone) and says so in ``tolerance["method"]``.
"""

from __future__ import annotations

import numpy as np

from geomkit.fitting import fit
from geomkit.gdt._common import (Characteristic, check_choice, check_direction,
                                 check_points, check_tol, extremes, min_width_2d,
                                 perp_basis, reject,
                                 size_of)

__all__ = ["flatness", "straightness", "circularity", "cylindricity", "sphericity"]

_METHODS = ("minzone", "lsq")


def _form(type_, kind, points, tol, method, need, details=None, data=None):
    P = check_points(points, need, type_)
    t = check_tol(tol)
    check_choice(method, _METHODS, "method")
    r = fit(P if data is None else data, kind, method)
    value = float(r.form_error)
    det = {"fit": r, "certificate_met": r.optimality.get("met")}
    det.update(details or {})
    return Characteristic(type_, value, {"zone": t, "method": method}, (), value <= t,
                          P.shape[0], np.asarray(r.contacts), det)


def flatness(points, tol, method="minzone") -> Characteristic:
    """Flatness: the smallest distance between two parallel planes holding every
    point (ISO 1101:2017 18.2, as understood; ASME Y14.5-2018 section 8).

    Parameters
    ----------
    points : (n, 3) float, n >= 3
    tol : float > 0
    method : {"minzone", "lsq"}

    Returns
    -------
    Characteristic
        ``measured`` the zone width; ``details["fit"]`` the plane (its ``point`` is
        the zone's mid-plane for minzone); ``deciding`` the contacts.
    """
    return _form("flatness", "plane", points, tol, method, 3)


def straightness(points, tol, method="minzone", normal=None) -> Characteristic:
    """Straightness of a line (an axis or a line element).

    * ``normal=None``: a line in space, cylindrical zone (the tolerance is a
      diameter, ISO 1101:2017 18.1 figure for the derived median line, as
      understood): ``measured`` is the diameter of the smallest cylinder holding the
      points (minzone) or of the cylinder about the least-squares line.
    * ``normal`` given: line elements in a section plane of that normal: the points
      are projected on the plane and the zone is two parallel lines in it;
      ``measured`` is the minimum width over every direction (exact, from the
      convex hull: ISO 1101 18.1, line elements) or the width about the
      least-squares line.

    Parameters
    ----------
    points : (n, 3) float, n >= 2 (3 with ``normal``)
    tol : float > 0
    method : {"minzone", "lsq"}
    normal : (3,) float, optional
    """
    if normal is None:
        ch = _form("straightness", "line", points, tol, method, 2,
                   {"zone_shape": "cylinder"})
        return ch
    P = check_points(points, 3, "straightness of line elements")
    t = check_tol(tol)
    check_choice(method, _METHODS, "method")
    n = check_direction(normal, "normal")
    e1, e2 = perp_basis(n)
    Q = np.column_stack([P @ e1, P @ e2])
    Qc = Q - Q.mean(axis=0)
    _, _, Vt = np.linalg.svd(Qc, full_matrices=False)
    u = Vt[-1]
    if method == "minzone":
        u, _ = min_width_2d(Q, u, max_angle=np.pi / 2)
    s = Qc @ u
    w = float(s.max() - s.min())
    nrm3 = u[0] * e1 + u[1] * e2
    return Characteristic("straightness", w, {"zone": t, "method": method}, (), w <= t,
                          P.shape[0], extremes(s, size_of(P), w),
                          {"zone_shape": "two lines", "section_normal": n,
                           "zone_normal": nrm3,
                           "out_of_plane": float(np.ptp(P @ n))})


def circularity(points, tol, method="minzone", normal=None) -> Characteristic:
    """Circularity (roundness) of one section: the smallest radial distance between
    two concentric circles in the section plane holding the points (ISO 1101:2017
    18.3, as understood; ASME Y14.5-2018 section 8).

    Parameters
    ----------
    points : (n, 3) float, n >= 3
        Points of one section.
    tol : float > 0
    method : {"minzone", "lsq"}
    normal : (3,) float, optional
        Normal of the section plane (e.g. the datum or feature axis); the points are
        projected on it.  Without it the section plane is the points' least-squares
        plane (the fit's convention).
    """
    P = check_points(points, 3, "circularity")
    data, det = None, {}
    if normal is not None:
        n = check_direction(normal, "normal")
        data = reject(P, n)
        det = {"section_normal": n,
               "out_of_plane": float(np.ptp(P @ n))}
    return _form("circularity", "circle", P, tol, method, 3, det, data)


def cylindricity(points, tol, method="minzone") -> Characteristic:
    """Cylindricity: the smallest radial distance between two coaxial cylinders
    holding the points (ISO 1101:2017 18.4, as understood; ASME Y14.5-2018
    section 8).

    Parameters
    ----------
    points : (n, 3) float, n >= 5
    tol : float > 0
    method : {"minzone", "lsq"}
    """
    return _form("cylindricity", "cylinder", points, tol, method, 5)


def sphericity(points, tol, method="minzone") -> Characteristic:
    """Sphericity: the smallest radial distance between two concentric spheres
    holding the points.  Not a symbol of ISO 1101:2017 or ASME Y14.5-2018 (a
    sphere's circularity there is per section); the zone is the 3-D analogue of
    cylindricity, as CMM software and ISO 10360-6 test features use it.

    Parameters
    ----------
    points : (n, 3) float, n >= 4
    tol : float > 0
    method : {"minzone", "lsq"}
    """
    return _form("sphericity", "sphere", points, tol, method, 4)
