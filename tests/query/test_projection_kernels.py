"""The fixed-order-2 derivative kernel and the candidate-buffer overflow accounting
of the projection (issue 15)."""

import sys

import numpy as np
import pytest

import geomkit
from geomkit import samples
from geomkit._kernels.surface import D1, D2, _binomial_table, derivs_scratch, surface_derivs, \
    surface_derivs2, surface_point_d1

ORDERS = ((0, 0), (1, 0), (0, 1), (2, 0), (1, 1), (0, 2))


def _random_surface(rng, p, q, nu, nv, rational):
    def knots(n, d):
        inner = np.sort(rng.uniform(0, 1, n - d - 1))
        return np.r_[np.zeros(d + 1), inner, np.ones(d + 1)]
    P = rng.normal(size=(nu, nv, 3)) * 10
    W = rng.uniform(0.3, 3.0, (nu, nv)) if rational else None
    return geomkit.Surface(p, q, knots(nu, p), knots(nv, q), P, W)


def _surfaces():
    rng = np.random.default_rng(5)
    out = [samples.load(n)[0] for n in ("freeform_1", "sphere", "torus", "heavy_weights",
                                        "crease", "plate_with_hole", "cylinder_quarter")]
    out += [_random_surface(rng, p, q, p + 3, q + 4, r)
            for p, q, r in ((1, 4, True), (4, 2, False), (5, 3, True), (2, 1, False))]
    return out


@pytest.mark.parametrize("s", _surfaces(), ids=lambda s: f"{s.degree_u}x{s.degree_v}")
def test_surface_derivs2_equals_the_general_kernel(s):
    """surface_derivs2 (k + l <= 2) against surface_derivs (A3.6 + A4.4, itself
    checked against geomdl): equal to rounding, at random parameters, knots, ends."""
    (a, b), (c, d) = s.domain
    rng = np.random.default_rng(0)
    uv = np.column_stack([rng.uniform(a, b, 300), rng.uniform(c, d, 300)])
    ku = np.unique(s.knots_u)
    kv = np.unique(s.knots_v)
    uv = np.vstack([uv, np.column_stack([ku, np.full(ku.size, 0.5 * (c + d))]),
                    np.column_stack([np.full(kv.size, 0.5 * (a + b)), kv])])
    p, q = s.degree_u, s.degree_v
    bin_ = _binomial_table(D2)
    # scratch of larger degree than the surface's, as the projection batch uses it
    scr1 = derivs_scratch(p, q, D2)
    scr2 = derivs_scratch(p + 2, q + 1, D2)
    S1 = np.empty((3, 3, 3))
    S2 = np.full((3, 3, 3), np.nan)
    for u, v in uv:
        surface_derivs(s.homogeneous, p, q, s.knots_u, s.knots_v, u, v, D2, bin_, scr1, S1)
        surface_derivs2(s.homogeneous, p, q, s.knots_u, s.knots_v, u, v, scr2, S2)
        scale = max(np.abs(S1[k, l]).max() for k, l in ORDERS)
        for k, l in ORDERS:
            assert np.abs(S1[k, l] - S2[k, l]).max() <= 1e-12 * scale, (u, v, k, l)


@pytest.mark.parametrize("s", _surfaces(), ids=lambda s: f"{s.degree_u}x{s.degree_v}")
def test_surface_point_d1_equals_the_general_kernel(s):
    """surface_point_d1 (S, S_u, S_v: the meshing measure's foot steps) against
    surface_derivs of order 1, equal to rounding at random parameters and at every
    knot (both ends included), on poles, creases and heavy weights; SKL[1, 1] is left
    as it was."""
    (a, b), (c, d) = s.domain
    rng = np.random.default_rng(1)
    ku = np.unique(s.knots_u)
    kv = np.unique(s.knots_v)
    uv = np.vstack([np.column_stack([rng.uniform(a, b, 300), rng.uniform(c, d, 300)]),
                    np.column_stack([ku, rng.uniform(c, d, ku.size)]),
                    np.column_stack([rng.uniform(a, b, kv.size), kv]),
                    [[a, c], [b, d], [a, d], [b, c]]])
    p, q = s.degree_u, s.degree_v
    bin_ = _binomial_table(D1)
    scr = derivs_scratch(p, q, D1)
    Du, Dv = np.empty((2, p + 1)), np.empty((2, q + 1))
    left, right = np.empty(max(p, q) + 1), np.empty(max(p, q) + 1)
    S1 = np.empty((2, 2, 3))
    S2 = np.full((2, 2, 3), 7.0)
    for u, v in uv:
        surface_derivs(s.homogeneous, p, q, s.knots_u, s.knots_v, u, v, D1, bin_, scr, S1)
        surface_point_d1(s.homogeneous, p, q, s.knots_u, s.knots_v, u, v, Du, Dv, left,
                         right, S2)
        scale = max(np.abs(S1[k, l]).max() for k, l in ORDERS[:3])
        for k, l in ORDERS[:3]:
            assert np.abs(S1[k, l] - S2[k, l]).max() <= 1e-12 * scale, (u, v, k, l)
        assert (S2[1, 1] == 7.0).all()


