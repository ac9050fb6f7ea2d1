"""Tessellation of trimmed surfaces (see tests/mesh/test_tessellate.py for the oracles):
face centroids inside the trim, holes kept as boundary loops, trimmed areas against
analytic truths (hypothesis-generated holes too), a circle trim on a non-uniformly
parametrized plane, trim loops straying outside the domain, and the direct path for
trimmed planes (no cells: the region's polygon triangulated once)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, note, settings
from hypothesis import strategies as st

from geomkit import OUTSIDE, Surface
from geomkit.mesh.tessellate import tessellate

from helpers import naive
from helpers.surfaces import describe, random_surfaces
from helpers.tesshelp import (REL, assert_manifold_oriented, boundary_loops, case_of,
                              circle_dict, edge_report, mesh_of, plane, regular_surface,
                              rotation)


# ======================================================================== 4. trims
@pytest.mark.parametrize("tol", [1e-2, 1e-3, 1e-4])
def test_plate_centroids_inside_the_trim(tol):
    case, mesh = mesh_of("plate_with_hole", tol)
    s = case.surfaces[0]
    UV = mesh.uv[mesh.faces]
    cls = s.classify_uv(UV.mean(axis=1))
    assert not np.any(cls == OUTSIDE), \
        f"{int((cls == OUTSIDE).sum())} face centroids in the hole at tol {tol}"
    # the hole is there: two boundary loops, the inner one's vertices on the circle
    # of radius 20 about (50, 50)
    assert boundary_loops(mesh.faces) == 2
    r = edge_report(mesh.faces)
    bv = np.unique(r["edges"][r["count"] == 1])
    rho = np.hypot(mesh.vertices[bv, 0] - 50.0, mesh.vertices[bv, 1] - 50.0)
    inner = rho < 30.0
    assert inner.sum() >= 8 and np.abs(rho[inner] - 20.0).max() <= 1e-9

@st.composite
def holed_planes(draw):
    """(surface, truth area, curved trim length bound in 3-D, hole kind): a rotated
    a x b plane with a random circle hole (exact NURBS) or a random star-shaped
    polygon hole."""
    a = draw(st.floats(1.0, 200.0))
    b = draw(st.floats(1.0, 200.0))
    angles = draw(st.tuples(*[st.floats(-math.pi, math.pi)] * 3))
    c = np.array([draw(st.floats(0.3, 0.7)), draw(st.floats(0.3, 0.7))])
    outer = [[0, 0], [1, 0], [1, 1], [0, 1], [0, 0]]
    if draw(st.booleans()):
        r = draw(st.floats(0.01, 0.25))
        s = plane(a, b, [outer, circle_dict(c, r)], rotation(*angles))
        return s, a * b * (1 - math.pi * r * r), 2 * math.pi * r * max(a, b), "circle"
    # star-shaped about c with every angular gap in (0.2, 1.8) x 2 pi / n < pi (n >= 4):
    # a simple polygon, so the shoelace area is the hole's area
    n = draw(st.integers(4, 12))
    jitter = np.array(draw(st.lists(st.floats(-1.0, 1.0), min_size=n, max_size=n)))
    th = 2 * math.pi / n * (np.arange(n) + 0.4 * jitter) + draw(st.floats(0, 2 * math.pi))
    rad = np.array(draw(st.lists(st.floats(0.03, 0.25), min_size=n, max_size=n)))
    pts = c + rad[:, None] * np.c_[np.cos(th), np.sin(th)]
    pts = np.vstack([pts, pts[:1]])
    x, y = pts[:, 0], pts[:, 1]
    hole = 0.5 * abs(np.sum(x[:-1] * y[1:] - x[1:] * y[:-1]))
    s = plane(a, b, [outer, pts.tolist()], rotation(*angles))
    return s, a * b * (1 - hole), 0.0, "star"


@settings(max_examples=10)
@given(data=holed_planes(), rel=st.sampled_from([1e-2, 1e-3]))
def test_random_holes_in_a_plane(data, rel):
    s, truth, curved_length, kind = data
    tol = rel * max(s.size, 1.0)
    note(f"{kind} hole, tol {tol}, {describe(s)}, trim {[l.to_case() for l in s.trim]}")
    mesh = tessellate(s, tol)
    UV = mesh.uv[mesh.faces]
    cls = s.classify_uv(UV.mean(axis=1))
    assert not np.any(cls == OUTSIDE), f"{int((cls == OUTSIDE).sum())} centroids in the hole"
    assert_manifold_oriented(mesh.faces, kind)
    assert boundary_loops(mesh.faces) == 2
    # exact polygon: only rounding; circle: chords within tol of the circle
    bound = tol * curved_length + 1e-9 * truth
    assert abs(mesh.area - truth) <= bound, (f"{kind}: area {mesh.area} vs {truth}, "
                                             f"bound {bound}")
    assert mesh.max_deviation <= tol

@st.composite
def trimmed_freeforms(draw):
    s = draw(random_surfaces(rational=True))
    c = [draw(st.floats(0.3, 0.7)), draw(st.floats(0.3, 0.7))]
    r = draw(st.floats(0.02, 0.25))
    return Surface(s.degree_u, s.degree_v, s.knots_u, s.knots_v, regular_surface(s),
                   s.weights, trim=[circle_dict(c, r)])


@settings(max_examples=8)
@given(s=trimmed_freeforms(), rel=st.sampled_from([1e-2, 3e-3]))
def test_random_freeform_with_a_hole(s, rel):
    """A random freeform whose trim is one circle loop: the face is the disc inside it
    (an odd number of loops winds around a point inside the disc)."""
    tol = rel * s.size
    note(f"tol {tol}: geomkit.Surface(**{describe(s)}, trim={[l.to_case() for l in s.trim]})")
    mesh = tessellate(s, tol)
    UV = mesh.uv[mesh.faces]
    cls = s.classify_uv(UV.mean(axis=1))
    assert not np.any(cls == OUTSIDE), f"{int((cls == OUTSIDE).sum())} centroids outside"
    assert_manifold_oriented(mesh.faces)
    assert boundary_loops(mesh.faces) == 1
    r = naive.sample_mesh_deviation(mesh, [s], n_faces=3000, n_worst=300, exact_above=tol)
    assert r["to_surface"] <= tol * REL, r
    assert r["to_mesh"] <= tol * REL, r


NONUNIFORM_PLANE = dict(degree_u=1, degree_v=2, knots_u=[0, 0, 1, 1],
                        knots_v=[0, 0, 0, 0.123, 1, 1, 1],
                        control_points=[[[x, y, 0.0] for y in (0, 100 / 3, 200 / 3, 100)]
                                        for x in (0.0, 100.0)])
"""The square [0, 100]^2 (z = 0) with a non-uniform parametrization in v (knot 0.123,
evenly spaced control rows): UV straight lines are not straight in 3-D."""


@pytest.mark.parametrize("tol", [3e-2, 1e-2])
@pytest.mark.parametrize("kind", ["disc", "hole"])
def test_trim_on_a_nonuniformly_parametrized_plane(kind, tol):
    """A circle trim (centre (0.5, 0.3), radius 0.25 in UV) on a flat but non-uniformly
    parametrized square, as the face (disc) or as a hole in it.  Found by
    ``test_random_freeform_with_a_hole`` with more examples; kept as a fixed case.
    Both one-sided distances must hold along the trim, as everywhere; the trimmed
    region is planar, so the distances are also checked with shapely, exactly."""
    import shapely

    circle = circle_dict((0.5, 0.3), 0.25)
    trim = [circle] if kind == "disc" else [[[0, 0], [1, 0], [1, 1], [0, 1], [0, 0]], circle]
    s = Surface(**NONUNIFORM_PLANE, trim=trim)
    mesh = tessellate(s, tol)
    assert mesh.max_deviation <= tol
    r = naive.sample_mesh_deviation(mesh, [s], exact_above=tol)
    # exact, in the plane z = 0: the two-sided distance between the mesh boundary edges
    # along the trim and the exact trim curve (densely sampled; its sag ~1e-9)
    rep = edge_report(mesh.faces)
    E = mesh.vertices[rep["edges"][rep["count"] == 1]][:, :, :2]          # (k, 2, 2)
    on_square = ((np.abs(E) < 1e-9) | (np.abs(E - 100) < 1e-9)).any(axis=2).all(axis=1)
    E = E[~on_square]                          # the outer square (hole case) is exact
    lines, sag = naive.trim_boundary_polylines(s)
    C = lines[-1][:, :2]                       # the circle: the last loop, one piece
    bnd = shapely.multilinestrings(list(E))
    curve = shapely.LineString(C)
    probes = np.concatenate([E[:, 0], 0.5 * (E[:, 0] + E[:, 1]), E[:, 1]])
    gap = max(shapely.distance(shapely.points(C), bnd).max(),
              shapely.distance(shapely.points(probes), curve).max() - sag)
    assert r["to_surface"] <= tol * REL and r["to_mesh"] <= tol * REL and gap <= tol, (
        f"{kind} tol {tol}: mesh -> surface {r['to_surface'] / tol:.2f} tol, surface -> mesh "
        f"{r['to_mesh'] / tol:.2f} tol, trim curve vs mesh boundary "
        f"{gap / tol:.2f} tol, worst (face, point): {r['worst_to_surface']} / "
        f"{r['worst_to_mesh']}")


def test_trim_loop_straying_outside_the_domain_within_tolerance():
    """A trim loop may lie outside the domain by the validation tolerance (IGES files
    do this): the mesh boundary follows it clipped to the domain instead of failing."""
    P = np.array([[[0, 0, 0], [0, 1, 0]], [[1, 0, 0], [1, 1, 0.0]]])
    e = 1e-9
    loop = [[-e, -e], [1 + e, -e], [1 + e, 1 + e], [-e, 1 + e], [-e, -e]]
    s = Surface(1, 1, [0, 0, 1, 1], [0, 0, 1, 1], P, trim=[loop])
    mesh = tessellate(s, 1e-3)
    assert np.isfinite(mesh.vertices).all() and mesh.max_deviation <= 1e-3
    assert np.allclose(mesh.vertices.min(axis=0), 0) and np.allclose(mesh.vertices.max(axis=0),
                                                                     [1, 1, 0])
    assert abs(mesh.area - 1.0) < 1e-12


# ======================================================================== trimmed planes
def test_trim_polylines_chords_within_half_tol_of_the_exact_boundary():
    """The kernel's trim polylines against a dense sampling of the exact boundary
    curves S(C(t)) (``naive.trim_boundary_polylines``, 4000 points per span), both
    ways: every dense point is within the chord target of the polyline's 3-D chords,
    and every chord's midpoint within it (plus the dense polyline's sag) of the curve.
    On a curved freeform with a circle trim, the non-uniformly parametrized plane
    (where UV chords bow in 3-D) and a rotated plate with a hole."""
    from geomkit.mesh.trim_polylines import TrimPolylines
    from geomkit.mesh.tessellate import TRIM_TARGET

    rng = np.random.default_rng(11)
    nu = nv = 5
    gu, gv = np.meshgrid(np.linspace(0, 100, nu), np.linspace(0, 100, nv), indexing="ij")
    net = np.stack([gu, gv, 8.0 * rng.standard_normal((nu, nv))], axis=-1)
    knots = [0, 0, 0, 0, 0.5, 1, 1, 1, 1]
    free = Surface(3, 3, knots, knots, net, trim=[circle_dict((0.45, 0.55), 0.3)])
    nonuni = Surface(**NONUNIFORM_PLANE, trim=[circle_dict((0.5, 0.3), 0.25)])
    outer = [[0, 0], [1, 0], [1, 1], [0, 1], [0, 0]]
    plate = plane(80.0, 30.0, [outer, circle_dict((0.4, 0.6), 0.2)], rotation(0.3, -1.1, 2.0))
    for s in (free, nonuni, plate):
        for tol in (1e-1, 1e-2):
            target = TRIM_TARGET * tol
            loops = TrimPolylines(s, target).loops
            mine = [s.evaluate(L) for L in loops]
            dense, sag = naive.trim_boundary_polylines(s)
            dense = [d for d in dense if np.ptp(d, axis=0).max() > 0]
            if len(mine) < len(dense):   # the domain rectangle is left out (exact)
                dense = dense[len(dense) - len(mine):]
            X = np.concatenate(dense)
            d1 = naive.point_polyline_distance(X, mine).max()
            mids = np.concatenate([0.5 * (m[1:] + m[:-1]) for m in mine])
            d2 = naive.point_polyline_distance(mids, dense).max() - sag
            assert max(d1, d2) <= target * REL, (s, tol, d1, d2, target)


def test_trimmed_plane_direct_path_matches_the_cell_path(monkeypatch):
    """The plate with a hole through the direct path (no cells) and, with it switched
    off, through the cell path: both hold tol by the independent sampler, both have
    the hole as a second boundary loop with its vertices on the circle, and their
    areas agree with the analytic area within the chord bound."""
    import importlib

    T = importlib.import_module("geomkit.mesh.tessellate")
    case = case_of("plate_with_hole")
    tol = 1e-2
    direct = tessellate(case.surfaces, tol)
    monkeypatch.setattr(T, "affine_map", lambda s, size: None)
    cells = tessellate(case.surfaces, tol)
    assert direct.stats["surfaces"][0].get("planar_trimmed") is True
    assert "planar_trimmed" not in cells.stats["surfaces"][0]
    truth = case.truth["area"]
    for mesh in (direct, cells):
        assert mesh.max_deviation <= tol
        r = naive.sample_mesh_deviation(mesh, case.surfaces, exact_above=tol)
        assert r["to_surface"] <= tol * REL and r["to_mesh"] <= tol * REL, r
        assert_manifold_oriented(mesh.faces)
        assert boundary_loops(mesh.faces) == 2
        assert abs(mesh.area - truth) <= tol * 2 * math.pi * 20.0
        rep = edge_report(mesh.faces)
        bv = np.unique(rep["edges"][rep["count"] == 1])
        rho = np.hypot(mesh.vertices[bv, 0] - 50.0, mesh.vertices[bv, 1] - 50.0)
        assert np.abs(rho[rho < 30] - 20.0).max() <= 1e-9


def test_planar_triangulation_falls_back_when_delaunay_misses_a_boundary_edge():
    """A comb-shaped trim (long thin teeth) whose vertices' Delaunay triangulation
    crosses the boundary: the check sees it and the constrained triangulation is used;
    either way the triangles cover exactly the polygon (area, shapely containment)
    and every boundary edge is a triangle edge."""
    import shapely

    from geomkit.mesh.trim_polylines import TrimPolylines, _delaunay_inside, planar_trimmed

    teeth = []
    for i in range(6):
        x = 0.1 + 0.13 * i
        teeth += [[x, 0.1], [x + 0.02, 0.9], [x + 0.07, 0.9], [x + 0.09, 0.1 + 0.05]]
    comb = teeth + [[0.95, 0.1 + 0.05], [0.95, 0.05], [0.1, 0.05], teeth[0]]
    s = plane(10.0, 10.0, [comb])
    trim = TrimPolylines(s, 1e-3)
    region = trim.region
    assert _delaunay_inside(region)[1] is None, "the comb no longer needs the fallback"
    uv, F = planar_trimmed(trim)
    tri = uv[F]
    a = tri[:, 1] - tri[:, 0]
    b = tri[:, 2] - tri[:, 0]
    area2 = a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0]
    assert np.all(area2 > 0)
    assert abs(0.5 * area2.sum() - region.area) <= 1e-12
    polys = shapely.polygons(tri)
    assert shapely.covers(shapely.buffer(region, 1e-12), polys).all()
    P = np.asarray(comb)
    keys = {tuple(sorted((tuple(p), tuple(q)))) for t in tri for p, q in
            ((t[0], t[1]), (t[1], t[2]), (t[2], t[0]))}
    for p, q in zip(P[:-1], P[1:]):
        assert tuple(sorted((tuple(p), tuple(q)))) in keys, (p, q)
    mesh = tessellate(s, 1e-3)
    assert mesh.stats["surfaces"][0].get("planar_trimmed") is True
    assert_manifold_oriented(mesh.faces) and boundary_loops(mesh.faces) == 1
    assert abs(mesh.area - 100.0 * region.area) <= 1e-9


def test_affine_test_uses_greville_abscissae():
    """A degree-2 B-spline over three spans whose net is the affine image of its
    Greville abscissae is an affine map (two triangles, deviation 0, vertices on S),
    trimmed too (direct path, area exact for a polygon hole); moving one interior
    control point in the plane (still flat, no longer affine) sends it to the cell
    path."""
    from geomkit.mesh.trim_polylines import affine_map

    ku = [0, 0, 0, 0.2, 0.7, 1, 1, 1]
    kv = [0, 0, 0.5, 1, 1]
    gu = np.array([(ku[i + 1] + ku[i + 2]) / 2 for i in range(5)])
    gv = np.array(kv[1:4])
    o, a, b = np.array([1.0, 2, 3]), np.array([40.0, 5, 0]), np.array([-3.0, 20, 7])
    net = o + gu[:, None, None] * a + gv[None, :, None] * b
    s = Surface(2, 1, ku, kv, net)
    assert affine_map(s, s.size) is not None
    m = tessellate(s, 1e-3)
    assert len(m.faces) == 2 and m.max_deviation == 0.0
    assert np.allclose(s.evaluate(m.uv), m.vertices, atol=1e-12)
    hole = [[0.3, 0.3], [0.6, 0.35], [0.5, 0.7], [0.3, 0.3]]
    outer = [[0, 0], [1, 0], [1, 1], [0, 1], [0, 0]]
    st_ = Surface(2, 1, ku, kv, net, trim=[outer, hole])
    mt = tessellate(st_, 1e-3)
    assert mt.stats["surfaces"][0].get("planar_trimmed") is True
    full = np.linalg.norm(np.cross(a, b))
    hole_uv = 0.5 * abs((0.6 - 0.3) * (0.7 - 0.3) - (0.5 - 0.3) * (0.35 - 0.3))
    assert abs(mt.area - full * (1 - hole_uv)) <= 1e-9 * full
    r = naive.sample_mesh_deviation(mt, [st_], exact_above=1e-3)
    assert r["to_surface"] <= 1e-9 and r["to_mesh"] <= 1e-9
    bent = net.copy()
    bent[2, 1] += 0.2 * a          # in the plane: flat, but S is no longer affine
    s2 = Surface(2, 1, ku, kv, bent, trim=[outer, hole])
    assert affine_map(s2, s2.size) is None
    m2 = tessellate(s2, 1e-3)
    assert "planar_trimmed" not in m2.stats["surfaces"][0] and m2.max_deviation <= 1e-3


def _segment_distances(X, E):
    """(n,) distance of each point ``X`` (n, 3) to the nearest of the segments ``E``
    (k, 2, 3), by brute force."""
    A, d = E[:, 0], E[:, 1] - E[:, 0]
    dd = np.maximum((d * d).sum(axis=1), 1e-300)
    out = np.empty(len(X))
    for a in range(0, len(X), 256):
        P = X[a:a + 256, None]
        w = np.clip(((P - A) * d).sum(axis=2) / dd, 0.0, 1.0)
        out[a:a + 256] = np.linalg.norm(P - (A + w[..., None] * d), axis=2).min(axis=1)
    return out


@pytest.mark.parametrize("part", ["nist_ctc_05_ap203.stp", "nist_ftc_06_ap242.stp",
                                  "euclid_screw_ap214.step", "ug16_io1_ap214.stp",
                                  "inventor2015_cylinder_block_face6.stp"])
def test_mesh_boundary_follows_the_trim_curves_of_real_parts(part):
    """On every trimmed face of real parts (planes with holes and slots, cylinders,
    cones, a screw, Inventor's quintic pcurve), the mesh boundary and the exact trim
    curves ``S(C(t))`` (200 points a knot span) lie within tol of each other both ways:
    the trim polylines' rule (the chord within tol / 2 of its UV chord's image, and
    within tol / 2 of the curve or 0.9 tol with the two added) holds where the mesh is
    made.  Pieces with no boundary edge along them (a closed surface's seam, welded)
    are left out of the curve -> boundary side."""
    from helpers.parts import part_surfaces

    S, size = part_surfaces(part)
    tol = 1e-3 * size
    m = tessellate(S, tol)
    checked = 0
    for i, s in enumerate(S):
        F = m.faces[m.face_surface == i]
        if not s.trim or not len(F):
            continue
        e = np.sort(np.concatenate([F[:, [0, 1]], F[:, [1, 2]], F[:, [2, 0]]]), axis=1)
        u, c = np.unique(e, axis=0, return_counts=True)
        E = m.vertices[u[c == 1]]
        lines, sag = naive.trim_boundary_polylines(s, per_span=200)
        for P in lines:
            d = _segment_distances(P, E)
            if np.median(d) < 0.5 * tol:  # (a seam's piece: no boundary along it)
                assert d.max() <= tol, (part, i, d.max() / tol)
                checked += 1
        X = np.concatenate([E[:, 0], 0.5 * (E[:, 0] + E[:, 1]), E[:, 1]])
        d = naive.point_polyline_distance(X, lines)
        on = d < 5 * tol  # boundary points along the trim (not on a domain edge)
        assert (d[on] - sag <= tol).all(), (part, i, (d[on] - sag).max() / tol)
    assert checked >= 2  # (the one-face Inventor part: its two curved pieces)
