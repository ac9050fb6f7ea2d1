"""The projection's second-order certificate (candidates settled without a Newton run):
its derivative bounds are true bounds, a settled candidate never changes an answer,
and it refuses where the distance function is not provably above the foot's."""

import numpy as np
import pytest

import geomkit
from geomkit import samples
from geomkit.query.projection_cert import sub_span_bounds


def _scan_points(surfaces, n, rng, offset=0.01):
    """Points on the surface moved off it by up to ``offset`` of the model size."""
    pts = []
    for s in surfaces:
        (u0, u1), (v0, v1) = s.domain
        uv = np.c_[rng.uniform(u0, u1, n), rng.uniform(v0, v1, n)]
        X = s.evaluate(uv)
        d = rng.normal(size=(n, 3))
        d *= (rng.uniform(0, offset * s.size, n) / np.linalg.norm(d, axis=1))[:, None]
        pts.append(X + d)
    return np.concatenate(pts)


@pytest.mark.parametrize("name", ["freeform_1", "sphere", "torus", "heavy_weights",
                                  "crease", "cylinder_quarter"])
def test_sub_span_bounds_hold(name):
    """Every sampled derivative norm is within its sub-span's bound (the bounds are
    proven: convex hull of the subdivided Bézier nets and the quotient rule), and the
    bounds are not vacuous (within 10x of the sampled maximum on most sub-spans)."""
    rng = np.random.default_rng(0)
    for s in samples.load(name):
        bu, bv, B = sub_span_bounds(s, 4, 3)
        assert np.all(np.isfinite(B)) and np.all(B >= 0)
        (u0, u1), (v0, v1) = s.domain
        uv = np.c_[rng.uniform(u0, u1, 20000), rng.uniform(v0, v1, 20000)]
        uv[:3000, 0] = bu[rng.integers(0, bu.size, 3000)]  # on sub-span borders too
        uv[3000:6000, 1] = bv[rng.integers(0, bv.size, 3000)]
        D = s.derivatives(uv, 2)
        # a value on a border may be the left- or the right-sided one: either cell
        cells = []
        for side in ("left", "right"):
            iu = np.clip(np.searchsorted(bu, uv[:, 0], side) - 1, 0, bu.size - 2)
            for side_v in ("left", "right"):
                iv = np.clip(np.searchsorted(bv, uv[:, 1], side_v) - 1, 0, bv.size - 2)
                cells.append(B[iu, iv])
        b = np.max(cells, axis=0)
        val = np.linalg.norm(np.stack([D[:, 1, 0], D[:, 0, 1], D[:, 2, 0], D[:, 1, 1],
                                       D[:, 0, 2]], axis=1), axis=2)
        assert np.all(val <= b * (1 + 1e-9) + 1e-12), name
        assert np.median(b[:, 0] / np.maximum(val[:, 0], 1e-300)) < 10.0


@pytest.mark.parametrize("name", ["freeform_1", "sphere", "torus"])
def test_certificate_on_off_same_answers(name):
    """Scan points (within 1% of the model size) with the certificate on and off: the
    same surface and status for every point, distances equal to rounding, feet equal
    to the Newton's own precision — and far fewer Newton runs with it on."""
    S = samples.load(name)
    P = _scan_points(S, 3000, np.random.default_rng(1))
    pr = geomkit.Projector(S)
    pr.certify = False
    off = pr.project(P)
    pr.certify = True
    on = pr.project(P)
    size = pr.size
    assert np.array_equal(on.surface, off.surface)
    assert np.array_equal(on.status, off.status)
    assert np.max(np.abs(on.distance - off.distance)) <= 1e-12 * size
    assert np.max(np.abs(on.point - off.point)) <= 1e-8 * size
    assert np.all(on.lower_bound <= on.distance + 1e-12 * size)
    assert off.stats["certified_skips"] == 0
    assert on.stats["certified_skips"] > 0.3 * len(P)
    assert on.stats["newton_runs"] + on.stats["certified_skips"] >= off.stats["newton_runs"]
    assert on.stats["newton_runs"] < 0.8 * off.stats["newton_runs"]


def test_certificate_refuses_near_the_centre_of_curvature():
    """Points 1e-3 from the sphere's centre (distance ~ radius: the distance function
    is nearly flat over the whole sphere, the certificate's d* K term alone reaches
    1) are never certified, and their answers stay
    exact; at a quarter of the radius from the surface it does certify."""
    sph = samples.load("sphere")
    pr = geomkit.Projector(sph)
    rng = np.random.default_rng(2)
    d = rng.normal(size=(400, 3))
    d /= np.linalg.norm(d, axis=1)[:, None]
    near_centre = 1e-3 * d[:6]  # every triangle is a candidate there: a few points
    res = pr.project(near_centre)
    assert res.stats["certified_skips"] == 0
    assert np.max(np.abs(res.distance - (10.0 - 1e-3))) <= 1e-9
    res2 = pr.project(7.5 * d)  # 2.5 inside the surface of radius 10
    assert res2.stats["certified_skips"] > 0
    assert np.max(np.abs(res2.distance - 2.5)) <= 1e-9


