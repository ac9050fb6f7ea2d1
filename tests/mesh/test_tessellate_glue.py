"""Per-face helpers of tessellate rewritten for fewer numpy calls give the same values
as the formulas they replace:

* :func:`geomkit.mesh.trim_polylines.packed_trims` (from each loop's kept pack)
  against the piece-by-piece concatenation, one loop and several;
* :func:`geomkit.mesh.cells.closed_directions` (open-both-ways surfaces answered from
  the net's corners) against the 17-sample test alone, on every sample surface and on
  nets closed, nearly closed and open in each direction;
* :func:`geomkit.mesh.quadtree._lines` against the span-by-span formula, bit for bit.
"""

from __future__ import annotations

import importlib
import itertools
import warnings

import numpy as np

from geomkit import Surface, samples
from geomkit.cad.step import read_step
from geomkit.mesh.trim_polylines import packed_trims
from geomkit.mesh.weld import points

from helpers.paths import DATA

C = importlib.import_module("geomkit.mesh.cells")
Q = importlib.import_module("geomkit.mesh.quadtree")


def _packed_by_piece(surface):
    cps, ws, ks, deg, npl = [], [], [], [], []
    for loop in surface.trim:
        npl.append(len(loop.pieces))
        for c in loop.pieces:
            cps.append(c.control_points)
            ws.append(c.weights)
            ks.append(c.knots)
            deg.append(c.degree)
    return (np.concatenate(cps), np.concatenate(ws), np.concatenate(ks),
            np.array(deg, dtype=np.int64),
            np.cumsum([0] + [len(w) for w in ws]).astype(np.int64),
            np.cumsum([0] + [len(k) for k in ks]).astype(np.int64),
            np.cumsum([0] + npl).astype(np.int64))


def test_packed_trims_match_the_piece_by_piece_concatenation():
    seen = {1: 0, 2: 0}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        part = read_step(DATA / "parts" / "nx9_face_recognition_ap214.stp").surfaces
    for name, surfaces in [(n, samples.load(n)) for n in samples.names()] + [("nx9", part)]:
        for s in surfaces:
            if not s.trim:
                continue
            seen[min(len(s.trim), 2)] += 1
            for a, b in zip(packed_trims(s), _packed_by_piece(s)):
                assert a.dtype == b.dtype and np.array_equal(a, b), name
    assert seen[1] and seen[2]  # one loop and several


def _closed_by_samples(s, size):
    """The 17-sample test alone (closed_directions before its corner shortcut)."""
    (u0, u1), (v0, v1) = s.domain
    eps = 1e-10 * size
    t = np.linspace(0.0, 1.0, 17)
    v = v0 + (v1 - v0) * t
    u = u0 + (u1 - u0) * t
    uv = np.empty((4, 17, 2))
    uv[0, :, 0], uv[1, :, 0], uv[:2, :, 1] = u0, u1, v
    uv[2, :, 1], uv[3, :, 1], uv[2:, :, 0] = v0, v1, u
    P = points(s, uv.reshape(-1, 2)).reshape(4, 17, 3)
    return (bool(np.abs(P[0] - P[1]).max() <= eps), bool(np.abs(P[2] - P[3]).max() <= eps))


def _net(closed_u, closed_v, gap, rng):
    """A bicubic net whose last row (column) repeats the first (closed_u / closed_v),
    moved by ``gap`` (a multiple of the closure threshold, 0: exactly closed)."""
    P = rng.random((5, 6, 3))
    if closed_u:
        P[-1] = P[0] + gap
    if closed_v:
        P[:, -1] = P[:, 0] + gap
    if closed_u and closed_v:
        P[-1, -1] = P[0, 0] + gap
    k = lambda n: np.r_[[0.0] * 4, np.linspace(0, 1, n - 2)[1:-1], [1.0] * 4]  # noqa: E731
    return Surface(3, 3, k(5), k(6), P)


