"""The shortcuts of plane_section give exactly what the plain steps give.

Each fast path (faces rejected by their control net's bounds, the densification and
trim bisection kernels, classification of a run of curve points by one, the pairing of
curve ends from one distance matrix, the nearest-segment search of the boundary
distance) is compared, bit for bit, with the plain computation it replaces, written
out here as the oracle (the loops plane_section ran before)."""

from __future__ import annotations

import numpy as np
import pytest

import geomkit
from geomkit import samples
from geomkit.nurbs.trimming import OUTSIDE
from geomkit.section import clip as clip_mod, joins, plane as plane_mod
from geomkit.section.trace import _Eval, trace_surface
from geomkit.cad.occ import HAVE_OCP
from helpers.paths import DATA


def _plate():
    return samples.load("plate_with_hole")[0]


def _chains(s, plane, tol=1e-6):
    plane = plane_mod.as_plane(plane)
    P = s.control_points.reshape(-1, 3)
    scale = float(np.abs(plane[3]) + np.abs(P).max())
    zsnap = 64 * np.finfo(float).eps * scale
    chains, _, _ = trace_surface(s, plane, tol, zsnap, max(0.25 * tol, 1e-13 * scale))
    return _Eval(s, plane), chains, zsnap


def _dom(ev):
    return max(ev.box[1] - ev.box[0], ev.box[3] - ev.box[2])


# ------------------------------------------------------------- oracles: the plain loops
def _densify_rounds(ev, uv, h, zsnap):
    for _ in range(40):
        seg = np.linalg.norm(np.diff(uv, axis=0), axis=1)
        long_ = np.nonzero(seg > h)[0]
        if not len(long_):
            break
        mid, _f = ev.project(0.5 * (uv[long_] + uv[long_ + 1]), seg[long_], 0.25 * zsnap)
        uv = np.insert(uv, long_ + 1, mid, axis=0)
    return uv


def _boundaries_bisection(s, ev, a_in, b_out, zsnap, iters=60):
    a, b = a_in.copy(), b_out.copy()
    band = 1e-14 * max(ev.box[1] - ev.box[0], ev.box[3] - ev.box[2])
    along = s.classify_uv(a, band) == OUTSIDE
    act = np.arange(len(a))
    for _ in range(iters):
        m, _f = ev.project(0.5 * (a[act] + b[act]), np.linalg.norm(b[act] - a[act], axis=1),
                           0.25 * zsnap)
        o = np.empty(len(act), bool)
        wide = along[act]
        if (~wide).any():
            o[~wide] = s.classify_uv(m[~wide], band) == OUTSIDE
        if wide.any():
            o[wide] = s.classify_uv(m[wide]) == OUTSIDE
        b[act[o]] = m[o]
        a[act[~o]] = m[~o]
        act = act[np.linalg.norm(b[act] - a[act], axis=1) > 1e-13]
        if not len(act):
            break
    return a