@pytest.mark.parametrize("rational", [False, True])
@pytest.mark.parametrize("nu,nv", [(2, 2), (3, 5)])
def test_bilinear_derivs2_equals_the_general_kernel(nu, nv, rational):
    """The degree (1, 1) fast path (``project_bilinear``) against surface_derivs (one
    span and several, rational and not; random parameters, knots, ends) and the
    plate with a hole: equal to rounding."""
    from geomkit._kernels.project_bilinear import derivs2, derivs2_bilinear

    rng = np.random.default_rng(nu * nv + rational)
    surfs = [_random_surface(rng, 1, 1, nu, nv, rational)]
    if nu == 2 and not rational:
        surfs.append(samples.load("plate_with_hole")[0])
    bin_ = _binomial_table(D2)
    for s in surfs:
        (a, b), (c, d) = s.domain
        uv = np.column_stack([rng.uniform(a, b, 300), rng.uniform(c, d, 300)])
        ku = np.unique(s.knots_u)
        kv = np.unique(s.knots_v)
        uv = np.vstack([uv, np.column_stack([ku, np.full(ku.size, 0.5 * (c + d))]),
                        np.column_stack([np.full(kv.size, 0.5 * (a + b)), kv]),
                        [[a, c], [b, d], [a, d], [b, c]]])
        scr = derivs_scratch(1, 1, D2)
        S1 = np.empty((3, 3, 3))
        S2 = np.full((3, 3, 3), np.nan)
        S3 = np.full((3, 3, 3), np.nan)
        for u, v in uv:
            surface_derivs(s.homogeneous, 1, 1, s.knots_u, s.knots_v, u, v, D2, bin_, scr, S1)
            derivs2_bilinear(s.homogeneous, s.knots_u, s.knots_v, u, v, S2)
            derivs2(s.homogeneous, 1, 1, s.knots_u, s.knots_v, u, v, scr, S3)
            scale = max(np.abs(S1[k, l]).max() for k, l in ORDERS)
            for k, l in ORDERS:
                assert np.abs(S1[k, l] - S2[k, l]).max() <= 1e-12 * scale, (u, v, k, l)
                assert np.array_equal(S2[k, l], S3[k, l])


def test_candidate_overflow_never_drops_a_candidate():
    """The sphere's centre sees every triangle as a candidate (far more than the 64 of
    the initial buffer): the buffer grows instead of dropping candidates (issue 15: an
    overflow never passes silently), the second pass tries up to RERUN_STARTS_MAX of
    them and a last pass every candidate, so even this point is proven (its answer
    and lower bound hold)."""
    from geomkit.query.projection import RERUN_STARTS_MAX

    sphere = samples.load("sphere")[0]
    P = np.array([[0.0, 0.0, 0.0], [0.0, 0.0, 12.0], [3.0, 1.0, 2.0]])
    pr = geomkit.Projector(sphere)
    assert pr.mesh.faces.shape[0] > RERUN_STARTS_MAX
    res = pr.project(P)
    assert res.stats["candidate_overflow"] >= 1
    assert res.stats["not_proven"] == 0 and res.stats["start_cap_reruns"] >= 2
    assert res.feet_tried[0] == 127  # every candidate (> RERUN_STARTS_MAX), capped at 127
    assert abs(res.distance[0] - 10.0) < 1e-9
    assert abs(res.distance[1] - 2.0) < 1e-9
    assert abs(res.distance[2] - (10.0 - np.sqrt(14.0))) < 1e-9
    assert np.all(res.lower_bound <= res.distance + 1e-12)


def test_scan_points_are_proven():
    """Points near a surface have few candidates: none overflows, all proven."""
    s = samples.load("freeform_1")[0]
    rng = np.random.default_rng(1)
    (a, b), (c, d) = s.domain
    uv = np.column_stack([rng.uniform(a, b, 500), rng.uniform(c, d, 500)])
    P = s.evaluate(uv) + 0.3 * rng.normal(size=(500, 3))
    pr = geomkit.project_points(s, P)
    assert pr.stats["candidate_overflow"] == 0
    assert pr.stats["not_proven"] == 0


