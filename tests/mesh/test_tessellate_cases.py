"""Tessellation: hard cases (poles, crease, heavy weights, twist, a tiny trim loop,
two surfaces), economy (planes are two triangles, cylinder face counts), input errors,
random surfaces (hypothesis) and the fast paths (uniform grid, hanging-node counts,
the measurement cache, degenerate triangles, affine planes).  The oracles are the
ones of tests/mesh/test_tessellate.py."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import HealthCheck, given, note, settings
from hypothesis import strategies as st

from geomkit import OUTSIDE, InvalidInputError, Surface, samples
from geomkit.mesh.tessellate import tessellate

from helpers import naive
from helpers.surfaces import describe, random_surfaces
from helpers.tesshelp import (REL, assert_manifold_oriented, boundary_loops, case_of,
                              circle_dict, edge_report, euler_characteristic, face_areas,
                              mesh_of, plane, regular_surface, surface_faces)


# ======================================================================== 5. hard cases
@pytest.mark.parametrize("tol", [1e-2, 1e-3])
def test_sphere_poles(tol):
    case, mesh = mesh_of("sphere", tol)
    s = case.surfaces[0]
    edges = naive.surface_edges(s)
    assert edges["poles"] == {"v0", "v1"} and edges["closed_u"]
    V = mesh.vertices
    for v in (0.0, 1.0):
        pole = s.evaluate([0.37, v])
        at = np.nonzero(np.linalg.norm(V - pole, axis=1) <= 1e-9 * s.size)[0]
        assert len(at) == 1, f"{len(at)} vertices at the pole v = {v}"
        # the pole vertex is used, by a fan of faces all around it
        fan = np.nonzero((mesh.faces == at[0]).any(axis=1))[0]
        assert len(fan) >= 3
    assert mesh.to_trimesh().is_watertight
    area = face_areas(V, mesh.faces)
    j = int(np.argmin(area))
    assert area[j] > 1e-12 * s.size ** 2, (
        f"{int((area <= 1e-12 * s.size ** 2).sum())} degenerate faces, smallest area "
        f"{area[j]:.3g} at uv {mesh.uv[mesh.faces[j]].tolist()}")


@pytest.mark.parametrize("tol", [1e-2, 1e-3, 1e-4])
def test_crease_is_a_mesh_edge(tol):
    """C0 at u = 0.5: no triangle straddles it in UV."""
    _, mesh = mesh_of("crease", tol)
    u = mesh.uv[mesh.faces][..., 0]
    straddle = ~(np.all(u <= 0.5, axis=1) | np.all(u >= 0.5, axis=1))
    assert not straddle.any(), (f"{int(straddle.sum())} faces straddle u = 0.5, e.g. "
                                f"{mesh.uv[mesh.faces[straddle][0]].tolist()}")
    # and the crease line is there: vertices on u = 0.5 spanning v in [0, 1]
    on = mesh.uv[np.abs(mesh.uv[:, 0] - 0.5) <= 0.0]
    assert on[:, 1].min() == 0.0 and on[:, 1].max() == 1.0


def test_heavy_weights_dense_sampling():
    """Weights 200 and 0.005 in one net: the deviation holds with 12 random points per
    face on every face (a different random stream from the generic test)."""
    tol = 1e-2
    case, mesh = mesh_of("heavy_weights", tol)
    r = naive.sample_mesh_deviation(mesh, case.surfaces, n_faces=10 ** 6, k_mesh=12,
                                    k_surf=6, seed=7, exact_above=tol)
    assert r["faces"] == len(mesh.faces)
    assert r["to_surface"] <= tol * REL, r["worst_to_surface"]
    assert r["to_mesh"] <= tol * REL, r["worst_to_mesh"]


@pytest.mark.parametrize("tol", [1e-2, 1e-3])
def test_saddle_twist(tol):
    """z = x y / 10: a bilinear twist is not flat anywhere, so two triangles per cell
    deviate by up to 10 at the centre; the mesh refines and stays within tol."""
    _, mesh = mesh_of("saddle", tol)
    V = mesh.vertices
    assert np.abs(V[:, 2] - V[:, 0] * V[:, 1] / 10).max() <= 1e-12 * 35
    # independent: the analytic distance to z = x y / 10 from face points, by Newton
    # on the parameters (x, y) of the graph
    rng = np.random.default_rng(3)
    T = V[mesh.faces]
    bary = naive.random_barycentric(rng, len(T), 6).reshape(-1, 3)
    X = np.einsum("nc,ncd->nd", bary, np.repeat(T, 6, axis=0))
    x, y = X[:, 0].copy(), X[:, 1].copy()
    for _ in range(20):   # minimise (x-X)^2 + (y-Y)^2 + (xy/10 - Z)^2
        f = x * y / 10 - X[:, 2]
        gx = (x - X[:, 0]) + f * y / 10
        gy = (y - X[:, 1]) + f * x / 10
        hxx = 1 + (y / 10) ** 2
        hyy = 1 + (x / 10) ** 2
        hxy = (x / 10) * (y / 10) + f / 10
        det = hxx * hyy - hxy ** 2
        x, y = x - (hyy * gx - hxy * gy) / det, y - (hxx * gy - hxy * gx) / det
    d = np.sqrt((x - X[:, 0]) ** 2 + (y - X[:, 1]) ** 2 + (x * y / 10 - X[:, 2]) ** 2)
    assert d.max() <= tol * REL
    assert d.max() > 0.2 * tol      # the mesh is not trivially fine: it uses the budget
    assert len(mesh.faces) > 100


@pytest.mark.parametrize("tol", [5e-2, 1e-2, 1e-3])
def test_tiny_trim_loop_is_a_hole(tol):
    """A hole of radius 1e-4 in UV (0.01 in 3-D) in a 100 x 100 plane stays a hole, also
    when it is smaller than the tolerance (its polyline keeps three edges or more)."""
    c, r = (0.37, 0.61), 1e-4
    s = plane(100.0, 100.0, [[[0, 0], [1, 0], [1, 1], [0, 1], [0, 0]], circle_dict(c, r)])
    mesh = tessellate(s, tol)
    assert_manifold_oriented(mesh.faces, "tiny hole")
    assert boundary_loops(mesh.faces) == 2
    # the inner loop's vertices lie on the circle (3-D radius 0.01 around (37, 61))
    r = edge_report(mesh.faces)
    bv = np.unique(r["edges"][r["count"] == 1])
    r3 = np.hypot(mesh.vertices[bv, 0] - 37.0, mesh.vertices[bv, 1] - 61.0)
    inner = r3 < 1.0
    assert inner.sum() >= 3 and np.abs(r3[inner] - 0.01).max() <= 1e-9
    UV = mesh.uv[mesh.faces]
    assert not np.any(s.classify_uv(UV.mean(axis=1)) == OUTSIDE)
    truth = 1e4 - math.pi * 0.01 ** 2
    assert abs(mesh.area - truth) <= tol * 2 * math.pi * 0.01 + 1e-9 * truth


@pytest.mark.parametrize("tol", [1e-2, 1e-3])
def test_sphere_pair_two_surfaces(tol):
    case, mesh = mesh_of("sphere_pair", tol)
    assert set(np.unique(mesh.face_surface)) == {0, 1}
    assert set(np.unique(mesh.vertex_surface)) == {0, 1}
    # every face uses vertices of its own surface only: no vertex shared
    assert np.all(mesh.vertex_surface[mesh.faces] == mesh.face_surface[:, None])
    for i in (0, 1):
        F = surface_faces(mesh, i)
        assert_manifold_oriented(F, f"sphere_pair[{i}]")
        assert euler_characteristic(F) == 2
        assert boundary_loops(F) == 0
    assert mesh.to_trimesh().is_watertight
    # the two spheres are apart by the truth's min distance (5): no vertex of one is
    # within 5 - 2 tol of the other's vertices
    from scipy.spatial import cKDTree
    a = mesh.vertices[mesh.vertex_surface == 0]
    b = mesh.vertices[mesh.vertex_surface == 1]
    d, _ = cKDTree(a).query(b, k=1)
    assert d.min() >= case.truth["min_distance"] - 2 * tol


# ======================================================================== 6. economy
@pytest.mark.parametrize("tol", [1e-2, 1e-3, 1e-4])
def test_flat_planes_are_two_triangles(tol):
    _, mesh = mesh_of("offset_planes", tol)
    assert np.bincount(mesh.face_surface).tolist() == [2, 2]


def test_cylinder_face_count_grows_like_inverse_sqrt_tol():
    """Singly curved: the chord error needs h ~ sqrt(tol) across, nothing along, so the
    face count grows ~ 1/sqrt(tol): ~10x from 1e-2 to 1e-4 (1/tol would be 100x)."""
    n = {t: len(mesh_of("cylinder_quarter", t)[1].faces) for t in (1e-2, 1e-3, 1e-4)}
    assert n[1e-2] < n[1e-3] < n[1e-4]
    ratio = n[1e-4] / n[1e-2]
    assert 6 <= ratio <= 16, f"face counts {n}: ratio {ratio:.2f}"


# ======================================================================== 7. input errors
CYL = samples.load("cylinder_quarter")


@pytest.mark.parametrize("kwargs, field", [
    (dict(tol=0.0), "tol"), (dict(tol=-1e-3), "tol"), (dict(tol=float("nan")), "tol"),
    (dict(tol=float("inf")), "tol"), (dict(tol="abc"), "tol"), (dict(tol=None), "tol"),
    (dict(tol=1e-2, max_angle=math.pi), "max_angle"),
    (dict(tol=1e-2, max_angle=4.0), "max_angle"),
    (dict(tol=1e-2, max_angle=0.0), "max_angle"),
    (dict(tol=1e-2, max_angle=float("nan")), "max_angle"),
    (dict(tol=1e-2, max_angle="abc"), "max_angle"),
    (dict(tol=1e-2, max_edge=0.0), "max_edge"), (dict(tol=1e-2, max_edge=-1.0), "max_edge"),
    (dict(tol=1e-2, max_edge=float("nan")), "max_edge"),
    (dict(tol=1e-2, max_edge="abc"), "max_edge"),
    (dict(tol=1e-2, samples_per_edge=1), "samples_per_edge"),
], ids=lambda v: repr(v) if not isinstance(v, dict) else
    ",".join(f"{k}={v[k]!r}" for k in v))
def test_bad_arguments_name_the_field(kwargs, field):
    with pytest.raises(InvalidInputError) as exc:
        tessellate(CYL, **kwargs)
    assert exc.value.field == field
    assert field in str(exc.value)


@pytest.mark.parametrize("bad", ["sphere", [], [CYL[0], "x"], None, 42, CYL[0].to_dict()],
                         ids=["str", "empty", "mixed", "None", "int", "dict"])
def test_non_surface_input_names_the_field(bad):
    """The error names the argument, or the element of a list that is not a Surface."""
    with pytest.raises(InvalidInputError) as exc:
        tessellate(bad, 1e-2)
    assert exc.value.field == ("surfaces[1]" if isinstance(bad, list) and bad else "surfaces")


@pytest.mark.parametrize("fn", ["tessellate", "project_points", "plane_section",
                                "surface_distance", "save"])
def test_every_entry_point_checks_surfaces_alike(fn, tmp_path):
    """One validator for every entry point taking surfaces: the same field and message."""
    import geomkit

    calls = {"tessellate": lambda x: geomkit.tessellate(x, 1e-2),
             "project_points": lambda x: geomkit.project_points(x, [[0.0, 0.0, 0.0]]),
             "plane_section": lambda x: geomkit.plane_section(x, (0.0, 0.0, 1.0, 0.0)),
             "surface_distance": lambda x: geomkit.surface_distance(x, CYL),
             "save": lambda x: geomkit.save(tmp_path / "c.json", x)}
    for bad, field in (("sphere", None), ([CYL[0], 7], "[1]")):
        with pytest.raises(InvalidInputError) as exc:
            calls[fn](bad)
        if field:
            assert exc.value.field.endswith(field), (fn, exc.value.field)
        assert "Surface" in str(exc.value), (fn, str(exc.value))

# ======================================================================== 8. hypothesis
@st.composite
def regular_random_surfaces(draw):
    """Surfaces from conftest's ``random_surfaces`` (rational: random degrees, knots,
    weights in [0.05, 20]) made regular by :func:`regular_surface`: raw draws are mostly
    degenerate (size 0, collapsed rows, boundaries touching themselves), where "no
    degenerate faces" and "manifold" are not meaningful."""
    s = draw(random_surfaces(rational=True))
    return Surface(s.degree_u, s.degree_v, s.knots_u, s.knots_v, regular_surface(s),
                   s.weights)