def _join_ends_plain(curves, tol, bridged, exact):
    curves = list(curves)
    while True:
        opens = [i for i, c in enumerate(curves) if not c["closed"]]
        if not opens:
            return curves
        E = np.array([[curves[i]["X"][0], curves[i]["X"][-1]] for i in opens]).reshape(-1, 3)
        D = np.linalg.norm(E[:, None] - E[None], axis=2)
        np.fill_diagonal(D, np.inf)
        for k, i in enumerate(opens):
            D[2 * k, 2 * k + 1] = D[2 * k + 1, 2 * k] = (
                D[2 * k, 2 * k + 1] + exact if len(curves[i]["X"]) > 2 else np.inf)
        a, b = divmod(int(np.argmin(D)), len(E))
        dist = float(np.linalg.norm(E[a] - E[b]))
        if not (np.isfinite(D[a, b]) and dist <= tol):
            return curves
        bridged[0] = max(bridged[0], dist)
        i, j = opens[a // 2], opens[b // 2]
        dup = dist <= exact
        if i == j:
            c = curves[i]
            c["closed"] = True
            if dup:
                for k in ("uv", "sid", "X"):
                    c[k] = c[k][:-1]
            continue
        A = curves[i] if a % 2 else joins._rev(curves[i])
        B = joins._rev(curves[j]) if b % 2 else curves[j]
        merged = {k: (np.concatenate([A[k], B[k][int(dup):]]) if k in ("uv", "sid", "X")
                      else A[k]) for k in A}
        merged["chord"] = max(A["chord"], B["chord"])
        curves = [c for k, c in enumerate(curves) if k not in (i, j)] + [merged]


# ------------------------------------------------------------- kernels against loops
@pytest.mark.parametrize("plane", [[0, 1, 0, -50], [1, -1, 0, 0], [1, 0.3, 0, -60]])
def test_densify_and_trim_bisection_kernels_give_the_loops_points(plane):
    s = _plate()
    ev, chains, zsnap = _chains(s, plane)
    assert chains
    rng = np.random.default_rng(3)
    for c in chains:
        for h in (1e-3, 1.0 / 64, 0.3):
            h = h * _dom(ev)
            fast = clip_mod._densify(ev, c["uv"], h, zsnap)
            assert np.array_equal(fast, _densify_rounds(ev, c["uv"], h, zsnap))
        uv = clip_mod._densify(ev, c["uv"], clip_mod.TRIM_STEP * _dom(ev), zsnap)
        out = s.classify_uv(uv) == OUTSIDE
        i = np.flatnonzero(out[1:] != out[:-1])
        assert len(i), "the chain crosses the hole"
        a_in = np.where(out[i][:, None], uv[i + 1], uv[i])
        b_out = np.where(out[i][:, None], uv[i], uv[i + 1])
        # and pairs farther apart (more bisection steps), a few with a_in in the band
        k = rng.integers(0, len(uv), 8)
        ins = ~out[k]
        a_more = np.concatenate([a_in, uv[k[ins]]])
        b_more = np.concatenate([b_out, np.repeat(b_out[:1], ins.sum(), axis=0)])
        for a, b in ((a_in, b_out), (a_more, b_more)):
            fast = clip_mod._boundaries(s, ev, a, b, zsnap)
            assert np.array_equal(fast, _boundaries_bisection(s, ev, a, b, zsnap))


def test_run_classification_gives_every_points_class():
    s = _plate()
    ev, chains, zsnap = _chains(s, [1, 0.3, 0, -60])
    h = clip_mod.TRIM_STEP * _dom(ev)
    uvs = [clip_mod._densify(ev, c["uv"], h, zsnap) for c in chains]
    rng = np.random.default_rng(7)
    (u0, u1), (v0, v1) = s.domain
    # random walks through the domain, grazing the hole and the outer edge
    for _ in range(20):
        steps = rng.normal(size=(400, 2)) * 0.004 * (u1 - u0)
        uvs.append(np.clip(rng.uniform([u0, v0], [u1, v1]) + np.cumsum(steps, axis=0),
                           [u0 - 1e-3, v0], [u1, v1]))
    # points on the trim loops and a hair off them
    from geomkit.nurbs.trims import loop_samples
    for loop in s.trim:
        on = loop_samples(loop, 64)
        uvs += [on, on + 1e-10, on - 3e-9, on[::-1] * (1 + 1e-9)]
    for uv in uvs:
        uv = np.ascontiguousarray(uv)
        assert np.array_equal(clip_mod._not_outside(s, uv), s.classify_uv(uv) != OUTSIDE)


def test_boundary_distance_nearest_segments_as_all_segments():
    s = _plate()
    rng = np.random.default_rng(11)
    b = s.bounds
    P = rng.uniform(b[0] - 5, b[1] + 5, size=(3000, 3))
    P[:, 2] = rng.normal(size=3000) * 0.01
    d = joins.boundary_distance(s, P)
    A, B, _tree, _h = s._cache[("boundary_polyline", 256)]
    brute = np.concatenate([joins._segment_distances(P[i:i + 200, None, :], A[None], B[None])
                            .min(axis=1) for i in range(0, len(P), 200)])
    np.testing.assert_allclose(d, brute, rtol=0, atol=1e-12 * s.size)
    near = joins.boundary_distance(s, P, upto=1.0)
    ok = brute <= 1.0
    np.testing.assert_allclose(near[ok], brute[ok], rtol=0, atol=1e-12 * s.size)
    assert (near[~ok] > 1.0).all()


# ------------------------------------------------------------- joins against the loop
def _random_curves(rng, n):
    """Open and closed curves whose ends meet (exactly, within a hair, within tol),
    with ties, two-point curves and curves that close on themselves."""
    hubs = rng.uniform(-1, 1, size=(max(2, n // 2), 3))
    curves = []
    for k in range(n):
        m = int(rng.choice([2, 2, 3, 5, 9]))
        X = rng.uniform(-1, 1, size=(m, 3))
        X[0] = hubs[rng.integers(len(hubs))]
        X[-1] = hubs[rng.integers(len(hubs))]
        for e in (0, -1):
            r = rng.random()
            if r < 0.3:
                X[e] += rng.normal(size=3) * 1e-9
            elif r < 0.5:
                X[e] += rng.normal(size=3) * 1e-4
        curves.append({"uv": rng.random((m, 2)), "sid": np.full(m, k), "X": X,
                       "closed": bool(rng.random() < 0.1), "chord": float(rng.random())})
    return curves


@pytest.mark.parametrize("seed", range(40))
def test_join_ends_joins_as_the_loop_over_all_pairs(seed, monkeypatch):
    if seed % 4 == 3:   # the fallback for stacks of ends: the loop itself
        monkeypatch.setattr(joins, "HEAP_PAIRS", 0)
    rng = np.random.default_rng(seed)
    curves = _random_curves(rng, int(rng.integers(1, 30)))
    tol, exact = (1e-3, 1e-8) if seed % 2 else (2e-4, 0.0)
    copy = [{k: (v.copy() if isinstance(v, np.ndarray) else v) for k, v in c.items()}
            for c in curves]
    b1, b2 = [0.0], [0.0]
    fast = joins.join_ends(curves, tol, b1, exact=exact)
    plain = _join_ends_plain(copy, tol, b2, exact)
    assert b1 == b2 and len(fast) == len(plain)
    for c, d in zip(fast, plain):
        assert c["closed"] == d["closed"] and c["chord"] == d["chord"]
        for k in ("uv", "sid", "X"):
            assert np.array_equal(c[k], d[k])


# ------------------------------------------------------------- faces rejected by bounds
def _same_section(a, b):
    assert len(a.curves) == len(b.curves) and a.closed == b.closed
    for x, y in zip(a.curves, b.curves):
        assert np.array_equal(x, y)
    for x, y in zip(a.uv, b.uv):
        assert np.array_equal(x, y)
    assert np.array_equal(a.points, b.points) and a.coplanar == b.coplanar
    assert a.max_chord_error == b.max_chord_error and a.max_residual == b.max_residual
    assert a.max_gap_bridged == b.max_gap_bridged and a.failed == b.failed


def _with_and_without_rejection(monkeypatch, surfaces, plane, tol, gap=0.0):
    sec = geomkit.plane_section(surfaces, plane, tol, gap=gap)
    with monkeypatch.context() as m:
        m.setattr(plane_mod, "BOUNDS_MARGIN", np.inf)   # nothing rejected
        every = geomkit.plane_section(surfaces, plane, tol, gap=gap)
    _same_section(sec, every)
    abcd = sec.plane
    rejected = [k for k, st in sec.stats.items() if st["subpatches"] == 0]
    for k in rejected:
        h = surfaces[k].control_points.reshape(-1, 3) @ abcd[:3] + abcd[3]
        assert h.min() > 0 or h.max() < 0
        assert every.stats[k]["leaves"] == 0
    assert all(every.stats[k]["subpatches"] > 0 for k in every.stats)
    return sec, rejected


def test_faces_rejected_by_their_bounds_change_nothing(monkeypatch):
    case = samples.load_case("sphere_pair")
    for plane in ([0, 1, 0, 0], [0, 0, 1, -3], [1, 0, 0, -100]):
        _with_and_without_rejection(monkeypatch, case.surfaces, plane, 1e-5)
    plate = _plate()
    sec, rejected = _with_and_without_rejection(monkeypatch, [plate], [0, 1, 0, -500], 1e-6)
    assert rejected == [0] and len(sec.curves) == 0


@pytest.mark.occ
@pytest.mark.skipif(not HAVE_OCP, reason="reading STEP needs cadquery-ocp")
def test_faces_rejected_by_their_bounds_change_nothing_on_a_real_part(monkeypatch):
    """NIST CTC-01 at its mid-plane z (the slowest section in docs/benchmarks.md):
    most faces miss the plane and are not sectioned; the 11 closed loops are the same
    bits."""
    from geomkit.cad.step import read_step

    case = read_step(DATA / "parts" / "nist_ctc_01_ap203.stp")
    S = case.surfaces
    B = np.array([s.bounds for s in S])
    lo, hi = B[:, 0].min(axis=0), B[:, 1].max(axis=0)
    size = float(np.linalg.norm(hi - lo))
    sec, rejected = _with_and_without_rejection(
        monkeypatch, S, [0, 0, 1, -0.5 * (lo[2] + hi[2])], 1e-4 * size, case.edge_gap)
    assert (len(sec.curves), sum(sec.closed)) == (11, 11)
    assert len(rejected) > len(S) // 4


# ------------------------------------------------------------- distinct rows
def test_unique_rows_as_numpy_unique():
    """trace.unique_rows gives np.unique(axis=0, return_inverse=True): rows of a few
    values (many repeats), signed zeros, integer pairs, and the leaf corners of a
    section of the plate with a hole."""
    from geomkit.section.trace import unique_rows
    from geomkit._kernels import section as K

    rng = np.random.default_rng(5)
    cases = [rng.choice(rng.normal(size=30), size=(3000, 2)),
             rng.integers(0, 50, size=(2000, 2)),
             np.array([[0.0, 1.0], [-0.0, 1.0], [0.0, -0.0], [1.0, 0.0]]),
             rng.normal(size=(1, 2))]
    s = _plate()
    ev, _, zsnap = _chains(s, [1, 0.3, 0, -60])
    bp = s.bezier_patches()
    leaves, _ = K.subdivide(bp.homogeneous, bp.u_breaks, bp.v_breaks, ev.plane, zsnap,
                            1e-7, 80)
    cases.append(np.stack([leaves[:, [0, 1, 1, 0]].ravel(), leaves[:, [2, 2, 3, 3]].ravel()],
                          axis=1))
    for a in cases:
        u, inv = unique_rows(a)
        u_np, inv_np = np.unique(a, axis=0, return_inverse=True)
        assert np.array_equal(u, u_np) and np.array_equal(inv, inv_np.ravel())
        assert np.array_equal(u[inv], a)


def test_unique_rows_small_as_lexsort():
    """The Python sort of up to SMALL_ROWS rows gives the lexsort path's arrays bit for
    bit (signed zeros: the same one kept), and NaN rows go to the lexsort path."""
    from geomkit.section import trace

    rng = np.random.default_rng(11)
    vals = np.array([0.0, -0.0, 1.0, -1.0, 2.5, 1e-300, np.inf, -np.inf])
    for n in list(range(1, trace.SMALL_ROWS + 1)) * 20:
        for a in (rng.choice(vals, size=(n, 2)), rng.integers(-3, 4, size=(n, 2)),
                  rng.normal(size=(n, 2))):
            u, inv = trace.unique_rows(a)
            u0, inv0 = trace._unique_rows_sorted(a)
            assert u.dtype == u0.dtype and inv.dtype == inv0.dtype
            assert np.array_equal(u, u0) and np.array_equal(inv, inv0)
            assert np.array_equal(np.signbit(u), np.signbit(u0))
    a = np.array([[np.nan, 1.0], [0.0, 1.0], [0.0, 1.0]])
    u, inv = trace.unique_rows(a)
    assert np.array_equal(inv, [1, 0, 0]) and len(u) == 2


def test_merge_nodes_as_the_tree():
    """trace._merge_nodes (a close-pair check before the tree) gives the tree's union on
    grids of leaf corners (many equal u and v), with pairs a hair inside and outside
    the radius, and on random points."""
    from scipy.spatial import cKDTree

    from geomkit._kernels import section as K
    from geomkit.section.trace import _merge_nodes

    def tree(uv, r):
        parent = np.arange(len(uv))
        for i, j in cKDTree(uv).query_pairs(r, output_type="ndarray"):
            a, b = parent[i], parent[j]
            while parent[a] != a:
                a = parent[a]
            while parent[b] != b:
                b = parent[b]
            parent[max(a, b)] = min(a, b)
        for i in range(len(uv)):
            while parent[parent[i]] != parent[i]:
                parent[i] = parent[parent[i]]
        return parent

    rng = np.random.default_rng(7)
    r = 1e-11
    g = np.linspace(0, 1, 9)
    grid = np.stack(np.meshgrid(g, g), axis=-1).reshape(-1, 2)
    for k in range(40):
        uv = grid.copy()
        extra = grid[rng.choice(len(grid), 5)]
        off = rng.normal(size=(5, 2))
        off *= r * rng.choice([0.5, 0.999999, 1.000001, 2, 1e3], size=(5, 1)) / np.linalg.norm(
            off, axis=1, keepdims=True)
        uv = np.concatenate([uv, extra + off if k % 2 else rng.random((5, 2))])
        uv = uv[rng.permutation(len(uv))]
        brute = (np.abs(uv[:, None] - uv[None]) <= r * (1 + 1e-9)).all(axis=2)
        np.fill_diagonal(brute, False)
        assert K.has_close_pair(uv, np.lexsort((uv[:, 1], uv[:, 0])), r * (1 + 1e-9)) \
            == brute.any()
        assert np.array_equal(_merge_nodes(uv, r), tree(uv, r))


def _contact_points_plain(ev, contacts, curves, plane, tol):
    sid = np.array([k for k, _ in contacts])
    uv = np.array([q for _, q in contacts])
    X = np.empty((len(uv), 3))
    for k in np.unique(sid):
        m = sid == k
        X[m] = ev[int(k)].points(uv[m])
    f = np.abs(X @ plane[:3] + plane[3])
    order = np.argsort(f, kind="stable")
    curveX = np.concatenate([c["X"] for c in curves]) if curves else np.empty((0, 3))
    keep = []
    for i in order:
        if any(np.linalg.norm(X[i] - X[j]) <= tol for j in keep):
            continue
        if len(curveX) and np.min(np.linalg.norm(curveX - X[i], axis=1)) <= tol:
            continue
        keep.append(i)
    keep = np.array(keep, dtype=np.int64)
    return X[keep], uv[keep], sid[keep]


@pytest.mark.parametrize("seed", range(5))
def test_contact_points_as_the_loop(seed):
    """plane._contact_points (curve points in blocks with grown boxes) keeps the
    candidates the loop over every curve point keeps: candidates on, a hair off and
    about tol from long and short curves, and clustered."""
    class Lift:
        def __init__(self, z):
            self.z = z

        def points(self, uv):
            return np.column_stack([uv, np.full(len(uv), self.z)])

    rng = np.random.default_rng(seed)
    tol = 10.0 ** rng.uniform(-5, -2)
    ev = {0: Lift(0.0), 1: Lift(0.5 * tol), 2: Lift(3 * tol)}
    curves = []
    for k in range(rng.integers(1, 6)):
        t = np.linspace(0, 1, rng.integers(1, 400))[:, None]
        X = np.column_stack([np.cos(3 * t + k), np.sin(2 * t), 0 * t])
        curves.append({"X": X})
    P = np.concatenate([c["X"] for c in curves])
    contacts = []
    for _ in range(60):
        p = P[rng.integers(len(P))]
        d = rng.normal(size=2)
        d *= tol * rng.choice([0.0, 0.5, 0.999999, 1.000001, 2.0, 50.0]) / np.linalg.norm(d)
        contacts.append((int(rng.integers(3)), p[:2] + d))
    plane = np.array([0.0, 0.0, 1.0, 0.0])
    got = plane_mod._contact_points(ev, contacts, curves, plane, tol)
    want = _contact_points_plain(ev, contacts, curves, plane, tol)
    for g, w in zip(got, want):
        assert np.array_equal(g, w)
    assert 0 < len(want[0]) < len(contacts)


# ------------------------------------------------------------- joins over all curves at once
def _drop_shared_edges_plain(curves, tol):
    def poly(c):
        X = c["X"]
        return np.vstack([X, X[:1]]) if c["closed"] else X

    if len(curves) < 2:
        return curves
    amin = np.array([c["X"].min(axis=0) for c in curves])
    amax = np.array([c["X"].max(axis=0) for c in curves])
    drop = set()
    for i, a in enumerate(curves):
        if np.linalg.norm(np.diff(a["X"], axis=0), axis=1).sum() <= 4 * tol:
            continue
        inside = np.flatnonzero((amin[i] >= amin - tol).all(axis=1)
                                & (amax[i] <= amax + tol).all(axis=1))
        for j in inside:
            if j == i or j in drop:
                continue
            if joins._near_polyline(a["X"], poly(curves[j]), tol):
                drop.add(i)
                break
    return [c for k, c in enumerate(curves) if k not in drop]


def _merge_point_curves_plain(curves, exact):
    keep, spots = [], []
    for c in curves:
        X = c["X"]
        if not c["closed"] and len(X) and \
                float(np.linalg.norm(X.max(axis=0) - X.min(axis=0))) <= exact:
            if any(float(np.linalg.norm(X[0] - q)) <= exact for q in spots):
                continue
            spots.append(X[0])
        keep.append(c)
    return keep


def _pieces(rng, n, tol):
    """Open and closed polylines: long ones, copies of parts of them a hair off (shared
    edges), points (one or many samples within tol), and pieces exactly 4 tol long."""
    out = []
    for k in range(n):
        kind = k % 5
        if kind == 0:
            X = np.cumsum(rng.normal(size=(rng.integers(2, 40), 3)), axis=0)
        elif kind == 1 and out:
            Y = out[rng.integers(len(out))]["X"]
            X = Y[: max(1, len(Y) // 2)] + rng.normal(size=(1, 3)) * 0.3 * tol
        elif kind == 2:
            X = rng.normal(size=(1, 3)) + rng.uniform(0, 0.4 * tol, size=(rng.integers(1, 5), 3))
        elif kind == 3:
            d = rng.normal(size=3)
            X = np.array([[0.0, 0, 0], 4 * tol * d / np.linalg.norm(d)]) + rng.normal(size=3)
        else:
            X = rng.normal(size=(rng.integers(3, 9), 3))
        out.append({"X": X, "closed": bool(kind == 4 and rng.integers(2))})
    return out


@pytest.mark.parametrize("seed", range(6))
def test_shared_edges_and_point_pieces_as_the_loops_over_curves(seed):
    rng = np.random.default_rng(seed)
    tol = 10.0 ** rng.uniform(-4, -1)
    curves = _pieces(rng, 60 + 40 * seed, tol)
    got = joins.drop_shared_edges(curves, tol)
    want = _drop_shared_edges_plain(curves, tol)
    assert [id(c) for c in got] == [id(c) for c in want]
    got = joins.merge_point_curves(curves, tol)
    want = _merge_point_curves_plain(curves, tol)
    assert [id(c) for c in got] == [id(c) for c in want]


@pytest.mark.parametrize("seed", range(4))
def test_point_pieces_at_the_tolerance(seed):
    """Point pieces whose starts (and extents) are ``tol`` apart within a few ulps, in
    chains and clusters."""
    rng = np.random.default_rng(seed)
    tol = 10.0 ** rng.uniform(-6, 0)
    curves = []
    base = rng.normal(size=3) * 10 ** rng.uniform(0, 3)
    for k in range(300):
        d = rng.normal(size=3)
        d *= tol / np.linalg.norm(d) * (1 + rng.choice([-2, -1, 0, 1, 2]) * 2.0 ** -52)
        p = base + d if k % 3 else base + rng.uniform(-2, 2, 3) * tol
        ext = np.array([p, p + d * rng.choice([0.0, 1.0, 0.5])])
        curves.append({"X": ext[: 1 + k % 2], "closed": bool(k % 17 == 0)})
        if k % 5 == 0:
            base = p
    want = [id(c) for c in _merge_point_curves_plain(curves, tol)]
    assert [id(c) for c in joins.merge_point_curves(curves, tol)] == want
    assert len(want) < len(curves)


@pytest.mark.occ
@pytest.mark.skipif(not HAVE_OCP, reason="reading STEP needs cadquery-ocp")
def test_shared_edges_and_point_pieces_on_the_apex_section(monkeypatch):
    """NIST CTC-01 AP242 at its mid-plane z: 86 pieces before joining, 4 of them
    within the tolerance of a point (the most pieces of the 39 bench mid-planes with
    CTC-05 y and Pro/E z)."""
    from geomkit.cad.step import read_step

    case = read_step(DATA / "parts" / "nist_ctc_01_ap242.stp")
    S = case.surfaces
    B = np.array([s.bounds for s in S])
    lo, hi = B[:, 0].min(axis=0), B[:, 1].max(axis=0)
    size = float(np.linalg.norm(hi - lo))
    seen = []
    for name, plain in (("drop_shared_edges", _drop_shared_edges_plain),
                        ("merge_point_curves", _merge_point_curves_plain)):
        fast = getattr(plane_mod, name)

        def both(curves, tol, fast=fast, plain=plain):
            got = fast(curves, tol)
            assert [id(c) for c in got] == [id(c) for c in plain(curves, tol)]
            seen.append(len(curves))
            return got

        monkeypatch.setattr(plane_mod, name, both)
    geomkit.plane_section(S, [0, 0, 1, -0.5 * (lo[2] + hi[2])], 1e-4 * size,
                          gap=case.edge_gap or 0.0)
    assert len(seen) == 2 and seen[0] > 50


def test_eval_points_serial_gives_the_threaded_batch():
    """``_Eval.points`` evaluates up to ``SERIAL_POINTS`` points in the calling thread:
    the threaded batch's bits, below, at and above the bound."""
    from geomkit._kernels.surface import surface_points
    from geomkit.section import trace as T
    s = _plate()
    ev = T._Eval(s, np.array([0.0, 1.0, 0.0, -50.0]))
    (u0, u1), (v0, v1) = s.domain
    rng = np.random.default_rng(5)
    for n in (1, 300, T.SERIAL_POINTS, T.SERIAL_POINTS + 1):
        uv = np.column_stack([rng.uniform(u0, u1, n), rng.uniform(v0, v1, n)])
        want = np.empty((n, 3))
        a = ev.args
        surface_points(a[0], a[1], a[2], a[3], a[4], uv, want)
        assert np.array_equal(ev.points(uv), want)
