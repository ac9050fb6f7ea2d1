"""Profile of a surface / of a line against the exact NURBS nominal (ISO 1101:2017
18.5-18.8 and the UZ modifier, as understood; ASME Y14.5-2018 section 11, the U
modifier).

The deviation of a point is its signed distance to the trimmed nominal surfaces
(:func:`geomkit.query.projection_part.project_points`): positive along the surface
normal (``S_u x S_v``), i.e. outside the material when the model's normals point
out of it.  The tolerance zone lies between two offsets of the exact surface:

* equal bilateral (default): offsets -tol/2 and +tol/2;
* unequal, ``unequal=U`` (ASME U: the part of the zone *outside* the material,
  along the normal): offsets -(tol - U) and +U.  ISO 1101 ``UZ`` gives the offset of
  the zone's centre instead: UZ = U - tol/2 (so ``U = UZ + tol/2``).

``measured`` = 2 max_i |d_i - c| with c = U - tol/2 the offset of the zone centre
(c = 0 bilateral): the smallest zone of that centre holding every point; the
feature passes iff ``measured <= tol``, i.e. every d_i lies in the zone.
"""

from __future__ import annotations

import numpy as np
from scipy.optimize import linprog
from scipy.spatial.transform import Rotation

from geomkit.errors import DegenerateGeometryError, InvalidInputError
from geomkit.gdt._common import (CONTACT_ABS, CONTACT_REL, Characteristic,
                                 check_direction, check_points,
                                 check_tol, perp_basis, reject, size_of)
from geomkit.gdt.datums import DOFS, DatumFrame
from geomkit.nurbs.surface import as_surfaces
from geomkit.query.projection_part import project_points
from geomkit.query.results import BEYOND, FAILED, STATUS_NAMES
from geomkit.validate import as_float_array

__all__ = ["profile_surface", "profile_line", "rigid_minimax"]

#: Largest fit iteration count; the fit stops earlier when the LP predicts a decrease
#: below FIT_TOL * size.
FIT_ITER, FIT_TOL = 100, 1e-14
#: A section plane nearly tangent to the surface (in-plane share of the normal below
#: this) makes the in-plane distance ill defined.
MIN_INPLANE = 0.1


def _project_one(surfaces, X):
    pr = project_points(surfaces, X)
    bad = np.nonzero((pr.status == BEYOND) | (pr.status == FAILED)
                     | ~np.isfinite(pr.signed_distance))[0]
    if bad.size:
        i = int(bad[0])
        raise DegenerateGeometryError(
            f"{bad.size} point(s) could not be projected on the nominal surfaces (first: "
            f"index {i}, status {STATUS_NAMES.get(int(pr.status[i]), pr.status[i])})",
            "points")
    return (pr.signed_distance.astype(np.float64), pr.point, pr.normal,
            np.asarray(pr.surface))


def _project(surfaces, X, owner=None):
    """Signed distances, unit gradients and feet of points on the surfaces; with
    ``owner`` each point only on its own surface (index into ``surfaces``)."""
    if owner is None:
        d, foot, nrm, surf = _project_one(surfaces, X)
    else:
        n = X.shape[0]
        d, foot, nrm = np.empty(n), np.empty((n, 3)), np.empty((n, 3))
        surf = np.asarray(owner, np.int64).copy()
        for k in np.unique(surf):
            m = surf == k
            d[m], foot[m], nrm[m], _ = _project_one([surfaces[int(k)]], X[m])
    G = X - foot
    with np.errstate(invalid="ignore", divide="ignore"):
        grad = G / d[:, None]
    small = np.abs(d) <= 1e-12 * size_of(X)
    grad[small] = nrm[small]
    grad /= np.linalg.norm(grad, axis=1)[:, None]
    return d, grad, surf


class _Scaled:
    """Distances seen in the zone: (d - c) / w, w the in-plane share (profile_line)."""

    def __init__(self, surfaces, c, plane_n=None, owner=None):
        self.surfaces, self.c, self.plane_n, self.owner = surfaces, c, plane_n, owner

    def __call__(self, X):
        d, g, surf = _project(self.surfaces, X, self.owner)
        w = np.ones_like(d)
        if self.plane_n is not None:
            w = np.linalg.norm(reject(g, self.plane_n), axis=1)
            low = np.nonzero(w < MIN_INPLANE)[0]
            if low.size:
                raise DegenerateGeometryError(
                    f"the section plane is nearly tangent to the surface at point "
                    f"{int(low[0])} (in-plane share of the normal {w[low[0]]:.3g})",
                    "plane")
        return (d / w) - self.c, g / w[:, None], surf, w