@settings(max_examples=10, suppress_health_check=[HealthCheck.too_slow])
@given(s=regular_random_surfaces(), rel=st.sampled_from([1e-2, 3e-3]))
def test_random_surfaces_deviation_manifold_no_degenerate_faces(s, rel):
    tol = rel * s.size
    note(f"tol {tol}: geomkit.Surface(**{describe(s)})")
    mesh = tessellate(s, tol)
    assert mesh.max_deviation <= tol
    assert_manifold_oriented(mesh.faces, "random")
    assert boundary_loops(mesh.faces) == 1          # a disc
    area = face_areas(mesh.vertices, mesh.faces)
    assert area.min() > 1e-12 * s.size ** 2
    r = naive.sample_mesh_deviation(mesh, [s], n_faces=2000, n_worst=300, exact_above=tol)
    assert r["to_surface"] <= tol * REL, r
    assert r["to_mesh"] <= tol * REL, r


# ======================================================================== 8. fast paths
def test_uniform_grid_and_adaptive_paths_both_hold_tol(monkeypatch):
    """A small untrimmed surface is meshed as one measured uniform grid; with the grid
    path switched off the adaptive path meshes it instead: both meshes pass the
    independent sampler and have comparable sizes."""
    import importlib

    T = importlib.import_module("geomkit.mesh.tessellate")  # the module, not the function
    case = case_of("cylinder_quarter")
    tol = 1e-3
    grid = tessellate(case.surfaces, tol)
    monkeypatch.setattr(T, "GRID_CELLS", 0)
    adaptive = tessellate(case.surfaces, tol)
    assert grid.stats["surfaces"][0].get("uniform_grid") is True
    assert "uniform_grid" not in adaptive.stats["surfaces"][0]
    for mesh in (grid, adaptive):
        assert mesh.max_deviation <= tol
        r = naive.sample_mesh_deviation(mesh, case.surfaces, exact_above=tol)
        assert r["to_surface"] <= tol * REL and r["to_mesh"] <= tol * REL, r
        assert_manifold_oriented(mesh.faces)
    assert 0.5 <= len(grid.faces) / len(adaptive.faces) <= 1.5


