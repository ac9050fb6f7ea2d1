"""The trim polylines kernel's shortcuts against the route they replaced, bit for bit:
each 1/16 grid point's ``S(C(t))`` evaluated once per piece (``grid_cache``) against
evaluating it at every test, and a sample's knot span taken from the segment's part
(``_span_of``) against the binary search (``_curve_at``).  On every trimmed face of
four real parts, at two chord tolerances, with and without segments across smooth
knots."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

from geomkit._kernels.tess_trim import _curve_at, _curve_in_span, _span_of, trim_polylines
from geomkit.cad.step import read_step
from geomkit.mesh.trim_polylines import SEED_SPANS, affine_map, packed_trims

from helpers.paths import DATA

PARTS = ["nx9_face_recognition_ap214.stp", "nist_ftc_07_ap242.stp",
         "catia_v5_ventilator_swept_faces.stp", "nist_ctc_05_ap203.stp"]


def _surfaces(part):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        S = read_step(DATA / "parts" / part).surfaces
    B = np.array([s.bounds for s in S])
    return S, float(np.linalg.norm(B[:, 1].max(axis=0) - B[:, 0].min(axis=0)))


def _run(s, chord_tol, cross_knots, grid_cache):
    (u0, u1), (v0, v1) = s.domain
    CP, W, K, deg, cp_off, k_off, _ = packed_trims(s)
    counts = np.empty(len(deg), dtype=np.int64)
    out = np.empty((100_000, 3))
    n = trim_polylines(CP, W, K, deg, cp_off, k_off, SEED_SPANS, u0, v0, u1, v1,
                       s.homogeneous, s.degree_u, s.degree_v, s.knots_u, s.knots_v, chord_tol,
                       chord_tol, 2 * chord_tol, affine_map(s, s.size) is None, cross_knots,
                       out, counts, grid_cache)
    assert n > 0
    return out[:n].copy(), counts


@pytest.mark.parametrize("part", PARTS)
def test_grid_cache_gives_the_same_polylines(part):
    S, size = _surfaces(part)
    rows = 0
    for s in S:
        if not s.trim:
            continue
        for rel in (1e-3, 1e-4):
            for cross in (False, True):
                a, ca = _run(s, 0.5 * rel * size, cross, True)
                b, cb = _run(s, 0.5 * rel * size, cross, False)
                assert np.array_equal(ca, cb)
                assert a.tobytes() == b.tobytes()
                rows += len(a)
    assert rows > 100


def test_span_from_the_part_is_the_binary_search_span():
    rng = np.random.default_rng(3)
    S, _ = _surfaces("nist_ftc_07_ap242.stp")
    checked = 0
    for s in S[:80]:
        for loop in s.trim or ():
            for c in loop.pieces:
                Pc, pc, Uc = c.homogeneous, c.degree, np.asarray(c.knots, dtype=np.float64)
                (u0, u1), (v0, v1) = s.domain
                N, lft, rgt = np.empty(pc + 1), np.empty(pc + 1), np.empty(pc + 1)
                ks = np.unique(Uc[pc: len(Uc) - pc])
                ts = np.concatenate([ks, rng.uniform(ks[0], ks[-1], 20),
                                     np.nextafter(ks, -np.inf)[1:], np.nextafter(ks, np.inf)[:-1]])
                for t in ts:
                    want = _curve_at(Pc, pc, Uc, t, u0, v0, u1, v1, N, lft, rgt)
                    for hint in range(pc, len(Uc) - pc - 1):  # every span as the hint
                        got = _curve_in_span(Pc, pc, Uc, _span_of(Pc, pc, Uc, t, hint), t, u0,
                                             v0, u1, v1, N, lft, rgt)
                        assert got == want
                        checked += 1
    assert checked > 1000