def rigid_minimax(values, X, basis, L, max_iter=FIT_ITER, center=None):
    """Rigid motion of points minimising max_i |e_i| (sequential LP, trust region).

    Parameters
    ----------
    values : callable X -> (e (n,), grad (n, 3), ...)
        Zone deviations e_i of moved points and their gradients de_i/dx_i.
    X : (n, 3) float
    basis : (k, 6) float
        Allowed motions as rows (omega, t): 6 x 6 identity for every rigid motion,
        3 rows for motions in a plane.
    L : float
        Length scale (rotations are scaled by it).
    center : (3,) float, optional
        The point rotations turn about (default the moved points' centroid; give it
        when the basis holds rotations without every translation).

    Returns
    -------
    R : (3, 3), t : (3,)
        The motion ``x -> R x + t`` found.
    info : dict
        iterations, first and last max |e|, ``converged``.
    """
    k = basis.shape[0]
    R, t = np.eye(3), np.zeros(3)
    e, g = values(X)[:2]
    f0 = f = float(np.abs(e).max())
    rho = max(f, 1e-9 * L)
    it, converged = 0, False
    Y = X
    while it < max_iter:
        it += 1
        c = Y.mean(axis=0) if center is None else np.asarray(center, np.float64)
        J = np.hstack([np.cross(Y - c, g) / L, g]) @ basis.T         # (n, k)
        A = np.vstack([np.column_stack([J, -np.ones(len(e))]),
                       np.column_stack([-J, -np.ones(len(e))])])
        b = np.concatenate([-e, e])
        cost = np.zeros(k + 1)
        cost[-1] = 1.0
        res = linprog(cost, A_ub=A, b_ub=b, bounds=[(-rho, rho)] * k + [(None, None)],
                      method="highs-ds")
        if res.status != 0 or res.x is None:
            break
        y, s = res.x[:k], float(res.x[-1])
        pred = f - s
        if pred <= FIT_TOL * L:
            converged = True
            break
        m = y @ basis
        dR = Rotation.from_rotvec(m[:3] / L).as_matrix()
        Yn = (Y - c) @ dR.T + c + m[3:]
        en, gn = values(Yn)[:2]
        fn = float(np.abs(en).max())
        if fn < f:
            ratio = (f - fn) / pred
            Y, e, g = Yn, en, gn
            R, t = dR @ R, dR @ (t - c) + c + m[3:]
            f = fn
            if ratio > 0.5 and np.abs(y).max() > 0.99 * rho:
                rho *= 2.0
            elif ratio < 0.25:
                rho *= 0.5
        else:
            rho *= 0.25
            if rho < 1e-15 * L:
                converged = True
                break
    return R, t, {"iterations": it, "start_max": f0, "max": f, "converged": converged}


def _zone(tol, unequal):
    t = check_tol(tol)
    if unequal is None:
        return t, 0.0, {"zone": t, "unequal": None, "limits": (-t / 2, t / 2)}
    try:
        U = float(unequal)
    except (TypeError, ValueError):
        raise InvalidInputError(f"expected a number, got {unequal!r}", "unequal") from None
    if not (np.isfinite(U) and 0.0 <= U <= t):
        raise InvalidInputError(f"U must lie in [0, tol] = [0, {t}], got {unequal!r}",
                                "unequal")
    return t, U - t / 2, {"zone": t, "unequal": U, "uz": U - t / 2,
                          "limits": (U - t, U)}


def _check_owner(owner, n, k):
    o = np.asarray(owner)
    if o.shape != (n,) or not np.issubdtype(o.dtype, np.integer):
        raise InvalidInputError(f"expected {n} integer surface indices, got shape "
                                f"{o.shape} of {o.dtype}", "surface_of")
    if n and (o.min() < 0 or o.max() >= k):
        raise InvalidInputError(f"surface index out of range 0..{k - 1}", "surface_of")
    return o.astype(np.int64)


def _free_basis(frame, free):
    """Rows (omega, t) of the motions ``free`` names (``tx`` ... ``rz``) in the frame's
    axes."""
    rows = []
    for name in free:
        if name not in DOFS:
            raise InvalidInputError(f"unknown degree of freedom {name!r}; expected some "
                                    f"of {', '.join(DOFS)}", "free")
        r = np.zeros(6)
        ax = frame.axes["xyz".index(name[1])]
        if name[0] == "r":
            r[:3] = ax
        else:
            r[3:] = ax
        rows.append(r)
    return np.array(rows).reshape(-1, 6)