def test_uniform_grid_refuses_a_failing_grid():
    """A grid whose cells fail the measurement is not returned (the adaptive path
    takes over): heavy_weights with the grid predicted for 1000 x tol."""
    from geomkit.mesh import quadtree as qt

    s = samples.load("heavy_weights")[0]
    ub = np.unique(s.knots_u[s.degree_u:len(s.knots_u) - s.degree_u])
    vb = np.unique(s.knots_v[s.degree_v:len(s.knots_v) - s.degree_v])
    # target = 100 tol: the predicted grid is much too coarse for tol, twice
    assert qt.uniform_grid(s, ub, vb, 7, 6, 1e-3, 1e3 * 1e-3, 1e-3, 4096) is None
    c = samples.load("cylinder_quarter")[0]  # a grid that passes, for contrast
    out = qt.uniform_grid(c, np.array([0.0, 1.0]), np.array([0.0, 1.0]), 5, 6, 1e-3, 0.9e-3,
                          1e-3, 4096)
    assert out is not None and 0 < out[1].max() <= 1e-3 and len(out[0]) == 2 * len(out[2])


def test_hanging_node_counts_match_brute_force():
    """Kernel counts of lattice points strictly inside each cell edge, against a
    direct count over all points, on a randomly refined cell set."""
    from geomkit.mesh import quadtree as qt

    rng = np.random.default_rng(3)
    lat = qt.Lattice(np.array([0.0, 0.5, 1.0]), np.array([0.0, 1.0]))
    cells = lat.roots()
    for _ in range(6):
        pick = rng.random(len(cells)) < 0.4
        nu = np.where(pick, rng.integers(1, 4, len(cells)), 1)
        nv = np.where(pick, rng.integers(1, 4, len(cells)), 1)
        cells = qt.split(cells, nu, nv)
    pts = qt.lattice_points(cells)
    got = qt.EdgeIndex(pts, sorted_rows=True).counts(cells)
    gu, gv = pts[:, 0][None, :], pts[:, 1][None, :]
    iu0, iu1, iv0, iv1 = (cells[:, i][:, None] for i in range(4))
    inside_u = (gu > iu0) & (gu < iu1)
    inside_v = (gv > iv0) & (gv < iv1)
    want = np.stack([(inside_u & (gv == iv0)).sum(1), (inside_v & (gu == iu1)).sum(1),
                     (inside_u & (gv == iv1)).sum(1), (inside_v & (gu == iu0)).sum(1)], 1)
    assert np.array_equal(got, want)
    assert got.sum() > 0  # the refinement left hanging nodes to count
    keys = np.concatenate([cells[:, 2] * qt.KEY + cells[:, 0], cells[:, 3] * qt.KEY + cells[:, 1]])
    assert np.array_equal(qt.unique_ints(keys), np.unique(keys))