def test_kernel_foot_class_equals_classify_uv():
    """The batch kernel classifies every Newton foot against its face's trim loops
    (a foot inside its face prunes candidates; the trim and finish stages reuse the
    class): the classes equal :func:`geomkit.nurbs.trimming.classify_uv` on the same (u, v),
    here for feet inside the plate, outside it over the hole and on the hole's edge
    band, and on a second trimmed face with another degree of trim curve."""
    from geomkit._kernels import project as pk
    from geomkit.tolerances import NEWTON_STEP_TOL

    plate = samples.load("plate_with_hole")[0]
    P0 = np.zeros((2, 2, 3))
    P0[..., 0] = np.array([0.0, 100.0])[:, None]
    P0[..., 1] = np.array([0.0, 100.0])[None, :]
    tri = geomkit.Surface(1, 1, [0, 0, 1, 1], [0, 0, 1, 1], P0 + [0, 0, -5.0],
                          trim=[[[0.1, 0.1], [0.9, 0.1], [0.1, 0.9], [0.1, 0.1]]])
    surfaces = [plate, tri]
    pr = geomkit.Projector(surfaces)
    rng = np.random.default_rng(4)
    P = np.c_[rng.uniform(-10, 110, (3000, 2)), rng.uniform(-8, 4, 3000)]
    P[:200, :2] = [50.0, 50.0] + 20.0 * np.c_[np.cos(a := rng.uniform(0, 7, 200)),
                                             np.sin(a)] * (1 + 1e-12 * rng.normal(size=(200, 1)))
    n, K = len(P), 16
    fs = np.full((n, K), -1, dtype=np.int64)
    fuv = np.zeros((n, K, 2))
    fd = np.full((n, K), np.inf)
    fst = np.zeros((n, K), dtype=np.int64)
    fcls = np.full((n, K), 9, dtype=np.int8)
    nf = np.zeros(n, dtype=np.int64)
    g = pr.grid
    pk.project_batch(P, g.vertices, g.faces, pr.fdev, pr.face_surf, pr.face_uv, pr.dmax,
                     *g._args(), *pr.packed, pr.closed, pr.trimmed, *pr.breaks,
                     *pr.trim_pack, *pr.cert_pack, 1, NEWTON_STEP_TOL * pr.size,
                     np.full(n, np.inf), K,
                     np.zeros(n, dtype=np.int64), fs, fuv, fd, fst, fcls,
                     nf, np.zeros(n), np.full(n, np.inf), np.zeros(n, dtype=np.int64),
                     np.zeros((n, 5), dtype=np.int64))
    seen = set()
    for si, s in enumerate(surfaces):
        m = fs == si
        assert m.any()
        ref = s.classify_uv(fuv[m])
        assert np.array_equal(fcls[m], ref)
        seen |= {(si, int(c)) for c in np.unique(ref)}
    assert {(0, geomkit.INSIDE), (0, geomkit.OUTSIDE), (1, geomkit.INSIDE),
            (1, geomkit.OUTSIDE)} <= seen


def test_borrowed_views_count_nothing_and_free_nothing():
    """borrow_all (geomkit._kernels.numba_ext.borrow): the views read and write the owners'
    data, nested tuples included, and leave every allocation balanced (a borrowed
    array passed through unborrowed inside a tuple freed its owner early: a crash in
    the projection kernels)."""
    from numba import njit
    from numba.core.runtime import _nrt_python as nrt, rtsys

    from geomkit._kernels.numba_ext.borrow import borrow_all

    def body(n, flags, scr, a):
        x, (y, z) = scr
        tot = 0.0
        for i in range(n):
            if flags.shape[0] <= i % 70:  # rebound to an owned array (counted)
                flags = np.zeros(2 * flags.shape[0], dtype=np.int8)
            flags[i % 70] = 1
            y[i % y.shape[0]] += 1.0
            z[0] = i
            tot += a[i % a.shape[0]] + flags.sum()
        return tot + x.sum() + y.sum() + z[0]

    jbody = njit(body)

    @njit
    def inner(n, flags, scr, a):
        flags, scr, a = borrow_all((flags, scr, a))
        return jbody(n, flags, scr, a)

    @njit
    def outer(n, a):
        return inner(n, np.zeros(8, dtype=np.int8),
                     (np.ones(3), (np.zeros(4), np.zeros(2))), a)

    a = np.arange(5.0)
    outer(10, a)
    was = nrt.memsys_stats_enabled()
    nrt.memsys_enable_stats()
    try:
        before = rtsys.get_allocation_stats()
        for _ in range(200):
            got = outer(100, a)
        after = rtsys.get_allocation_stats()
    finally:
        if not was:
            nrt.memsys_disable_stats()
    assert after.alloc - before.alloc == after.free - before.free > 0
    assert after.mi_alloc - before.mi_alloc == after.mi_free - before.mi_free
    assert got == body(100, np.zeros(8, dtype=np.int8),
                       (np.ones(3), (np.zeros(4), np.zeros(2))), a)
    assert sys.getrefcount(a) == 2  # a is not counted twice, nor released


def test_borrow_all_refuses_what_it_cannot_borrow():
    from numba import njit
    from numba.core.errors import TypingError

    from geomkit._kernels.numba_ext.borrow import borrow_all

    @njit
    def f(lst):
        return borrow_all((lst,))

    with pytest.raises(TypingError):
        f([np.zeros(2)])
