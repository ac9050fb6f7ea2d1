"""The compiled fit of an edge's pcurve on a surface of revolution
(:func:`geomkit.cad.uvmap.map_edge`, kernel :mod:`geomkit._kernels.pcurve_map`) against
the numpy route it replaces in the readers (:func:`geomkit.cad.uvmap.map_pcurve` of the
edge's closed-form local coordinates): the same curve to rounding, within ``tol`` of the
mapped coordinates, on every kind of surface (a spindle torus's inner part too) and on
a real part."""

from __future__ import annotations

import math

import numpy as np
import pytest

from geomkit.cad import faceedges
from geomkit.cad.analytic import curve_eval
from geomkit.cad.brep import Analytic
from geomkit.cad.faceedges import Edge, _chain, _fit
from geomkit.nurbs.trimming import evaluate_trim_curve

from helpers.paths import DATA


def _numpy_route(monkeypatch, *args):
    with monkeypatch.context() as m:
        m.setattr(faceedges, "KIND_CODE", {})
        return _fit(*args)


def _edge_on(srf, a, b, reverse):
    """A cubic B-spline through surface points at local coordinates ``(a, b)``
    (its control points are those points: near the surface, not on it; both routes
    invert the same model points)."""
    O, X, Y, A = srf.O, srf.X, srf.Y, srf.A
    if srf.kind in ("cylinder", "cone"):
        rad = srf.R + a * math.tan(srf.alpha)
        P = O + np.outer(a, A) + (rad * np.cos(b))[:, None] * X + (rad * np.sin(b))[:, None] * Y
    elif srf.kind == "sphere":
        P = O + srf.R * (np.outer(np.sin(a), A) + (np.cos(a) * np.cos(b))[:, None] * X
                         + (np.cos(a) * np.sin(b))[:, None] * Y)
    else:
        rho = srf.R + srf.r * np.cos(a)
        P = O + np.outer(srf.r * np.sin(a), A) + (rho * np.cos(b))[:, None] * X \
            + (rho * np.sin(b))[:, None] * Y
    n = len(P)
    U = np.concatenate([[0.0] * 4, np.linspace(0, 1, n - 2)[1:-1], [1.0] * 4])
    return Edge((3, U, np.column_stack([P, np.ones(n)])), 1, reverse)


SURFACES = {
    "cylinder": (Analytic("cylinder", [1, 2, 3], [0, 0.6, 0.8], [1, 0, 0], R=5.0),
                 np.linspace(-3, 4, 9), np.linspace(0.4, 5.5, 9)),
    "cone": (Analytic("cone", [0, 0, 0], [0, 0, 1], [1, 0, 0], R=3.0, alpha=0.4),
             np.linspace(0, 6, 9), np.linspace(-1.0, 2.2, 9)),
    "sphere": (Analytic("sphere", [0, 1, 0], [1, 1, 0], [0, 0, 1], R=7.0),
               np.linspace(-1.2, 1.1, 9), np.linspace(0.2, 4.0, 9)),
    "torus": (Analytic("torus", [0, 0, 0], [0, 0, 1], [1, 0, 0], R=10.0, r=2.0),
              np.linspace(0.3, 5.0, 9), np.linspace(-0.5, 2.5, 9)),
    "spindle torus, inner part": (Analytic("torus", [0, 0, 0], [0, 0, 1], [1, 0, 0],
                                           R=1.0, r=3.0),
                                  np.linspace(2.2, 3.9, 9), np.linspace(0.1, 2.0, 9)),
}