def test_measured_triangles_are_found_only_when_identical():
    """The cache of earlier measurements returns a value only for a triangle with the
    same six UV coordinates (bit for bit), NaN otherwise."""
    import importlib

    _Measured = importlib.import_module("geomkit.mesh.cells")._Measured
    rng = np.random.default_rng(0)
    tri = rng.random((500, 3, 2))
    cache = _Measured()
    assert np.isnan(cache.get(tri)).all()
    cache.add(tri[:300], np.arange(300.0))
    cache.add(tri[300:400], np.arange(300.0, 400.0))
    probe = tri[::-1].copy()
    probe[0, 0, 0] = np.nextafter(probe[0, 0, 0], 2.0)  # one ulp off: tri[499], unseen
    probe[100, 2, 1] = np.nextafter(probe[100, 2, 1], 2.0)  # tri[399] moved: not found
    got = cache.get(probe)
    want = np.where(np.arange(500)[::-1] < 400, np.arange(500.0)[::-1], np.nan)
    want[100] = np.nan
    assert np.array_equal(got, want, equal_nan=True)


@pytest.mark.parametrize("order", ["aab", "abb", "aba", "collinear"])
def test_closest_on_degenerate_triangles_is_the_segment_distance(order):
    """Triangles with coincident or collinear corners (poles make them): the distance
    equals the exact point-to-segment distance (closed form), in every corner order;
    contracted products once sent b == c into the interior branch (errors ~100)."""
    from geomkit._kernels.triangles import closest_on_triangle

    rng = np.random.default_rng(7)
    for _ in range(300):
        x, y, p = rng.normal(size=(3, 3))
        tri = {"aab": (x, x.copy(), y), "abb": (x, y, y.copy()), "aba": (x, y, x.copy()),
               "collinear": (x, y, x + 0.3 * (y - x))}[order]
        d, s, w = closest_on_triangle(*p, *tri[0], *tri[1], *tri[2])
        t = np.clip(np.dot(p - x, y - x) / np.dot(y - x, y - x), 0.0, 1.0)
        exact = np.linalg.norm(x + t * (y - x) - p)
        q = tri[0] + s * (tri[1] - tri[0]) + w * (tri[2] - tri[0])
        assert abs(d - exact) <= 1e-12 * (1 + exact)
        assert abs(np.linalg.norm(q - p) - d) <= 1e-12 * (1 + exact)