def test_certificate_trimmed_parts_same_answers():
    """plate_with_hole (trimmed: every triangle borders the outer or the hole's trim
    polyline) with points above the hole and its edge: answers equal with the
    certificate on and off, and trim-boundary triangles settled."""
    plate = samples.load("plate_with_hole")
    pr = geomkit.Projector(plate)
    rng = np.random.default_rng(3)
    a = rng.uniform(0, 2 * np.pi, 2000)
    r = rng.uniform(0, 40, 2000)
    P = np.c_[50 + r * np.cos(a), 50 + r * np.sin(a), rng.uniform(-2, 2, 2000)]
    pr.certify = False
    off = pr.project(P)
    pr.certify = True
    on = pr.project(P)
    assert np.array_equal(on.surface, off.surface)
    assert np.array_equal(on.status, off.status)
    assert np.max(np.abs(on.distance - off.distance)) <= 1e-12 * pr.size
    assert on.stats["certified_skips"] > 0


@pytest.fixture(scope="module")
def impeller_projector():
    """pyiges' impeller: (surfaces, Projector)."""
    pytest.importorskip("pyiges")
    from geomkit.bench.projection_mesh import load_case
    S = load_case("impeller")
    return S, geomkit.Projector(S)


def _boundary_arcs_hold(pr, max_refused):
    """Every sample of the exact trim curves between the two vertices of a trim
    polyline edge (located by brute force: the nearest of 4,001 samples per segment)
    lies in the certificate box of that edge's triangle, unless the box is NaN
    (refused: at most ``max_refused`` of the boundary triangles)."""
    from geomkit._kernels import trim_feet as tf
    from geomkit.query.projection_trim import _boundary_edges

    box = pr.cert_pack[0]
    bedge = _boundary_edges(pr.mesh, pr.trimmed)
    fuv = pr.mesh.face_uv
    nb = bedge.any(axis=1)
    assert np.isnan(box[nb, 0]).mean() <= max_refused
    assert not np.isnan(box[~nb]).any()
    from scipy.spatial import cKDTree

    per, checked, grown = 4001, 0, 0
    for si in np.flatnonzero(pr.trimmed):
        s = pr.surfaces[si]
        seg, deg, _, _ = s.trim_segments()
        seg = np.ascontiguousarray(seg)
        M = seg.shape[0] * per
        suv, sseg, st = np.empty((M, 2)), np.empty(M, dtype=np.int64), np.empty(M)
        tf.trim_samples(seg, deg, per, suv, sseg, st)
        tri, k = np.nonzero(bedge & (pr.mesh.face_surface == si)[:, None])
        tree = cKDTree(suv)
        A, B = fuv[tri, k], fuv[tri, (k + 1) % 3]
        da, IA = tree.query(A)
        db, IB = tree.query(B)
        (u0, u1), (v0, v1) = s.domain  # the face lies in the domain
        for t, ia, ib, ea, eb in zip(tri, IA, IB, da, db):
            if np.isnan(box[t, 0]) or sseg[ia] != sseg[ib] or max(ea, eb) > 1e-3:
                continue  # refused, a seam or a segment junction: not this test
            lo, hi = sorted((ia, ib))
            arc = suv[lo + 1:hi]  # strictly between the two vertices, in the domain
            arc = np.c_[np.clip(arc[:, 0], u0, u1), np.clip(arc[:, 1], v0, v1)]
            inside = ((arc[:, 0] >= box[t, 0]) & (arc[:, 0] <= box[t, 1])
                      & (arc[:, 1] >= box[t, 2]) & (arc[:, 1] <= box[t, 3]))
            assert inside.all(), (si, t, arc[~inside][:3], box[t])
            tb = fuv[t]
            grown += bool(((arc[:, 0] < tb[:, 0].min()) | (arc[:, 0] > tb[:, 0].max())
                           | (arc[:, 1] < tb[:, 1].min())
                           | (arc[:, 1] > tb[:, 1].max())).any())
            checked += 1
    return checked, grown


def test_trim_boundary_boxes_hold_the_arcs():
    """plate_with_hole: every triangle has a box (none refused), every hole arc lies in
    its triangle's box."""
    pr = geomkit.Projector(samples.load("plate_with_hole"))
    checked, _ = _boundary_arcs_hold(pr, 0.0)
    assert checked > 20


def test_trim_boundary_boxes_hold_the_arcs_impeller(impeller_projector):
    """pyiges' impeller (trim curves of degree 1-3 on 277 faces): the arcs lie in
    their boxes, the boxes do grow past the triangles where the arc bulges out (the
    sliver the certificate must cover), and most boundary triangles get a box.  (With
    trim polylines started at the pieces' knots the impeller has 10,923 boundary
    triangles, 2,813 refused (0.26); 19,939 and 2,945 (0.15) from 5 seeds a span.)"""
    checked, grown = _boundary_arcs_hold(impeller_projector[1], 0.3)
    assert checked > 500 and grown > 50


