"""classify_uv against brute force: an analytic circle, even-odd polygons, a conic.

The documented contract (geomkit/_kernels/trim.py) for a boundary band ``tol``:

* a point within ``tol / 4`` of a trim curve is ``ON_BOUNDARY``;
* an ``ON_BOUNDARY`` point is within ``tol`` of a trim curve (or of the domain edge);
* every other point gets the exact inside/outside answer.

``check_contract`` below checks exactly these three statements against an oracle that
knows the true distance to the boundary and the true side.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings, strategies as st

import geomkit
from geomkit import INSIDE, ON_BOUNDARY, OUTSIDE, InvalidInputError, classify_uv

from helpers.trims import circle_dict, circle_quarters, unit_plate

PLATE = geomkit.samples.load("plate_with_hole")[0]
CENTRE = np.array([0.5, 0.5])  # the hole in UV: analytic circle
RADIUS = 0.2
TRUTH_AREA = 8743.362938564083  # plate area 100 x 100 minus pi 20^2

HSET = settings(max_examples=60, deadline=None, derandomize=True,
                suppress_health_check=[HealthCheck.too_slow])


# ------------------------------------------------------------------------ helpers
def on_circle(theta, r=RADIUS, c=CENTRE):
    return np.column_stack([c[0] + r * np.cos(theta), c[1] + r * np.sin(theta)])


def brute_circle_distance(pts, c=CENTRE, r=RADIUS, levels=3, n=2049):
    """Distance to a densely sampled exact circle: the nearest sample on a uniform grid
    of angles, refined ``levels - 1`` times in a window of two steps either side of the
    best sample, then the distance to the polyline through the finest window (its sag,
    r (step)^2 / 8 with step ~1e-8 rad, is ~1e-18)."""
    pts = np.atleast_2d(pts)
    px, py = pts[:, :1], pts[:, 1:]
    theta = np.linspace(0, 2 * np.pi, n, endpoint=False)[None, :].repeat(len(pts), 0)
    step = 2 * np.pi / n
    for _ in range(levels):
        d = np.hypot(c[0] + r * np.cos(theta) - px, c[1] + r * np.sin(theta) - py)
        best = theta[np.arange(len(pts)), np.argmin(d, axis=1)]
        theta = best[:, None] + np.linspace(-2 * step, 2 * step, n)[None, :]
        step = 4 * step / (n - 1)
    Q = np.stack([c[0] + r * np.cos(theta), c[1] + r * np.sin(theta)], axis=-1)
    a, b = Q[:, :-1], Q[:, 1:]
    e = b - a
    t = np.clip(np.einsum("pij,pij->pi", pts[:, None, :] - a, e)
                / np.einsum("pij,pij->pi", e, e), 0, 1)
    f = pts[:, None, :] - a - t[..., None] * e
    return np.sqrt(np.einsum("pij,pij->pi", f, f)).min(axis=1)


def edge_distance(pts):
    """Distance to the boundary of the unit square domain."""
    return np.abs(np.minimum.reduce([pts[:, 0], 1 - pts[:, 0], pts[:, 1], 1 - pts[:, 1]]))


def check_contract(got, inside, dist, tol, slack=0.0, context=""):
    """got: codes; inside: true side (bool); dist: true distance to the nearest trim
    curve or domain edge (within ``slack``)."""
    got = np.asarray(got)
    must_b = dist <= tol / 4 - slack
    bad1 = must_b & (got != ON_BOUNDARY)
    bad2 = (got == ON_BOUNDARY) & (dist > tol + slack)
    want = np.where(inside, INSIDE, OUTSIDE)
    bad3 = (got != ON_BOUNDARY) & (got != want)
    msg = []
    for name, bad in (("within tol/4 but not ON_BOUNDARY", bad1),
                      ("ON_BOUNDARY but farther than tol", bad2),
                      ("wrong side", bad3)):
        if bad.any():
            i = int(np.argmax(bad))
            msg.append(f"{name}: {int(bad.sum())} point(s), e.g. #{i} dist={dist[i]!r} "
                       f"got={got[i]} want={want[i]} tol={tol}")
    assert not msg, context + "\n" + "\n".join(msg)
    return must_b.sum(), (got == ON_BOUNDARY).sum()


def even_odd(pts, poly):
    """Brute-force even-odd point in polygon (ray to +u, half-open edge rule)."""
    x, y = pts[:, 0:1], pts[:, 1:2]
    a = np.asarray(poly, float)
    b = np.roll(a, -1, axis=0)
    x1, y1, x2, y2 = a[:, 0], a[:, 1], b[:, 0], b[:, 1]
    straddle = (y1 <= y) != (y2 <= y)
    with np.errstate(divide="ignore", invalid="ignore"):
        xint = x1 + (y - y1) * (x2 - x1) / (y2 - y1)
    return (np.count_nonzero(straddle & (x < xint), axis=1) % 2) == 1


def polygon_distance(pts, poly, chunk=256):
    """Brute-force distance from each point to the closed polygon ``poly``."""
    a = np.asarray(poly, float)
    b = np.roll(a, -1, axis=0)
    d = b - a
    ll = np.maximum(np.einsum("ij,ij->i", d, d), 1e-300)
    out = np.empty(len(pts))
    for k in range(0, len(pts), chunk):
        rel = pts[k: k + chunk, None, :] - a[None, :, :]
        t = np.clip(np.einsum("pij,ij->pi", rel, d) / ll, 0.0, 1.0)
        e = rel - t[..., None] * d[None]
        out[k: k + chunk] = np.sqrt(np.einsum("pij,pij->pi", e, e).min(axis=1))
    return out


# ----------------------------------------------------------- plate_with_hole basics
def test_hole_centre_and_hole_interior_are_outside():
    assert classify_uv(PLATE, [0.5, 0.5]) == OUTSIDE
    rng = np.random.default_rng(0)
    pts = on_circle(rng.uniform(0, 2 * np.pi, 200), r=rng.uniform(0, 0.199, 200))
    assert np.all(classify_uv(PLATE, pts) == OUTSIDE)


def test_plate_corner_regions_are_inside():
    corners = [[0.1, 0.1], [0.9, 0.1], [0.05, 0.95], [0.95, 0.95], [0.25, 0.25]]
    assert np.all(classify_uv(PLATE, corners) == INSIDE)
    rng = np.random.default_rng(1)
    pts = rng.uniform(0.001, 0.3, size=(400, 2))
    pts[100:200, 0] = 1 - pts[100:200, 0]
    pts[200:300, 1] = 1 - pts[200:300, 1]
    pts[300:] = 1 - pts[300:]
    assert np.all(classify_uv(PLATE, pts) == INSIDE)


def test_points_on_the_circle_are_on_boundary():
    theta = np.r_[np.linspace(0, 2 * np.pi, 997), np.arange(8) * np.pi / 4]
    pts = on_circle(theta)
    assert np.all(classify_uv(PLATE, pts) == ON_BOUNDARY)
    # also the Bézier joints written exactly
    joints = [[0.7, 0.5], [0.5, 0.3], [0.3, 0.5], [0.5, 0.7]]
    assert np.all(classify_uv(PLATE, joints) == ON_BOUNDARY)


@pytest.mark.parametrize("delta", [1e-6, 1e-7, 1e-8])
def test_points_just_off_the_circle(delta):
    theta = np.r_[np.linspace(0, 2 * np.pi, 1001), np.arange(8) * np.pi / 4]
    inner = classify_uv(PLATE, on_circle(theta, RADIUS - delta))
    outer = classify_uv(PLATE, on_circle(theta, RADIUS + delta))
    assert np.all(inner == OUTSIDE), np.bincount(inner, minlength=3)  # in the hole
    assert np.all(outer == INSIDE), np.bincount(outer, minlength=3)  # on the plate


def test_points_outside_the_domain_are_outside():
    pts = [[-0.1, 0.5], [1.1, 0.5], [0.5, -1e-3], [0.5, 1 + 1e-6], [2, 2], [-1, -1],
           [1 + 1e-8, 0.5], [1e300, 0.5], [-5, 0.5]]
    assert np.all(classify_uv(PLATE, pts) == OUTSIDE)


def test_domain_edge_points_are_on_boundary():
    pts = [[0, 0.5], [1, 0.3], [0.5, 0], [0.5, 1], [0, 0], [1, 1], [0, 1], [1, 0],
           [1 + 5e-10, 0.5], [0.5, -2e-10], [1e-10, 0.9]]
    assert np.all(classify_uv(PLATE, pts) == ON_BOUNDARY)


def test_untrimmed_surface_is_its_domain():
    s = geomkit.samples.load("saddle")[0]
    (u0, u1), (v0, v1) = s.domain
    mid = [(u0 + u1) / 2, (v0 + v1) / 2]
    got = classify_uv(s, [mid, [u0, mid[1]], [u1 + 1, mid[1]]])
    np.testing.assert_array_equal(got, [INSIDE, ON_BOUNDARY, OUTSIDE])


def test_output_shape_follows_input_and_bad_input_is_refused():
    uv = np.full((3, 4, 2), 0.1)
    got = classify_uv(PLATE, uv)
    assert got.shape == (3, 4) and got.dtype == np.int8 and np.all(got == INSIDE)
    assert classify_uv(PLATE, np.zeros((0, 2))).shape == (0,)
    with pytest.raises(InvalidInputError) as e:
        classify_uv(PLATE, [[0.1, 0.2, 0.3]])
    assert e.value.field == "uv"
    for tol in (-1.0, np.nan, np.inf):
        with pytest.raises(InvalidInputError) as e:
            classify_uv(PLATE, [0.1, 0.1], tol=tol)
        assert e.value.field == "tol"
    with pytest.raises(InvalidInputError):
        classify_uv(PLATE, [[np.nan, 0.5]])


# ------------------------------------------------------------ the tol guarantee
@pytest.mark.parametrize("tol", [1e-3, 1e-9])
def test_boundary_band_guarantee_against_brute_force_distance(tol):
    rng = np.random.default_rng(int(-math.log10(tol)))
    m = 1500
    theta = rng.uniform(0, 2 * np.pi, m)
    # signed offsets from the circle: across the whole band, at its edges, and beyond
    delta = np.concatenate([
        rng.uniform(-2 * tol, 2 * tol, m // 3),
        rng.choice([-1, 1], m // 3) * 10 ** rng.uniform(-17, math.log10(tol) + 1, m // 3),
        rng.choice([-1, 1], m - 2 * (m // 3)) * tol * rng.choice(
            [0.25 * (1 - 1e-3), 0.25 * (1 + 1e-3), 1 - 1e-3, 1 + 1e-3], m - 2 * (m // 3)),
    ])
    pts = on_circle(theta, RADIUS + delta)
    pts = np.vstack([pts, rng.uniform(0, 1, size=(1000, 2))])  # and anywhere on the plate
    d_circle = brute_circle_distance(pts)
    r = np.hypot(*(pts - CENTRE).T)
    # the brute-force distance agrees with the analytic one
    np.testing.assert_allclose(d_circle, np.abs(r - RADIUS), rtol=0, atol=2e-15)
    dist = np.minimum(d_circle, edge_distance(pts))
    inside = (r > RADIUS) & (pts > 0).all(axis=1) & (pts < 1).all(axis=1)
    got = classify_uv(PLATE, pts, tol=tol)
    n_must, n_b = check_contract(got, inside, dist, tol, slack=2e-15, context=f"tol={tol}")
    assert n_must > 300 and n_b >= n_must  # the band was really exercised


def test_default_tol_is_trim_tol_times_domain_size():
    # plate domain is the unit square: default band 1e-9
    t = geomkit.tolerances.TRIM_TOL
    near = on_circle(np.linspace(0, 2 * np.pi, 50), RADIUS + 0.2 * t)
    far = on_circle(np.linspace(0, 2 * np.pi, 50), RADIUS + 2 * t)
    assert np.all(classify_uv(PLATE, near) == ON_BOUNDARY)
    assert np.all(classify_uv(PLATE, far) == INSIDE)


# ------------------------------------------------------------------- area fraction
def test_area_fraction_grid_matches_truth():
    # cell-centre rule on an N x N grid.  Only cells the circle passes through can be
    # misclassified relative to the exact area; a circle of radius r crosses at most
    # 4 (2 r / h + 2) cells, so |error| <= 4 (2 r / h + 2) h^2 = 4.05e-3 for N = 400.
    n = 400
    h = 1.0 / n
    c = (np.arange(n) + 0.5) * h
    u, v = np.meshgrid(c, c, indexing="ij")
    got = classify_uv(PLATE, np.stack([u.ravel(), v.ravel()], axis=1))
    frac = np.mean(got == INSIDE) + 0.5 * np.mean(got == ON_BOUNDARY)
    bound = 4 * (2 * RADIUS / h + 2) * h * h
    truth = TRUTH_AREA / 10000.0
    assert abs(frac - truth) <= bound, (frac, truth, bound)
    # stronger: every grid centre farther than the band from the circle is classified
    # exactly (so the hole is the exact circle, not a polygonal approximation of it)
    r = np.hypot(u.ravel() - 0.5, v.ravel() - 0.5)
    clear = np.abs(r - RADIUS) > 1e-9
    assert clear.sum() > n * n - 10
    np.testing.assert_array_equal(got[clear], np.where(r[clear] > RADIUS, INSIDE, OUTSIDE))


def test_area_fraction_monte_carlo_matches_truth():
    # N uniform points: the inside fraction has standard deviation sqrt(p (1 - p) / N)
    # = 7.4e-4 for N = 2e5; we allow 5 sigma (fixed seed, so no flakiness either way).
    n = 200_000
    pts = np.random.default_rng(12345).uniform(0, 1, size=(n, 2))
    got = classify_uv(PLATE, pts)
    p = TRUTH_AREA / 10000.0
    sigma = math.sqrt(p * (1 - p) / n)
    frac = np.mean(got == INSIDE)
    assert abs(frac - p) <= 5 * sigma, (frac, p, sigma)
    assert np.count_nonzero(got == ON_BOUNDARY) == 0


# ---------------------------------------------------------- random polygons (hypothesis)
@st.composite
def star_polygon(draw, centre=None, rmin=0.05, rmax=0.45, nmin=3):
    n = draw(st.integers(nmin, 40))
    # angular gaps in [1, 1.9] (relative): no gap reaches pi, so the polygon is simple
    gaps = np.array(draw(st.lists(st.floats(1.0, 1.9), min_size=n, max_size=n)))
    start = draw(st.floats(0, 2 * np.pi))
    theta = start + 2 * np.pi * np.cumsum(gaps) / gaps.sum()
    radii = np.array(draw(st.lists(st.floats(rmin, rmax), min_size=n, max_size=n)))
    if centre is None:
        centre = (draw(st.floats(0.47, 0.53)), draw(st.floats(0.47, 0.53)))
    poly = np.column_stack([centre[0] + radii * np.cos(theta), centre[1] + radii * np.sin(theta)])
    if draw(st.booleans()):
        poly = poly[::-1]  # clockwise
    return poly


def query_points(poly_list, seed, m=300):
    rng = np.random.default_rng(seed)
    pts = [rng.uniform(0.001, 0.999, size=(m, 2))]
    for poly in poly_list:
        k = len(poly)
        # points on the horizontal through every vertex (the ray passes the vertex)
        pts.append(np.column_stack([rng.uniform(0.001, 0.999, k), poly[:, 1]]))
        pts.append(np.column_stack([poly[:, 0] - rng.uniform(0, 0.3, k), poly[:, 1]]))
        pts.append(poly)  # the vertices themselves
        b = np.roll(poly, -1, axis=0)
        s = rng.uniform(0, 1, (k, 1))
        pts.append(poly + s * (b - poly))  # on the edges
        nrm = (b - poly)[:, ::-1] * [1, -1]
        nrm /= np.hypot(*nrm.T)[:, None]
        off = rng.choice([-1, 1], (k, 1)) * 10 ** rng.uniform(-12, -2, (k, 1))
        pts.append(poly + s * (b - poly) + off * nrm)  # near the edges
    pts = np.vstack(pts)
    return pts[(pts > 0).all(axis=1) & (pts < 1).all(axis=1)]


@HSET
@given(poly=star_polygon(), seed=st.integers(0, 2**31), tol=st.sampled_from([1e-9, 1e-4]))
def test_random_star_polygons_vs_even_odd(poly, seed, tol):
    s = unit_plate([np.vstack([poly, poly[:1]])])
    pts = query_points([poly], seed)
    got = classify_uv(s, pts, tol=tol)
    dist = np.minimum(polygon_distance(pts, poly), edge_distance(pts))
    check_contract(got, even_odd(pts, poly), dist, tol, slack=1e-15,
                   context=f"polygon={poly.tolist()}")


@HSET
@given(outer=star_polygon(centre=(0.5, 0.5), rmin=0.3, rmax=0.48, nmin=8),
       inner=star_polygon(centre=(0.5, 0.5), rmin=0.02, rmax=0.2),
       seed=st.integers(0, 2**31))
def test_polygon_with_a_hole_vs_even_odd(outer, inner, seed):
    # The face is where an odd number of loops wind around the point, so the oracle is
    # the xor of the two even-odd tests (usually the hole lies inside the outer loop;
    # if it pokes out, parity is still the documented rule).
    s = unit_plate([np.vstack([outer, outer[:1]]), np.vstack([inner, inner[:1]])])
    pts = query_points([outer, inner], seed)
    got = classify_uv(s, pts)
    inside = even_odd(pts, outer) ^ even_odd(pts, inner)
    dist = np.minimum.reduce([polygon_distance(pts, outer), polygon_distance(pts, inner),
                              edge_distance(pts)])
    check_contract(got, inside, dist, 1e-9, slack=1e-15)


def test_vertices_on_the_ray_hand_checked():
    diamond = [[.5, .2], [.8, .5], [.5, .8], [.2, .5], [.5, .2]]
    s = unit_plate([diamond])
    pts = [[.1, .5], [.3, .5], [.5, .5], [.79, .5], [.9, .5], [.1, .2], [.1, .8],
           [.49, .2], [.5, .2], [.8, .5]]
    want = [OUTSIDE, INSIDE, INSIDE, INSIDE, OUTSIDE, OUTSIDE, OUTSIDE, OUTSIDE,
            ON_BOUNDARY, ON_BOUNDARY]
    np.testing.assert_array_equal(classify_uv(s, pts), want)
    # horizontal edges on the ray and a V-notch whose bottom vertex (0.6, 0.4) has both
    # neighbours above it
    comb = [[.1, .1], [.9, .1], [.9, .6], [.7, .6], [.6, .4], [.5, .6], [.3, .6], [.3, .8],
            [.1, .8], [.1, .1]]
    pts = np.array([[.05, .4], [.2, .4], [.55, .4], [.65, .4], [.95, .4],
                    [.05, .6], [.2, .6], [.6, .6], [.92, .6], [.6, .45], [.6, .35],
                    [.8, .6], [.2, .8], [.6, .4], [.05, .8], [.05, .1]])
    want = [OUTSIDE, INSIDE, INSIDE, INSIDE, OUTSIDE,
            OUTSIDE, INSIDE, OUTSIDE, OUTSIDE, OUTSIDE, INSIDE,
            ON_BOUNDARY, ON_BOUNDARY, ON_BOUNDARY, OUTSIDE, OUTSIDE]
    for loop in (comb, comb[::-1]):
        got = classify_uv(unit_plate([loop]), pts)
        np.testing.assert_array_equal(got, want)
    # the hand-written answers agree with the brute-force oracle where it applies
    off = np.array(want) != ON_BOUNDARY
    np.testing.assert_array_equal(even_odd(pts[off], comb[:-1]),
                                  np.array(want)[off] == INSIDE)


@pytest.mark.parametrize("pieces", ["single", "quarters"])
def test_ray_through_nurbs_joints_and_tangent_points(pieces):
    hole = circle_dict() if pieces == "single" else circle_quarters()
    s = unit_plate([[[0, 0], [1, 0], [1, 1], [0, 1], [0, 0]], hole])
    pts = [[.1, .5], [.35, .5], [.65, .5], [.75, .5],  # through the joints (0.3|0.7, 0.5)
           [.2, .3], [.2, .7], [.5, .3 - 1e-6], [.5, .7 + 1e-6],  # ray tangent at a joint
           [.5, .3 + 1e-6], [.45, .3 + 1e-6], [.1, .3 + 1e-12], [.5, .7 - 1e-6]]
    # (0.45, 0.300001) is below the circle (which is at v = 0.30635 there)
    want = [INSIDE, OUTSIDE, OUTSIDE, INSIDE, INSIDE, INSIDE, INSIDE, INSIDE, OUTSIDE,
            INSIDE, INSIDE, OUTSIDE]
    np.testing.assert_array_equal(classify_uv(s, pts), want)


# ------------------------------------------------- circle as several NURBS pieces
@pytest.mark.parametrize("tol", [None, 1e-3])
def test_circle_in_four_pieces_agrees_with_single_curve(tol):
    square = [[0, 0], [1, 0], [1, 1], [0, 1], [0, 0]]
    four = unit_plate([square, circle_quarters()])
    assert len(four.trim[1].pieces) == 4
    rng = np.random.default_rng(4)
    band = 1e-9 if tol is None else tol
    pts = np.vstack([rng.uniform(0, 1, size=(20000, 2)),
                     on_circle(rng.uniform(0, 2 * np.pi, 3000),
                               RADIUS + rng.uniform(-3 * band, 3 * band, 3000))])
    a = classify_uv(PLATE, pts, tol=tol)
    b = classify_uv(four, pts, tol=tol)
    d = np.minimum(np.abs(np.hypot(*(pts - CENTRE).T) - RADIUS), edge_distance(pts))
    clear = d > band * (1 + 1e-6)
    np.testing.assert_array_equal(a[clear], b[clear])
    near = d < band / 4 * (1 - 1e-6)
    assert np.all(a[near] == ON_BOUNDARY) and np.all(b[near] == ON_BOUNDARY)
    assert clear.sum() > 20000 and near.sum() > 100


# ------------------------------------------------------------------- tiny loop
@pytest.mark.parametrize("tol", [None, 1e-12])
def test_very_small_loop(tol):
    c = np.array([0.4, 0.6])
    r = 1e-6
    disk = unit_plate([circle_dict(c, r)])
    holed = unit_plate([[[0, 0], [1, 0], [1, 1], [0, 1], [0, 0]], circle_dict(c, r)])
    th = np.linspace(0, 2 * np.pi, 64, endpoint=False)
    centre = [c]
    just_in = on_circle(th, 0.9 * r, c)
    just_out = on_circle(th, 1.1 * r, c)
    far = on_circle(th, 2 * r, c)
    on = on_circle(th, r, c)
    for s, inn, out in ((disk, INSIDE, OUTSIDE), (holed, OUTSIDE, INSIDE)):
        assert classify_uv(s, centre, tol=tol)[0] == inn
        assert np.all(classify_uv(s, just_in, tol=tol) == inn)
        assert np.all(classify_uv(s, just_out, tol=tol) == out)
        assert np.all(classify_uv(s, far, tol=tol) == out)
        assert np.all(classify_uv(s, on, tol=tol) == ON_BOUNDARY)
    # the same loop as a tiny polygon
    poly = on_circle(np.linspace(0, 2 * np.pi, 7)[:-1], r, c)
    sp = unit_plate([np.vstack([poly, poly[:1]])])
    assert classify_uv(sp, centre, tol=tol)[0] == INSIDE
    assert np.all(classify_uv(sp, far, tol=tol) == OUTSIDE)


# -------------------------------------------------------------- extreme weights
A, C, B = np.array([0.2, 0.2]), np.array([0.5, 0.8]), np.array([0.8, 0.2])


def conic_point(t, w):
    t = np.asarray(t)[:, None]
    b0, b1, b2 = (1 - t) ** 2, 2 * t * (1 - t) * w, t * t
    return (b0 * A + b1 * C + b2 * B) / (b0 + b1 + b2)


def conic_polyline(w, eps=1e-11):
    """Brute-force polyline of the arc, refined by bisection until every chord is within
    ``eps`` of the curve at its mid-parameter.  Returns the points and the achieved sag."""
    t = np.linspace(0, 1, 257)
    for _ in range(80):
        mid = 0.5 * (t[:-1] + t[1:])
        P, M = conic_point(t, w), conic_point(mid, w)
        a, b = P[:-1], P[1:]
        d = b - a
        ll = np.maximum(np.einsum("ij,ij->i", d, d), 1e-300)
        s = np.clip(np.einsum("ij,ij->i", M - a, d) / ll, 0, 1)
        sag = np.hypot(*(M - a - s[:, None] * d).T)
        split = sag > eps
        if not split.any():
            return P, sag.max()
        t = np.sort(np.concatenate([t, mid[split]]))
    raise AssertionError("polyline refinement did not converge")


def conic_inside(pts, w):
    """Exact side: the loop (arc A-C-B with weights 1, w, 1, closed by the chord B-A)
    encloses {p in triangle ACB : tau_C^2 < 4 w^2 tau_A tau_B} (barycentric tau)."""
    T = np.array([[A[0], C[0], B[0]], [A[1], C[1], B[1]], [1, 1, 1]])
    tau = np.linalg.solve(T, np.vstack([pts.T, np.ones(len(pts))]))
    ta, tc, tb = tau
    in_tri = (tau > 0).all(axis=0)
    return in_tri & (tc * tc < 4 * w * w * ta * tb)


@pytest.mark.parametrize("w", [1e-6, 1e-3, 1e3, 1e6])
@pytest.mark.parametrize("tol", [None, 1e-4])
def test_extreme_weight_rational_trim(w, tol):
    arc = {"degree": 2, "knots": [0, 0, 0, 1, 1, 1], "control_points": [A, C, B],
           "weights": [1.0, w, 1.0]}
    chord = {"degree": 1, "knots": [0, 0, 1, 1], "control_points": [B, A]}
    s = unit_plate([[arc, chord]])
    apex = ((A + B) / 2 + w * C) / (1 + w)
    rng = np.random.default_rng(int(math.log10(w)) + 10)
    # random points, plus points on the symmetry axis at geometric offsets either side of
    # the apex and of the chord (the lens is 6e-7 thick for w = 1e-6; the arc passes
    # 6e-7 from C for w = 1e6)
    offs = 10 ** np.linspace(-9.5, -1, 120)
    axis = np.concatenate([apex[1] + offs, apex[1] - offs, 0.2 + offs, 0.2 - offs])
    pts = np.vstack([rng.uniform(0.01, 0.99, size=(1500, 2)),
                     np.column_stack([np.full(axis.size, 0.5), axis])])
    band = 1e-9 if tol is None else tol
    P, sag = conic_polyline(w, eps=band / 20)
    assert sag <= band / 20
    dist = np.minimum(polygon_distance(pts, P), edge_distance(pts))
    got = classify_uv(s, pts, tol=tol)
    # dist is to the closed polyline (arc samples + the chord back); true distance is
    # within sag of it
    check_contract(got, conic_inside(pts, w), dist, band, slack=sag + 1e-15,
                   context=f"w={w}")
    assert np.count_nonzero(got == OUTSIDE) > 10
    thickness = np.hypot(*(apex - (A + B) / 2))  # of the region, along the axis
    if thickness > 4 * band:
        assert np.count_nonzero(got == INSIDE) > 10


def test_segment_polyline_is_the_general_polyline():
    """A two-point polyline (read without the general route's checks) has the general
    route's chord-length knots [0, 0, 1, 1], its points copied and read-only; faults
    are the general route's errors."""
    import numpy as np
    from geomkit.errors import InvalidTrimError
    from geomkit.nurbs.surface import TrimCurve

    rng = np.random.default_rng(4)
    for _ in range(200):
        P = rng.normal(0, 10, (2, 2)) * 10.0 ** rng.integers(-8, 8)
        c = TrimCurve.polyline(P)
        seg = np.hypot(*np.diff(P, axis=0).T)
        t = np.concatenate([[0.0], np.cumsum(seg)])
        t /= t[-1]
        assert np.array_equal(c.knots, np.concatenate([[0.0], t, [1.0]]))
        assert np.array_equal(c.control_points, P) and not c.control_points.flags.writeable
        assert np.array_equal(c.weights, [1.0, 1.0])
        P[0, 0] += 1.0
        assert c.control_points[0, 0] != P[0, 0]
    for bad, what in (([[1.0, 2.0], [1.0, 2.0]], "coincide"), ([[0.0, np.nan], [1, 1]],
                      "non-finite"), ([[0.0, 0, 0], [1, 1, 1]], "shape")):
        with pytest.raises(InvalidTrimError, match=what):
            TrimCurve.polyline(bad)