def _profile(type_, P, surfaces, tol, frame, unequal, best_fit, plane_n, free=None,
             owner=None):
    t, c, tolerance = _zone(tol, unequal)
    if frame is not None and not isinstance(frame, DatumFrame):
        raise InvalidInputError(f"expected a DatumFrame or None, got "
                                f"{type(frame).__name__}", "frame")
    fit_it = (frame is None) if best_fit is None else bool(best_fit)
    L = size_of(P)
    surfaces = as_surfaces(surfaces)
    if owner is not None:
        owner = _check_owner(owner, P.shape[0], len(surfaces))
    vals = _Scaled(surfaces, c, plane_n, owner)
    details = {"best_fit": fit_it}
    X = P
    if free and frame is not None and plane_n is None:
        if not isinstance(free, (tuple, list)):
            raise InvalidInputError(f"expected a tuple of degrees of freedom, got "
                                    f"{free!r}", "free")
        basis = _free_basis(frame, free)
        R, tr, info = rigid_minimax(vals, P, basis, L, center=frame.origin)
        X = P @ R.T + tr
        details.update(rotation=R, translation=tr, fit=info, free=tuple(free))
    elif fit_it:
        if plane_n is None:
            basis = np.eye(6)
        else:
            e1, e2 = perp_basis(plane_n)
            basis = np.zeros((3, 6))
            basis[0, :3], basis[1, 3:], basis[2, 3:] = plane_n, e1, e2
        R, tr, info = rigid_minimax(vals, P, basis, L)
        X = P @ R.T + tr
        details.update(rotation=R, translation=tr, fit=info)
    e, _, surf, w = vals(X)
    dev = e + c
    value = 2.0 * float(np.abs(e).max())
    tl = CONTACT_REL * value + CONTACT_ABS * L
    deciding = np.nonzero(np.abs(e) >= np.abs(e).max() - tl)[0]
    details.update(deviation=dev, zone_center_offset=c, points=X,
                   range=(float(dev.min()), float(dev.max())),
                   surface=surf)
    if plane_n is not None:
        details["inplane_share_min"] = float(w.min())
    return Characteristic(type_, value, tolerance,
                          () if frame is None else frame.labels, value <= t,
                          P.shape[0], deciding, details)


def profile_surface(points, surfaces, tol, frame=None, unequal=None,
                    best_fit=None, free=None, surface_of=None) -> Characteristic:
    """Profile of a surface (ISO 1101:2017 18.7-18.8, as understood; ASME Y14.5-2018
    section 11).

    Parameters
    ----------
    points : (n, 3) float
        Measured points in CAD coordinates (with datums: already moved by their
        frame, e.g. with :func:`geomkit.gdt.align_to_cad`).
    surfaces : Surface or list of Surface
        The exact nominal (trimmed NURBS).
    tol : float > 0
        Zone width.
    frame : DatumFrame, optional
        The datums the zone refers to: the points are taken as they are (no fit);
        its labels are reported.  None: a profile without datums, whose zone may
        float (best fit, below).
    unequal : float in [0, tol], optional
        ASME U (ISO: U = UZ + tol/2), module doc.
    best_fit : bool, optional
        Default: True without ``frame``.  Rigid minimax fit (every rotation and
        translation) minimising max |d_i - c|: sequential LP on the linearisation
        d_i + g_i.(w x p_i + t), re-projecting after each step; a local optimum.
    free : tuple of str, optional
        With ``frame``: the degrees of freedom (``"tx"`` ... ``"rz"``, in the frame's
        axes; rotations about its origin) in which the zone still floats, e.g. the
        frame's own ``free`` (datums that do not fix every motion) or the
        translations of a composite profile's lower segment (orientation only).
        The same rigid minimax fit, restricted to those motions.
    surface_of : (n,) int, optional
        The surface (index into ``surfaces``) each point belongs to (its face):
        its deviation is then measured to that surface only, not to the nearest of
        all (a point near a corner keeps its face while the fit moves it).

    Returns
    -------
    Characteristic
        ``details``: ``deviation`` (n,) signed distances after the fit, ``range``,
        ``zone_center_offset``, ``rotation`` / ``translation`` (x -> R x + t) and
        ``fit`` of the best fit, ``points`` as evaluated, ``surface`` indices.

    Raises
    ------
    DegenerateGeometryError
        A point could not be projected.
    """
    P = check_points(points, 1 if best_fit is False or frame is not None else 3,
                     "profile of a surface")
    return _profile("profile_surface", P, surfaces, tol, frame, unequal, best_fit, None,
                    free, surface_of)


def profile_line(points, surfaces, plane, tol, frame=None, unequal=None,
                 best_fit=None) -> Characteristic:
    """Profile of a line in one section plane (ISO 1101:2017 18.5-18.6, as
    understood; ASME Y14.5-2018 section 11).

    The points are projected on the section plane; a point's deviation is its
    signed 3-D distance to the surface divided by the in-plane share of the
    distance direction: the distance to the section curve to first order (exact
    when the surface normal lies in the plane).  The best fit moves the points in
    the plane only (a rotation about its normal and two translations).

    Parameters
    ----------
    points : (n, 3) float
    surfaces : Surface or list of Surface
    plane : ((3,), (3,)) float
        A point of the section plane and its normal.
    tol, frame, unequal, best_fit
        As :func:`profile_surface`.

    Returns
    -------
    Characteristic
        As :func:`profile_surface`; ``details["out_of_plane"]`` the largest
        distance of the given points from the plane (removed), and
        ``inplane_share_min``.
    """
    P = check_points(points, 1 if best_fit is False or frame is not None else 2,
                     "profile of a line")
    try:
        p0, n = plane
    except (TypeError, ValueError):
        raise InvalidInputError("expected (point, normal)", "plane") from None
    p0 = as_float_array(p0, "plane[0]", shape=(3,))
    n = check_direction(n, "plane[1]")
    off = (P - p0) @ n
    X = P - off[:, None] * n
    ch = _profile("profile_line", X, surfaces, tol, frame, unequal, best_fit, n)
    ch.details["out_of_plane"] = float(np.abs(off).max())
    return ch