def test_trim_boundary_box_refuses_a_vertex_off_the_curve():
    """A boundary vertex moved off the exact trim curve (1e-6 in parameters): its
    triangles get no box (NaN: never settled); the others are unchanged."""
    from geomkit.query.projection_trim import _boundary_edges, cert_boxes

    pr = geomkit.Projector(samples.load("plate_with_hole"))
    mesh = pr.mesh
    bedge = _boundary_edges(mesh, pr.trimmed)
    ref = cert_boxes(mesh, pr.surfaces, pr.trimmed, pr.trim_pack[4])[0]
    # a vertex of a hole edge (not on the domain's sides)
    fuv = mesh.face_uv
    mid = np.abs(fuv - fuv.reshape(-1, 2).mean(0)).max(axis=2) < 0.3 * np.ptp(
        fuv.reshape(-1, 2), axis=0).max()
    t, k = np.argwhere(bedge & mid)[0]
    uv0 = fuv[t, k].copy()
    hit = np.all(fuv == uv0, axis=2)  # every corner at that vertex
    moved = fuv.copy()
    moved[hit] += 1e-6
    import copy
    m2 = copy.copy(mesh)
    m2.face_uv = moved
    box = cert_boxes(m2, pr.surfaces, pr.trimmed, pr.trim_pack[4])[0]
    refused = np.isnan(box[:, 0])
    assert refused[t]
    assert np.array_equal(box[~hit.any(1)], ref[~hit.any(1)])


@pytest.mark.parametrize("which", ["scan", "box"])
def test_certificate_trim_boundary_same_answers_impeller(impeller_projector, which):
    """pyiges' impeller, 1,500 scan / 300 box points (the bench's point sets): the same
    answers with the certificate on and off, and trim-boundary triangles settled (the
    impeller's triangles mostly border a trim curve)."""
    from geomkit.bench.projection_mesh import case_points

    S, pr = impeller_projector
    scan, box = case_points(S, 1500, np.random.default_rng(5))
    P = scan if which == "scan" else box[:300]
    try:
        pr.certify = False
        off = pr.project(P)
    finally:
        pr.certify = True
    on = pr.project(P)
    assert np.array_equal(on.surface, off.surface)
    assert np.array_equal(on.status, off.status)
    assert np.max(np.abs(on.distance - off.distance)) <= 1e-12 * pr.size
    assert np.all(on.lower_bound <= on.distance + 1e-12 * pr.size)
    assert on.stats["certified_skips"] > 0.2 * len(P)
    assert on.stats["newton_runs"] < off.stats["newton_runs"]


def test_deep_triangles_are_inside_their_faces(impeller_projector):
    """Every parameter point in the box of a triangle flagged deep, or in a deep cell
    of its surface's grid, is INSIDE its face by classify_uv (the oracle the kernel's
    classification follows, default band), and both exist; a foot there skips the
    classification: same answers with the flags cleared."""
    from geomkit.bench.projection_mesh import case_points

    S, pr = impeller_projector
    box = pr.cert_pack[0]
    deep = np.flatnonzero(box[:, 4] != 0)
    assert deep.size > 500
    rng = np.random.default_rng(6)
    fs = pr.mesh.face_surface
    for si in np.unique(fs[deep]):
        t = deep[fs[deep] == si]
        r = rng.random((t.size, 8, 2))
        r[:, :2] = [[0, 0], [1, 1]]  # box corners too
        uv = np.stack([box[t, 0, None] + r[..., 0] * (box[t, 1] - box[t, 0])[:, None],
                       box[t, 2, None] + r[..., 1] * (box[t, 3] - box[t, 2])[:, None]],
                      axis=-1).reshape(-1, 2)
        assert np.all(S[si].classify_uv(uv) == geomkit.INSIDE), si
    from geomkit.query.projection_trim import DEEP_GRID
    gdeep, goff = pr.cert_pack[1], pr.cert_pack[2]
    ncells = 0
    for si in np.flatnonzero(goff[:, 1]):
        G = goff[si, 1]
        cells = gdeep[goff[si, 0]:goff[si, 0] + G * G].reshape(G, G)
        i, j = np.nonzero(cells)
        ncells += i.size
        (u0, u1), (v0, v1) = S[si].domain
        r = rng.random((i.size, 6, 2))
        r[:, :2] = [[0, 0], [1 - 1e-15, 1 - 1e-15]]
        uv = np.stack([u0 + (i[:, None] + r[..., 0]) * (u1 - u0) / G,
                       v0 + (j[:, None] + r[..., 1]) * (v1 - v0) / G], axis=-1)
        assert np.all(S[si].classify_uv(uv.reshape(-1, 2)) == geomkit.INSIDE), si
    assert G == DEEP_GRID and ncells > 5000
    scan, _ = case_points(S, 1500, np.random.default_rng(7))
    ref = pr.project(scan)
    saved, cells = box[:, 4].copy(), pr.cert_pack[1].copy()
    try:
        box[:, 4] = 0.0
        pr.cert_pack[1][:] = 0
        off = pr.project(scan)
    finally:
        box[:, 4] = saved
        pr.cert_pack[1][:] = cells
    assert np.array_equal(ref.surface, off.surface)
    assert np.array_equal(ref.status, off.status)
    assert np.array_equal(ref.distance, off.distance)