@pytest.mark.parametrize("reverse", [False, True])
@pytest.mark.parametrize("kind", list(SURFACES))
def test_the_kernel_fits_what_the_numpy_route_fits(monkeypatch, kind, reverse):
    srf, a, b = SURFACES[kind]
    e = _edge_on(srf, a, b, reverse)
    size = float(np.ptp(e.points(65), axis=0).max())
    ab = _chain(srf, [e], size)[0]
    lo, hi = ab.min(axis=0), ab.max(axis=0)
    _, fu, fv = srf.build((lo[0], hi[0]), (lo[1], hi[1]))
    tol = 1e-10 * float(np.max(hi - lo))
    with monkeypatch.context() as m:  # the kernel route, not the numpy one
        m.setattr(faceedges, "map_pcurve", None)
        fast = _fit(srf, e, ab, fu, fv, tol)
    slow = _numpy_route(monkeypatch, srf, e, ab, fu, fv, tol)
    assert fast.degree == slow.degree == 5
    assert len(fast.knots) == len(slow.knots)  # the same spans
    np.testing.assert_allclose(fast.knots, slow.knots, rtol=0, atol=1e-13)
    np.testing.assert_allclose(fast.control_points, slow.control_points, rtol=0,
                               atol=1e-9 * float(np.max(hi - lo)))
    # within tol of the mapped coordinates of the edge's points (the oracle: closed
    # form inversion of the exact edge point, then the arc maps)
    s = np.linspace(0.0, 1.0, 401)
    t = np.linspace(fast.knots[0], fast.knots[-1], s.size)
    uv = evaluate_trim_curve(fast, t)[:, 0]
    X = curve_eval(e.curve, e.ts(s))
    loc, _ = srf.local(X)
    for k, f in ((0, fu), (1, fv)):
        x = loc[:, k]
        if srf.periodic[k]:
            ref = np.interp(s, np.linspace(0, 1, len(ab)), ab[:, k])
            x = ref + (x - ref + math.pi) % (2 * math.pi) - math.pi
        want = x if f is None else f(x)
        assert np.abs(uv[:, k] - want).max() <= 1.01 * tol + 1e-15


def test_a_real_part_reads_the_same_by_either_route(monkeypatch):
    from geomkit.cad.step import read_step

    path = DATA / "parts" / "nist_ftc_07_ap242.stp"
    fast = read_step(path, cache=False)
    with monkeypatch.context() as m:
        m.setattr(faceedges, "KIND_CODE", {})
        slow = read_step(path, cache=False)
    fitted = 0
    for a, b in zip(fast.surfaces, slow.surfaces):
        np.testing.assert_allclose(a.homogeneous, b.homogeneous, rtol=0, atol=1e-12 * a.size)
        (u0, u1), (v0, v1) = a.domain
        span = max(u1 - u0, v1 - v0)
        for la, lb in zip(a.trim, b.trim, strict=True):
            for ca, cb in zip(la.pieces, lb.pieces, strict=True):
                fitted += ca.degree == 5
                pa = evaluate_trim_curve(ca, np.linspace(ca.knots[0], ca.knots[-1], 101))
                pb = evaluate_trim_curve(cb, np.linspace(cb.knots[0], cb.knots[-1], 101))
                assert np.abs(pa - pb).max() <= 1e-11 * span
    assert fitted > 100  # the part's fillets and holes take the fitted route


def test_fit_start_spans_as_the_polyline_route_builds_them():
    """_fit's starting spans: the edge's distinct knots, both ways along it, are
    np.unique's (their diagonal polyline is TrimCurve.polyline's); a knot vector that
    is not finite is refused by the polyline's check."""
    from geomkit.errors import InvalidTrimError
    from geomkit.nurbs.surface import TrimCurve

    rng = np.random.default_rng(11)
    for _ in range(50):
        inner = np.sort(rng.choice(rng.uniform(0.1, 0.9, 6), 6))  # repeated knots
        U = np.concatenate([[0.0] * 4, inner, [1.0] * 4]) * rng.uniform(0.5, 3.0)
        p, t0, t1 = 3, float(U[3]), float(U[-4])
        for rev in (False, True):
            ref = (np.unique(U[p:len(U) - p]) - t0) / (t1 - t0)
            ref = np.unique(np.clip(1.0 - ref if rev else ref, 0.0, 1.0))
            sk = (faceedges._distinct(U[p:len(U) - p]) - t0) / (t1 - t0)
            sk = np.clip(sk, 0.0, 1.0) if not rev else np.clip(1.0 - sk, 0.0, 1.0)[::-1]
            sk = faceedges._distinct(sk)
            np.testing.assert_array_equal(sk, ref)
    with pytest.raises(InvalidTrimError):
        sk = np.array([0.0, np.nan, 1.0])
        TrimCurve.polyline(np.column_stack([sk, sk]))
