"""project_points and VoxelGrid against analytic distances, brute force and an
independent dense-sampling oracle (worst case, not median)."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.optimize import minimize

import geomkit
from geomkit.query import results as R
from geomkit.errors import InvalidInputError

N_RANDOM = 100_000


def _sample(name):
    return geomkit.samples.load(name)


@pytest.fixture(scope="module")
def rng():
    return np.random.default_rng(20261121)


def _box_points(surf, n, margin, rng):
    lo, hi = surf.bounds
    return rng.uniform(lo - margin, hi + margin, (n, 3))


# ------------------------------------------------------------------ analytic truths
def test_sphere_random_points_exact(rng):
    s = _sample("sphere")[0]
    P = _box_points(s, N_RANDOM, 10.0, rng)
    pr = geomkit.project_points(s, P)
    r = np.linalg.norm(P, axis=1)
    exact = np.abs(r - 10.0)
    assert np.all(pr.status != R.FAILED) and np.all(pr.status != R.BEYOND)
    assert np.max(np.abs(pr.distance - exact)) <= 1e-9
    # the normal points outward (S_u x S_v of this sample): sign of r - R
    far = np.abs(r - 10) > 1e-9
    assert np.all(np.sign(pr.signed_distance[far]) == np.sign(r[far] - 10.0))
    # feet lie on the sphere, and the lower bound holds
    assert np.max(np.abs(np.linalg.norm(pr.point, axis=1) - 10.0)) <= 1e-12
    assert np.all(pr.lower_bound <= pr.distance + 1e-12)
    assert np.all(pr.status[far] == R.INTERIOR)


def _torus_distance(P, R_, r_):
    rho = np.hypot(P[:, 0], P[:, 1])
    return np.hypot(rho - R_, P[:, 2]) - r_


def test_torus_random_points_exact(rng):
    s = _sample("torus")[0]
    P = _box_points(s, N_RANDOM, 10.0, rng)
    pr = geomkit.project_points(s, P)
    sd = _torus_distance(P, 20.0, 5.0)
    assert np.max(np.abs(pr.distance - np.abs(sd))) <= 1e-9
    far = np.abs(sd) > 1e-9
    # orientation of the sample's normal: compare signs up to one global flip
    flip = np.sign(pr.signed_distance[far][0] * sd[far][0])
    assert np.all(np.sign(pr.signed_distance[far]) == flip * np.sign(sd[far]))
    assert np.all(pr.status == R.INTERIOR)


def test_cylinder_quarter_feet_inside(rng):
    s = _sample("cylinder_quarter")[0]
    # points whose foot lies inside the patch: angle in (0, 90) deg, z in (0, 20)
    n = N_RANDOM
    ang = rng.uniform(0.01, np.pi / 2 - 0.01, n)
    rho = rng.uniform(0.0, 20.0, n)
    z = rng.uniform(0.01, 19.99, n)
    P = np.c_[rho * np.cos(ang), rho * np.sin(ang), z]
    pr = geomkit.project_points(s, P)
    exact = np.abs(rho - 10.0)
    assert np.max(np.abs(pr.distance - exact)) <= 1e-9
    assert np.all(pr.status[exact > 1e-9] == R.INTERIOR)


def _plate_distance(P):
    x, y, z = P.T
    dx = np.maximum(0, np.maximum(-x, x - 100))
    dy = np.maximum(0, np.maximum(-y, y - 100))
    rho = np.hypot(x - 50, y - 50)
    in_hole = rho < 20
    dxy = np.where(in_hole, 20 - rho, np.hypot(dx, dy))
    return np.hypot(dxy, z), in_hole


def test_plate_with_hole_random_points_exact(rng):
    s = _sample("plate_with_hole")[0]
    P = _box_points(s, N_RANDOM, 10.0, rng)
    pr = geomkit.project_points(s, P)
    exact, in_hole = _plate_distance(P)
    assert np.max(np.abs(pr.distance - exact)) <= 1e-9
    # above the hole the foot is on the hole's edge
    assert np.all(pr.status[in_hole] == R.TRIM_EDGE)
    rho = np.hypot(pr.point[in_hole, 0] - 50, pr.point[in_hole, 1] - 50)
    assert np.max(np.abs(rho - 20)) <= 1e-9
    # over the plate proper the foot is orthogonal
    x, y = P[:, 0], P[:, 1]
    inner = (x > 0.1) & (x < 99.9) & (y > 0.1) & (y < 99.9) & (np.hypot(x - 50, y - 50) > 20.1)
    assert np.all(pr.status[inner] == R.INTERIOR)
    outside = (x < 0) | (x > 100) | (y < 0) | (y > 100)
    assert np.all(pr.status[outside] == R.DOMAIN_EDGE)


def _saddle_distance(P, nv=2001, iters=80):
    """Independent oracle for the bilinear saddle z = x y / 10 on [-10, 10]^2: for fixed
    y the surface is a straight line in x, so min over x is closed form; then a dense
    scan over y and golden-section refinement."""
    def dist_y(y, p):
        # line X(x) = (x, y, x y / 10), x in [-10, 10]
        a = np.stack([np.ones_like(y), np.zeros_like(y), y / 10], axis=-1)
        b = np.stack([np.zeros_like(y), y, np.zeros_like(y)], axis=-1)
        t = np.einsum("...k,...k->...", p - b, a) / np.einsum("...k,...k->...", a, a)
        t = np.clip(t, -10, 10)
        return np.linalg.norm(b + t[..., None] * a - p, axis=-1)

    ys = np.linspace(-10, 10, nv)
    best = np.empty(P.shape[0])
    for a in range(0, P.shape[0], 2000):
        p = P[a:a + 2000]
        D = dist_y(ys[None, :], p[:, None, :])
        # refine around the two best local minima of the scan
        out = np.full(p.shape[0], np.inf)
        order = np.argsort(D, axis=1)[:, :6]
        for c in range(order.shape[1]):
            i = order[:, c]
            lo = ys[np.maximum(i - 1, 0)]
            hi = ys[np.minimum(i + 1, nv - 1)]
            g = (np.sqrt(5) - 1) / 2
            for _ in range(iters):
                m1 = hi - g * (hi - lo)
                m2 = lo + g * (hi - lo)
                f1 = dist_y(m1, p)
                f2 = dist_y(m2, p)
                left = f1 < f2
                hi = np.where(left, m2, hi)
                lo = np.where(left, lo, m1)
            out = np.minimum(out, np.minimum(dist_y(0.5 * (lo + hi), p),
                                             np.minimum(dist_y(ys[i], p), D[np.arange(len(p)), i])))
        best[a:a + 2000] = out
    return best


def test_saddle_random_points_exact(rng):
    s = _sample("saddle")[0]
    P = _box_points(s, 20_000, 10.0, rng)
    pr = geomkit.project_points(s, P)
    exact = _saddle_distance(P)
    # geomkit's foot is a surface point, so its distance can't be below the truth
    assert np.max(np.abs(pr.distance - exact)) <= 1e-9
    z = P[:, 0] * P[:, 1] / 10
    side = np.abs(P[:, 2] - z) > 1e-6
    inside = (np.abs(P[:, 0]) < 10) & (np.abs(P[:, 1]) < 10) & side
    # above the graph is the +z side; normals agree with one global orientation
    sgn = np.sign(P[inside, 2] - z[inside])
    flip = np.sign(pr.signed_distance[inside][0] * sgn[0])
    assert np.all(np.sign(pr.signed_distance[inside]) == flip * sgn)


def test_points_with_many_feet():
    sphere = _sample("sphere")[0]
    pr = geomkit.project_points(sphere, [[0, 0, 0]])
    assert abs(pr.distance[0] - 10.0) <= 1e-12
    assert abs(np.linalg.norm(pr.point[0]) - 10.0) <= 1e-12
    torus = _sample("torus")[0]
    axis = np.c_[np.zeros(7), np.zeros(7), np.linspace(-30, 30, 7)]
    pr = geomkit.project_points(torus, axis)
    exact = np.abs(np.hypot(20.0, axis[:, 2]) - 5.0)
    assert np.max(np.abs(pr.distance - exact)) <= 1e-9
    # the centre circle of the torus tube: every point of the circle is a foot
    pr = geomkit.project_points(torus, [[20.0, 0, 0], [0, -20.0, 0]])
    assert np.max(np.abs(pr.distance - 5.0)) <= 1e-12


# ------------------------------------------------------------------ hard cases
def _c0_pieces(knots, p):
    """Parameter intervals between the C0 knots (multiplicity >= degree)."""
    inner = np.unique(knots[p + 1:-p - 1])
    cuts = [k for k in inner if np.count_nonzero(knots == k) >= p]
    return list(zip([knots[p]] + cuts, cuts + [knots[-p - 1]]))


def _oracle(s, P, n=201):
    """Dense UV grid + bounded quasi-Newton (scipy L-BFGS-B) from the 3 best samples of
    every smooth piece (the domain split at C0 knots, where the gradient jumps)."""
    out = np.full(len(P), np.inf)
    for ua, ub in _c0_pieces(s.knots_u, s.degree_u):
        for va, vb in _c0_pieces(s.knots_v, s.degree_v):
            uu, vv = np.meshgrid(np.linspace(ua, ub, n), np.linspace(va, vb, n),
                                 indexing="ij")
            G = np.c_[uu.ravel(), vv.ravel()]
            X = geomkit.evaluate(s, G)
            if s.is_trimmed:
                keep = geomkit.classify_uv(s, G) != geomkit.OUTSIDE
                G, X = G[keep], X[keep]
            for i, p in enumerate(P):
                d2 = np.sum((X - p) ** 2, axis=1)
                for j in np.argsort(d2)[:3]:
                    def f(w, p=p):
                        r = geomkit.evaluate(s, w) - p
                        D = geomkit.derivatives(s, w, 1)
                        return float(r @ r), np.array([2 * r @ D[1, 0], 2 * r @ D[0, 1]])
                    res = minimize(f, G[j], jac=True, method="L-BFGS-B",
                                   bounds=[(ua, ub), (va, vb)],
                                   options={"ftol": 1e-30, "gtol": 1e-14, "maxiter": 500})
                    ok = not s.is_trimmed or geomkit.classify_uv(s, res.x) != geomkit.OUTSIDE
                    out[i] = min(out[i], np.sqrt(d2[j]), np.sqrt(res.fun) if ok else np.inf)
    return out


@pytest.mark.parametrize("name", ["crease", "heavy_weights", "freeform_1"])
def test_hard_surfaces_against_dense_oracle(name, rng):
    s = _sample(name)[0]
    P = _box_points(s, 150, 0.3 * s.size, rng)
    if name == "crease":  # points straddling the C0 crease x = 20
        P[:75, 0] = 20 + rng.uniform(-0.5, 0.5, 75)
        P[:75, 1] = rng.uniform(10, 25, 75)
    pr = geomkit.project_points(s, P)
    ref = _oracle(s, P)
    # never worse than the oracle; equal up to the oracle's own accuracy
    assert np.all(pr.distance <= ref + 1e-9)
    assert np.max(ref - pr.distance) <= 1e-6
    # the foot is a surface point at the reported parameters
    assert np.max(np.abs(geomkit.evaluate(s, pr.uv) - pr.point)) <= 1e-12


def test_near_the_poles_and_on_the_axis():
    s = _sample("sphere")[0]
    t = np.linspace(0, 2 * np.pi, 50, endpoint=False)
    pts = []
    for h in (1e-9, 1e-6, 1e-3, 0.1):
        for z in (-15.0, 13.0, 7.0):
            pts.append(np.c_[h * np.cos(t), h * np.sin(t), np.full(50, z)])
    P = np.vstack(pts + [np.array([[0, 0, 10.0], [0, 0, -10.0], [0, 0, 25.0]])])
    pr = geomkit.project_points(s, P)
    exact = np.abs(np.linalg.norm(P, axis=1) - 10)
    assert np.max(np.abs(pr.distance - exact)) <= 1e-9
    assert np.all(pr.status == R.INTERIOR)  # a pole is not an edge of the surface
    assert np.all(np.isfinite(pr.normal))


def test_near_trim_edges_of_the_hole():
    s = _sample("plate_with_hole")[0]
    t = np.linspace(0, 2 * np.pi, 400, endpoint=False)
    rho = np.r_[np.full(200, 20 - 1e-7), np.full(200, 20 + 1e-7)]
    z = np.r_[np.full(100, 1e-3), np.full(100, 5.0), np.full(100, 1e-3), np.full(100, -5.0)]
    P = np.c_[50 + rho * np.cos(t), 50 + rho * np.sin(t), z]
    pr = geomkit.project_points(s, P)
    exact, _ = _plate_distance(P)
    assert np.max(np.abs(pr.distance - exact)) <= 1e-9
    assert np.all(pr.status[:200] == R.TRIM_EDGE)


def test_two_surfaces_nearest_wins():
    a, b = _sample("sphere_pair")
    P = np.array([[0, 0, 0.0], [50, 50, 50], [-3, 2, 1]])
    pr = geomkit.project_points([a, b], P)
    da = geomkit.project_points(a, P).distance
    db = geomkit.project_points(b, P).distance
    assert np.allclose(pr.distance, np.minimum(da, db), atol=1e-12)
    assert np.all(pr.surface == np.where(da <= db, 0, 1))


# ------------------------------------------------------------------ options & errors
def test_max_distance_beyond():
    s = _sample("sphere")[0]
    pr = geomkit.project_points(s, [[0, 0, 12.0], [0, 0, 30.0]], max_distance=5.0)
    assert pr.status.tolist() == [R.INTERIOR, R.BEYOND]
    assert np.isnan(pr.distance[1]) and pr.lower_bound[1] > 5.0
    assert pr.counts()["beyond"] == 1


def test_chunks_stream_and_progress(rng):
    s = _sample("torus")[0]
    P = _box_points(s, 3000, 5.0, rng)
    calls = []
    whole = geomkit.project_points(s, P)
    chunked = geomkit.project_points(s, P, chunk_size=700,
                                     progress=lambda d, n: calls.append((d, n)))
    assert np.array_equal(whole.distance, chunked.distance)
    assert calls == [(700, 3000), (1400, 3000), (2100, 3000), (2800, 3000), (3000, 3000)]
    pr = geomkit.Projector(s)
    parts = list(pr.iter_project(P, chunk_size=1000))
    assert len(parts) == 3 and np.array_equal(np.concatenate([p.distance for p in parts]),
                                              whole.distance)


def test_empty_and_bad_points():
    s = _sample("sphere")[0]
    assert len(geomkit.project_points(s, np.empty((0, 3)))) == 0
    with pytest.raises(InvalidInputError, match="row 1"):
        geomkit.project_points(s, [[0, 0, 1.0], [np.nan, 0, 0]])
    with pytest.raises(InvalidInputError, match="shape"):
        geomkit.project_points(s, [[0, 0]])
    with pytest.raises(InvalidInputError, match="surfaces"):
        geomkit.project_points("sphere", [[0, 0, 0]])
    with pytest.raises(InvalidInputError, match="max_distance"):
        geomkit.project_points(s, [[0, 0, 0]], max_distance=-1)
    with pytest.raises(InvalidInputError, match="mesh_tol"):
        geomkit.Projector(s, mesh_tol=0)


def test_mesh_tolerance_changes_speed_not_answer(rng):
    s = _sample("freeform_1")[0]
    P = _box_points(s, 2000, 0.2 * s.size, rng)
    a = geomkit.Projector(s, mesh_tol=0.0005 * s.size).project(P)
    b = geomkit.Projector(s, mesh_tol=0.002 * s.size).project(P)
    c = geomkit.Projector(s, mesh_tol=0.5 * s.size)  # capped at the default
    assert c.mesh.tol <= 0.002 * s.size * (1 + 1e-12)
    assert np.max(np.abs(a.distance - b.distance)) <= 1e-9