def test_affine_plane_is_its_two_triangles_and_twisted_is_not():
    """A parallelogram net (any orientation, equal weights) is meshed as its own two
    triangles with deviation 0; a twisted bilinear patch (saddle) or a rational one
    with unequal weights goes through the measured paths."""
    rng = np.random.default_rng(5)
    Q, _ = np.linalg.qr(rng.normal(size=(3, 3)))
    o, a, b = rng.normal(size=3), 3.0 * Q[0], 0.5 * Q[1] + 2.0 * Q[2]
    net = np.array([[o, o + b], [o + a, o + a + b]])
    plane = Surface(1, 1, [0, 0, 2, 2], [0, 0, 1, 1], net)
    m = tessellate(plane, 1e-3)
    assert m.stats["surfaces"][0].get("affine_plane") is True
    assert len(m.faces) == 2 and m.max_deviation == 0.0
    assert np.allclose(plane.evaluate(m.uv), m.vertices, atol=1e-14)
    r = naive.sample_mesh_deviation(m, [plane], exact_above=1e-3)
    assert r["to_surface"] <= 1e-12 and r["to_mesh"] <= 1e-12
    twisted = net.copy()
    twisted[1, 1] += 0.3 * np.cross(a, b) / np.linalg.norm(np.cross(a, b))
    rational = Surface(1, 1, [0, 0, 2, 2], [0, 0, 1, 1], net, weights=[[1, 2], [1, 1]])
    for s in (Surface(1, 1, [0, 0, 2, 2], [0, 0, 1, 1], twisted), rational):
        st = tessellate(s, 1e-3).stats["surfaces"][0]
        assert "affine_plane" not in st
