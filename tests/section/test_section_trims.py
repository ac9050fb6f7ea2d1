"""The binned trim classification of section points (geomkit/_kernels/section_trims.py)
against the plain one: ``outside_binned`` walks only the trim segments of one bin over
v and must give ``classify_point``'s answer (after the domain test) exactly, for
points on the trim curves, at and around the band's distances from them, on the bins'
edges and the segments' grown v-ranges (one ulp either side), and anywhere in the
domain; with the bins built for the tolerance used and for a larger one.  With the
halvings of the trim segments kept from point to point (``winding_tree``, shared by
every probe, and one with room for 9 nodes that runs out), the same answers."""

from __future__ import annotations

import numpy as np
import pytest

from geomkit import samples
from geomkit._kernels import section_trims as T
from geomkit._kernels.trim import MAX_DEPTH, OUTSIDE, classify_point
from geomkit.cad.occ import HAVE_OCP
from geomkit.tolerances import TRIM_TOL
from helpers.paths import DATA


def _curve_points(seg, deg, t):
    """Points of each rational Bézier segment at the parameters ``t`` (de Casteljau)."""
    out = []
    for Q, d in zip(seg, deg):
        for tt in t:
            P = Q[:d + 1].copy()
            for r in range(d):
                P = (1 - tt) * P[:-1] + tt * P[1:]
            out.append(P[0, :2] / P[0, 2])
    return np.array(out)


def _probe_points(s, seg, deg, tol, rng):
    (u0, u1), (v0, v1) = s.domain
    on = _curve_points(seg, deg, np.r_[0.0, 1.0, rng.random(6)])
    pts = [on]
    for k in (0.125, 0.25, 0.5, 1.0, 1.5, 2.0, 2.5, 3.0):
        for sgn in (-1, 1):
            pts.append(on + sgn * k * tol * np.array([0.0, 1.0]))
            pts.append(on + sgn * k * tol * np.array([1.0, 0.0]))
    pts.append(np.column_stack([rng.uniform(u0, u1, 400), rng.uniform(v0, v1, 400)]))
    # v on the bins' edges and the segments' grown ranges, one ulp either side
    vlo, w, nb, _off, _items = T.trim_bins(seg, deg, tol)
    vs = [vlo + k * w for k in range(nb + 1)] if np.isfinite(w) else []
    ys = seg[:, :, 1] / seg[:, :, 2]
    for Q, d, y in zip(seg, deg, ys):
        lo, hi = y[:d + 1].min(), y[:d + 1].max()
        g = 2 * tol + 1e-15 * (abs(lo) + abs(hi)) if d == 1 else 0.25 * tol
        vs += [lo - g, hi + g, lo, hi]
    vs = np.array(vs)
    vs = np.concatenate([vs, np.nextafter(vs, -np.inf), np.nextafter(vs, np.inf)])
    us = rng.choice(on[:, 0], len(vs))
    pts.append(np.column_stack([us, vs]))
    return np.concatenate(pts)


def _check(s, rng):
    seg, deg, lp, nloops = s.trim_segments()
    (u0, u1), (v0, v1) = s.domain
    box = np.array([u0, u1, v0, v1])
    band = TRIM_TOL * max(u1 - u0, v1 - v0)
    p1 = seg.shape[1]
    scratch = (np.empty(max(nloops, 1), np.int64), np.empty((MAX_DEPTH + 2, p1, 3)),
               np.empty(MAX_DEPTH + 2, np.int64), np.empty((p1, 3)), np.empty((p1, 3)))
    tree = T.winding_tree(seg)
    small = (np.full(len(seg), -1, np.int64), np.empty((9, p1, 3)), np.empty((9, 8)),
             np.empty(9, np.int64), np.empty(9, np.int64), np.zeros(1, np.int64))
    nodes = np.empty(MAX_DEPTH + 2, np.int64)
    n = 0
    for tol, built in ((band, band), (1e-14 * max(u1 - u0, v1 - v0), band), (band, 7 * band)):
        bins = T.trim_bins(seg, deg, built)
        for u, v in _probe_points(s, seg, deg, tol, rng):
            want = bool(T._off_domain(u, v, box, tol)) or (
                classify_point(seg, deg, lp, nloops, u, v, tol, *scratch) == OUTSIDE)
            for t in (None, tree, small):
                got = T.outside_binned(seg, deg, lp, nloops, u, v, box, tol, bins, *scratch,
                                       t, None if t is None else nodes)
                assert got == want, (s.name, u, v, tol, built, t is None)
            n += 1
    return n