def test_closed_directions_matches_the_sampled_test():
    checked = 0
    for name in samples.names():
        for s in samples.load(name):
            assert C.closed_directions(s, s.size) == _closed_by_samples(s, s.size), name
            checked += 1
    rng = np.random.default_rng(3)
    for trial in range(60):
        cu, cv = bool(trial & 1), bool(trial & 2)
        s = _net(cu, cv, 0.0, rng)
        eps = 1e-10 * s.size
        gap = float(rng.choice([0.0, 0.5, 0.99, 1.01, 2.0, 2.1, 10.0])) * eps
        s = _net(cu, cv, gap, rng)
        got = C.closed_directions(s, s.size)
        assert got == _closed_by_samples(s, s.size), (trial, gap / eps)
        checked += 1
    assert checked > 60


def _lines_by_span(b, counts):
    parts = [b[i] + (b[i + 1] - b[i]) * (np.arange(c) / c) for i, c in enumerate(counts.tolist())]
    return np.concatenate(parts + [b[-1:]])


def test_grid_lines_match_the_span_by_span_formula():
    rng = np.random.default_rng(5)
    for trial in range(200):
        n = int(rng.integers(1, 12))
        b = np.cumsum(np.r_[rng.normal() * 10.0 ** rng.integers(-3, 4),
                            rng.random(n) * 10.0 ** rng.integers(-6, 3)])
        counts = rng.integers(1, 9, size=n) if trial % 3 else np.ones(n, dtype=np.int64)
        got = Q._lines(b, counts)
        want = _lines_by_span(b, counts)
        assert got.dtype == want.dtype and np.array_equal(got.view(np.int64),
                                                          want.view(np.int64)), trial


def _grid_both_ways(s, tol, pair, monkeypatch, box=None):
    ub = C.breakpoints(s.knots_u, s.degree_u)
    vb = C.breakpoints(s.knots_v, s.degree_v)
    if box is not None:  # the box's lines, as the box route makes them
        a0, a1, b0, b1 = box
        ub = np.concatenate([[a0], ub[(ub > a0) & (ub < a1)], [a1]])
        vb = np.concatenate([[b0], vb[(vb > b0) & (vb < b1)], [b1]])
    m = max(5, 2 * max(s.degree_u, s.degree_v) + 1)
    args = (s, ub, vb, m, 6, tol, C.CELL_TARGET * tol, C.EXACT_ABOVE * tol, 4096)
    closed = C.closed_directions(s, s.size)
    got = Q.uniform_grid(*args, box=box, pair=pair, closed=closed)
    with monkeypatch.context() as mp:
        mp.setattr(Q, "SMALL_GRID", -1)  # every grid by the Python steps
        want = Q.uniform_grid(*args, box=box, pair=pair, closed=closed)
    return got, want


def test_small_grid_kernel_matches_the_python_steps(monkeypatch):
    """The first grid in one compiled call (kept, failed and retried by the Python
    steps, or too big) against the Python steps alone, bit for bit, on the whole
    domain and on a box inside it."""
    kinds = set()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        part = read_step(DATA / "parts" / "euclid_screw_ap214.step").surfaces
    cases = [(s, t) for n in samples.names() for s in samples.load(n)
             for t in (1e-1, 1e-2, 1e-3)] + [(s, t) for s in part for t in (0.05, 0.01)]
    for (s, tol), inner in itertools.product(cases, (False, True)):
        box = None
        if inner:  # a box inside the domain (the box route: a face on a rectangle)
            (u0, u1), (v0, v1) = s.domain
            box = (u0 + 0.1 * (u1 - u0), u0 + 0.8 * (u1 - u0),
                   v0 + 0.2 * (v1 - v0), v0 + 0.9 * (v1 - v0))
        for pair in (False, True):
            got, want = _grid_both_ways(s, tol, pair, monkeypatch, box)
            assert (got is None) == (want is None)
            if got is None:
                kinds.add("refused")
                continue
            kinds.add("small" if len(got[2]) <= Q.SMALL_GRID else "big")
            for a, b in zip(got[:3] + got[3], want[:3] + want[3]):
                assert a.dtype == b.dtype and np.array_equal(a, b)
    assert kinds == {"refused", "small", "big"}


def _grid_cases(part_name):
    """``(surface, ub, vb, m)`` of every sample surface and every face of a real part:
    the domain's breakpoints and the estimates' samples as the tessellator takes them."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        part = read_step(DATA / "parts" / part_name).surfaces
    for s in [s for n in samples.names() for s in samples.load(n)] + list(part):
        yield (s, C.breakpoints(s.knots_u, s.degree_u), C.breakpoints(s.knots_v, s.degree_v),
               max(5, 2 * max(s.degree_u, s.degree_v) + 1))


def test_planned_grid_is_the_grid_small_grid_measures():
    """``quadtree.planned_grid`` (the trimmed faces' grid of the estimates) against the
    grid :func:`geomkit._kernels.tess_grid.small_grid` measures: the same cells, bit for
    bit, each cell's diagonal the one of the smaller estimate (small_grid measures it
    first)."""
    from geomkit._kernels.tess import cell_errors
    from geomkit._kernels.tess_grid import GRID_FAILED, GRID_OK, small_grid

    seen = folded = 0
    for s, ub, vb, m in _grid_cases("euclid_screw_ap214.step"):
        (u0, u1), (v0, v1) = s.domain
        closed = C.closed_directions(s, s.size)
        fold = Q.fold_lines(s, None, closed)
        for tol in (1e-1 * s.size, 1e-3 * s.size):
            st, u, v, cells, dev, diag, E, cu, cv, worst = small_grid(
                s.homogeneous, s.degree_u, s.degree_v, s.knots_u, s.knots_v, ub, vb, m, 6,
                tol, C.CELL_TARGET * tol, tol, 4096, 4096, u0, u1, v0, v1, True, fold)
            got = Q.planned_grid(s, ub, vb, m, C.CELL_TARGET * tol, 4096, closed)
            if st not in (GRID_OK, GRID_FAILED):
                assert got is None
                continue
            seen += 1
            assert np.array_equal(got[0], cells)
            # the diagonal of the smaller estimate (the domain's edge sags folded in)
            Ec = np.empty((len(cells), 5))
            cell_errors(s.homogeneous, s.degree_u, s.degree_v, s.knots_u, s.knots_v,
                        np.ascontiguousarray(cells), m, Ec, box=tuple(fold))
            assert np.array_equal(got[1], (Ec[:, 1] < Ec[:, 0]).astype(np.int64))
            folded += int(np.isnan(fold).any())
    assert seen > 20 and folded > 2


def test_whole_grid_kernel_matches_the_grid_weld_and_closed_steps():
    """``tess_grid.whole_grid`` (a whole face's first grid, its triangles, vertices and
    closed directions in one call) against ``quadtree.uniform_grid``, ``weld.weld_grid``
    and ``cells.closed_directions``, bit for bit, on every sample surface (poles, seams,
    creases) and the faces of a part with cylinders and cones; where its first grid is
    not kept, uniform_grid going on from it (``first``) as from its own."""
    from geomkit._kernels.tess_grid import GRID_OK, whole_grid
    from geomkit.mesh.weld import boundary_pairs, merge, weld_grid
    from geomkit.tolerances import WELD_REL

    kept = closed = went_on = 0
    for s, ub, vb, m in _grid_cases("ug16_io1_ap214.stp"):
        size = s.size
        for tol in (1e-2 * size, 1e-3 * size):
            got = whole_grid(s.homogeneous, s.degree_u, s.degree_v, s.knots_u, s.knots_v, 6,
                             tol, C.CELL_TARGET * tol, C.EXACT_ABOVE * tol, 4096,
                             Q.SMALL_GRID, True, WELD_REL * size, 1e-10 * size, C.EDGE_T)
            want = Q.uniform_grid(s, ub, vb, m, 6, tol, C.CELL_TARGET * tol,
                                  C.EXACT_ABOVE * tol, 4096, pair=True,
                                  closed=C.closed_directions(s, size))
            if got[0] != GRID_OK:  # the Python steps go on from the kernel's first grid
                again = Q.uniform_grid(s, ub, vb, m, 6, tol, C.CELL_TARGET * tol,
                                       C.EXACT_ABOVE * tol, 4096, pair=True,
                                       closed=(bool(got[10]), bool(got[11])), first=got[12])
                assert (again is None) == (want is None)
                if want is not None:
                    for a, b in zip(again[:3] + again[3], want[:3] + want[3]):
                        assert a.dtype == b.dtype and np.array_equal(a, b)
                went_on += 1
                continue
            tri_uv, dev, cells, (u, v, diag) = want
            for a, b in zip(got[1:4], (tri_uv, dev, cells)):
                assert a.dtype == b.dtype and np.array_equal(a, b)
            welded = weld_grid(s, u, v, diag, size)
            assert got[4] == (welded is not None)
            P, UV, inv, bnd, near = got[5:10]
            pairs = boundary_pairs(P, bnd, size) if near else ()
            mine = (merge(P, UV, inv, pairs) if len(pairs) else
                    (P, inv.reshape(-1, 3), UV, np.ones(len(inv) // 3, dtype=bool)))
            for a, b in zip(mine, welded):
                assert a.dtype == b.dtype and np.array_equal(a, b)
            assert (bool(got[10]), bool(got[11])) == C.closed_directions(s, size)
            kept += 1
            closed += bool(got[10] or got[11])
    assert kept > 30 and closed > 3 and went_on > 3


def test_trimmed_first_kernel_makes_the_mesh_of_the_steps(monkeypatch):
    """A trimmed face's first grid in one call
    (:func:`geomkit._kernels.tess_face.trimmed_first`) against the steps of
    ``tessellate._trimmed_grid`` (``FIRST_CELLS = 0``): the same mesh, bit for bit
    (vertices, faces, UVs, deviations, stats), on real parts whose faces take each
    way out of the kernel: a mesh, a failed measure (the steps go on from the second
    grid: NIST CTC-01) and a cut cell left to GEOS (CTC-05)."""
    from geomkit import tessellate
    from geomkit._kernels.tess_face import FACE_FAILED, FACE_LEFT, FACE_OK

    T = importlib.import_module("geomkit.mesh.tessellate")
    first = T._trimmed_first
    seen = set()

    def counted(*args):
        out = first(*args)
        seen.add(int(out[0]))
        return out

    monkeypatch.setattr(T, "_trimmed_first", counted)
    most = T.FIRST_CELLS
    for part in ("inventor2015_cylinder_block_face6.stp", "nist_ctc_01_ap203.stp",
                 "nist_ctc_05_ap203.stp"):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            S = read_step(DATA / "parts" / part).surfaces
        B = np.array([s.bounds for s in S])
        tol = 1e-3 * float(np.linalg.norm(B[:, 1].max(axis=0) - B[:, 0].min(axis=0)))
        a = tessellate(S, tol)
        monkeypatch.setattr(T, "FIRST_CELLS", 0)  # every first grid by the steps
        b = tessellate(S, tol)
        monkeypatch.setattr(T, "FIRST_CELLS", most)
        for x, y in ((a.vertices, b.vertices), (a.faces, b.faces), (a.uv, b.uv),
                     (a.face_deviation, b.face_deviation), (a.face_surface, b.face_surface)):
            assert np.array_equal(x, y)
        for sa, sb in zip(a.stats["surfaces"], b.stats["surfaces"]):
            assert {k: v for k, v in sa.items() if k != "seconds"} == \
                {k: v for k, v in sb.items() if k != "seconds"}
    assert {FACE_OK, FACE_FAILED, FACE_LEFT} <= seen