def test_tree_winding_is_segment_winding():
    """Random rational segments of degrees 2-5 and points on them, near them (1e-15 to
    1e-1 of their size, either side) and anywhere: ``_tree_winding`` with one tree for
    all the points gives ``_segment_winding``'s (winding, on) for each, at several
    tolerances, and the tree runs full on the way (the rest walked as before)."""
    from geomkit._kernels.trim import _segment_winding
    rng = np.random.default_rng(7)
    for deg in (2, 3, 4, 5):
        seg = np.zeros((6, 6, 3))
        for k in range(6):
            seg[k, :deg + 1, :2] = rng.uniform(-1, 1, (deg + 1, 2)).cumsum(axis=0)
            seg[k, :deg + 1, 2] = rng.uniform(0.3, 3.0, deg + 1)
            seg[k, :deg + 1, :2] *= seg[k, :deg + 1, 2:3]
        degs = np.full(6, deg, np.int64)
        on = _curve_points(seg, degs, rng.random(40))
        d = 10.0 ** rng.uniform(-15, -1, (len(on), 1)) * rng.choice([-1, 1], (len(on), 2))
        pts = np.concatenate([on, on + d, rng.uniform(-3, 8, (200, 2))])
        tree = T.winding_tree(seg)
        scr = (np.empty((MAX_DEPTH + 2, 6, 3)), np.empty(MAX_DEPTH + 2, np.int64),
               np.empty((6, 3)), np.empty((6, 3)))
        nodes = np.empty(MAX_DEPTH + 2, np.int64)
        for tol in (1e-14, 1e-9, 1e-3):
            for s in range(6):
                for x, y in pts:
                    want = _segment_winding(seg[s], deg, x, y, tol, *scr)
                    got = T._tree_winding(tree, s, seg[s], deg, x, y, tol, nodes, *scr)
                    assert tuple(got) == tuple(want), (deg, s, x, y, tol)
        assert tree[5][0] > T.TREE_NODES - 2


def test_outside_binned_on_the_plate_with_hole():
    s = samples.load("plate_with_hole")[0]
    assert _check(s, np.random.default_rng(0)) > 1000


def test_trim_bins_hold_every_segment_somewhere():
    """Every segment is in the bins of its grown v-range; one bin when tol**2 would not
    be a normal number."""
    s = samples.load("plate_with_hole")[0]
    seg, deg, _lp, _n = s.trim_segments()
    vlo, w, nb, off, items = T.trim_bins(seg, deg, 1e-9)
    assert nb > 1 and set(items.tolist()) == set(range(len(seg)))
    assert off[0] == 0 and off[-1] == len(items) and np.all(np.diff(off) >= 0)
    vlo, w, nb, off, items = T.trim_bins(seg, deg, 1e-200)
    assert nb == 1 and items.tolist() == list(range(len(seg)))


@pytest.mark.occ
@pytest.mark.skipif(not HAVE_OCP, reason="reading STEP needs cadquery-ocp")
@pytest.mark.parametrize("part", ["nist_ctc_05_ap203.stp", "euclid_screw_ap214.step"])
def test_outside_binned_on_real_faces(part):
    """The faces with the most trim segments of two parts (lines, arcs, splines)."""
    from geomkit.cad.step import read_step

    S = [s for s in read_step(DATA / "parts" / part).surfaces if s.is_trimmed]
    S = sorted(S, key=lambda s: -len(s.trim_segments()[0]))[:4]
    rng = np.random.default_rng(1)
    assert sum(_check(s, rng) for s in S) > 4000
