"""Tests of geomkit.tessellate: the chord tolerance holds, measured independently.

What is checked, and against what:

1. **Deviation** — an independent sampler (``tests/naive.py``,
   :func:`naive.sample_mesh_deviation`; it never calls geomkit's tessellation kernels,
   only ``Surface.evaluate``/``derivatives``/``classify_uv``) bounds both one-sided
   distances on every face (on meshes of more than 30k faces: 30k random faces plus
   the 2,000 with the largest reported ``face_deviation``):

   * mesh -> surface: random barycentric points X of each 3-D triangle (plus its
     centroid, plus random points on the mesh boundary edges) are projected onto the
     surface by a damped Newton iteration on |S(u, v) - X|^2 from the barycentric UV
     (second derivatives from ``Surface.derivatives(uv, 2)``, clamped to the domain);
     |X - S(uv*)| is an upper bound of dist(X, S) whatever the convergence; points still
     above tol are projected again from the nearest points of a 129 x 129 parameter
     grid.  A foot point outside the trim is replaced by the distance to the exact trim
     boundary.
   * surface -> mesh: random UV points in each face's UV triangle (faces touching a
     pole are skipped: their pole vertex keeps only one of its parameters; seam
     vertices are moved to the face's side), and points of the exact trim curves,
     mapped by S; distance to the mesh by trimesh's point–triangle routine over
     candidate triangles (nearest centroids), made exact (every triangle that could be
     closer) for the points above tol.
     (``trimesh.proximity.closest_point`` needs ``rtree``, which is not a geomkit
     dependency; the candidate search replaces its r-tree.)

   Both must be ``<= tol (1 + 1e-9)``, on every sample at tol 1e-2 and 1e-3, and at
   1e-4 for the cases that tessellate in a few seconds there.
2. **Area** against the analytic truth within a stated first-order bound (see
   :func:`test_area_within_curvature_and_chord_bound`), shrinking with tol.
3. **Clean meshes**: manifold and consistently oriented, boundary edges only on the
   domain edge or a trim, sphere and torus closed with Euler characteristic 2 and 0,
   no near-zero-area faces, face normals agreeing with the surface normals (and, beyond
   the issue's list, no sliver edges shorter than tol/100 on untrimmed surfaces).
4. **Trims**: no face centroid outside the trimmed region; trimmed area matches the
   analytic area (hypothesis-generated holes too); a circle trim on a non-uniformly
   parametrized plane (a case hypothesis found) keeps both distances.
5. **Hard cases**: poles, crease, heavy weights, twist, a tiny trim loop, two surfaces.
6. **Economy**: a plane is two triangles; a cylinder's face count grows like 1/sqrt(tol).
7. **Input errors** name the field.
8. **Random surfaces** (hypothesis): deviation, manifold, no degenerate faces.

Meshes of the bundled cases are built once per (case, tol) and shared between tests.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import HealthCheck, given, note, settings
from hypothesis import strategies as st

import geomkit
from geomkit import ON_BOUNDARY, OUTSIDE, InvalidInputError, Surface, samples
from geomkit.tessellate import tessellate

import naive
from conftest import describe, random_surfaces

NAMES = samples.names()
REL = 1 + 1e-9                       # rounding slack on "<= tol"
FAST_1E4 = ["crease", "cylinder_quarter", "offset_planes", "plate_with_hole", "saddle"]
"""Cases whose tol 1e-4 mesh builds in a few seconds (crease and saddle: ~2-4 s, 200k+
faces, sampled on 32k of them).  Measured while writing these tests, at 1e-4: sphere
~33 s, wave_seed003 ~44 s, torus ~60 s, freeform_1 ~150 s, heavy_weights > 8 min; those
are checked at 1e-2 and 1e-3 only, to keep this file within ~4 minutes."""
S2 = 2 ** -0.5

_CASES: dict = {}
_MESHES: dict = {}


def case_of(name):
    if name not in _CASES:
        _CASES[name] = samples.load_case(name)
    return _CASES[name]


def mesh_of(name, tol):
    """(case, mesh) for a bundled case, tessellated once per (name, tol)."""
    key = (name, tol)
    if key not in _MESHES:
        case = case_of(name)
        _MESHES[key] = tessellate(case.surfaces, tol)
    return case_of(name), _MESHES[key]


# ------------------------------------------------------------------ mesh helpers
def directed_edges(F):
    """(3m, 2) directed edges (a, b) of faces F (m, 3), face-major."""
    return np.stack([F, np.roll(F, -1, axis=1)], axis=-1).reshape(-1, 2)


def edge_report(F):
    """Undirected edges of faces F (m, 3) with their multiplicities, the undirected edge
    of each directed edge (face-major, ``3 * face + corner``), and the largest
    multiplicity of a directed edge."""
    d = directed_edges(F).astype(np.int64)
    n = int(F.max(initial=0)) + 1
    lo, hi = d.min(axis=1), d.max(axis=1)
    ukey, inv, cnt = np.unique(lo * n + hi, return_inverse=True, return_counts=True)
    _, dcnt = np.unique(d[:, 0] * n + d[:, 1], return_counts=True)
    return {"edges": np.stack([ukey // n, ukey % n], axis=1), "count": cnt,
            "edge_of": inv.ravel(), "max_count": int(cnt.max(initial=0)),
            "max_directed": int(dcnt.max(initial=0))}


def assert_manifold_oriented(F, what=""):
    """Every edge is used by one face (boundary) or two faces that traverse it in
    opposite directions (so the surface is a manifold, consistently oriented)."""
    assert len(F), f"{what}: no faces"
    assert np.all((F[:, 0] != F[:, 1]) & (F[:, 1] != F[:, 2]) & (F[:, 0] != F[:, 2])), \
        f"{what}: a face repeats a vertex"
    r = edge_report(F)
    bad = np.nonzero(r["count"] > 2)[0]
    assert not len(bad), (f"{what}: {len(bad)} edges shared by more than two faces, e.g. "
                          f"{r['edges'][bad[:3]].tolist()} x{r['count'][bad[:3]].tolist()}")
    assert r["max_directed"] == 1, (f"{what}: an edge is traversed twice in the same "
                                    "direction (inconsistent orientation)")
    return r


def euler_characteristic(F):
    r = edge_report(F)
    return len(np.unique(F)) - len(r["edges"]) + len(F)


def boundary_loops(F):
    """Number of closed boundary loops of faces F (boundary vertices must have degree 2)."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    r = edge_report(F)
    B = r["edges"][r["count"] == 1]
    if not len(B):
        return 0
    verts, local = np.unique(B, return_inverse=True)
    local = local.reshape(-1, 2)
    deg = np.bincount(local.ravel(), minlength=len(verts))
    assert np.all(deg == 2), f"boundary is not a set of simple loops (degrees {np.unique(deg)})"
    n = len(verts)
    g = coo_matrix((np.ones(len(local)), (local[:, 0], local[:, 1])), shape=(n, n))
    return int(connected_components(g, directed=False)[0])


def face_areas(V, F):
    T = V[F]
    return 0.5 * np.linalg.norm(np.cross(T[:, 1] - T[:, 0], T[:, 2] - T[:, 0]), axis=1)


def surface_faces(mesh, i):
    """Faces of surface i (global vertex indices)."""
    return mesh.faces[mesh.face_surface == i]


def id_of(name, tol):
    return f"{name}-{tol:g}"


# ======================================================================== 1. deviation
DEVIATION_CASES = ([pytest.param(n, t, id=id_of(n, t)) for t in (1e-2, 1e-3) for n in NAMES]
                   + [pytest.param(n, 1e-4, id=id_of(n, 1e-4)) for n in FAST_1E4])


@pytest.mark.parametrize("name, tol", DEVIATION_CASES)
def test_deviation_independent_sampler(name, tol):
    """Both one-sided distances, sampled independently, are within tol everywhere."""
    case, mesh = mesh_of(name, tol)
    m = len(mesh.faces)
    assert mesh.face_deviation.shape == (m,)
    assert np.all(np.isfinite(mesh.face_deviation)) and np.all(mesh.face_deviation >= 0)
    assert mesh.max_deviation <= tol, f"reported max deviation {mesh.max_deviation} > {tol}"
    assert mesh.tol == tol
    r = naive.sample_mesh_deviation(mesh, case.surfaces, exact_above=tol)
    # the sampler looked at every face, or at the 30k + 2k subset
    assert r["faces"] >= min(m, 30_000)
    assert r["clean_fraction"] > 0.95, "too few faces usable for the parametric side"
    assert r["to_surface"] <= tol * REL, (
        f"{name} tol {tol}: a mesh point is {r['to_surface']:.6g} from the surface "
        f"(face, point) = {r['worst_to_surface']}")
    assert r["to_mesh"] <= tol * REL, (
        f"{name} tol {tol}: a surface point is {r['to_mesh']:.6g} from the mesh "
        f"(face, point) = {r['worst_to_mesh']}")


def test_sampler_detects_a_deviation():
    """The sampler is not a tautology: a mesh built for 1e-2 fails a 1e-3 check, and
    one vertex pushed off the sphere by 10 tol is seen from both sides, at its faces."""
    case, mesh = mesh_of("sphere", 1e-2)
    r = naive.sample_mesh_deviation(mesh, case.surfaces, n_faces=3000, n_worst=200,
                                    exact_above=1e-3)
    assert r["to_surface"] > 1e-3 and r["to_mesh"] > 1e-3
    tol = 1e-2
    V = mesh.vertices.copy()
    i = int(np.argmin(np.abs(mesh.uv - [0.3, 0.4]).sum(axis=1)))   # an ordinary vertex
    V[i] *= 1 + 10 * tol / np.linalg.norm(V[i])                     # radially out
    bumped = geomkit.types.Mesh(V, mesh.faces, mesh.uv, mesh.vertex_surface,
                                mesh.face_surface, mesh.face_deviation, tol, {})
    fan = np.nonzero((mesh.faces == i).any(axis=1))[0]
    r = naive.sample_mesh_deviation(bumped, case.surfaces, exact_above=tol)
    assert r["to_surface"] > 2 * tol and r["worst_to_surface"][0] in fan
    assert r["to_mesh"] > 1.5 * tol and r["worst_to_mesh"][0] in fan


# ======================================================================== 2. area
AREA = {"sphere": 1 / 10, "torus": 1 / 5, "cylinder_quarter": 1 / 10}   # kappa_max


def area_error_bound(name, tol):
    """The first-order bound of |A_mesh - A| for a mesh within ``tol`` of the surface."""
    case = case_of(name)
    A = case.truth["area"]
    if name == "plate_with_hole":
        # plane: 3-D = 100 x UV.  The outer loop is the domain rectangle (exact chords);
        # the hole (radius 0.2 in UV, 20 in 3-D) is replaced by chords deviating at most
        # tol from it: the area between them is at most tol * (hole length).
        return tol * 2 * math.pi * 20.0
    return 2 * tol * AREA[name] * A


@pytest.mark.parametrize("name", ["plate_with_hole", "sphere", "torus", "cylinder_quarter"])
def test_area_within_curvature_and_chord_bound(name):
    """Mesh area vs the analytic area.

    Bound (first order in delta, as stated in the issue): for a mesh whose vertices
    lie on the surface and which deviates at most delta from it,

        |A_mesh - A| <= 2 delta kappa_max A,

    kappa_max the largest principal curvature (sphere 1/10, torus 1/r = 1/5, cylinder
    1/10).  The mesh lies in the delta-shell around the surface, where moving along the
    normal scales areas by (1 +- delta k1)(1 +- delta k2) = 1 +- 2 delta kappa_max to
    first order.  (Sphere, exactly: the radial projection of an inscribed triangle,
    whose plane is at distance R - d from the centre, d <= delta, onto the sphere has
    Jacobian R^2 (R - d) / |x|^3 between (R - d) / R and R^2 / (R - d)^2, i.e. within
    1 +- 2 delta / R to first order.)

    For the planar trimmed plate the triangles are exact and only the trim is
    approximated: the boundary chords deviate at most delta from the trim curve, so the
    area between chords and curve is at most delta_uv * (trim length in UV) in UV, i.e.
    delta * (trim length in 3-D) in 3-D (3-D = 100 x UV): 2 pi 20 delta for the hole
    (the outer loop is the domain rectangle, whose chords are exact).

    delta = tol (the guarantee).  The error must also shrink from tol 1e-2 to 1e-3.
    """
    A = case_of(name).truth["area"]
    errs = {}
    for tol in (1e-2, 1e-3):
        _, mesh = mesh_of(name, tol)
        errs[tol] = abs(mesh.area - A)
        bound = area_error_bound(name, tol)
        assert errs[tol] <= bound, (f"{name} tol {tol}: |A_mesh - A| = {errs[tol]:.4g} "
                                    f"> bound {bound:.4g} (A = {A})")
    assert errs[1e-3] < 0.5 * errs[1e-2], f"area error does not shrink with tol: {errs}"


# ======================================================================== 3. clean meshes
CLEAN_CASES = [pytest.param(n, t, id=id_of(n, t)) for t in (1e-2, 1e-3) for n in NAMES]


def _sigma_min(surface, uv):
    """Smallest singular value of [S_u S_v] at uv (n, 2)."""
    D = surface.derivatives(uv, 1)
    Su, Sv = D[:, 1, 0], D[:, 0, 1]
    a = np.einsum("ij,ij->i", Su, Su)
    b = np.einsum("ij,ij->i", Su, Sv)
    c = np.einsum("ij,ij->i", Sv, Sv)
    lam = 0.5 * (a + c) - np.sqrt(0.25 * (a - c) ** 2 + b * b)
    return np.sqrt(np.maximum(lam, 0.0))


def per_surface(name, tol):
    """[(what, surface, faces F, corner UVs (seams/poles fixed), clean mask)]."""
    case, mesh = mesh_of(name, tol)
    out = []
    for i, s in enumerate(case.surfaces):
        F = surface_faces(mesh, i)
        UV, clean = naive.face_corner_uv(s, mesh.uv[F])
        out.append((f"{name}[{i}] tol {tol}", s, F, UV, clean))
    return mesh, out


@pytest.mark.parametrize("name, tol", CLEAN_CASES)
def test_manifold_and_consistently_oriented(name, tol):
    mesh, parts = per_surface(name, tol)
    nv = len(mesh.vertices)
    assert mesh.vertices.shape == (nv, 3) and mesh.uv.shape == (nv, 2)
    assert mesh.faces.min() >= 0 and mesh.faces.max() < nv
    assert np.all(np.isfinite(mesh.vertices))
    for what, s, F, UV, clean in parts:
        assert_manifold_oriented(F, what)
        # vertices lie on the surface at their UV
        vi = np.unique(F)
        gap = np.linalg.norm(s.evaluate(mesh.uv[vi]) - mesh.vertices[vi], axis=1).max()
        assert gap <= 1e-9 * s.size, f"{what}: vertex off S(uv) by {gap:.3g}"


@pytest.mark.parametrize("name, tol", CLEAN_CASES)
def test_boundary_edges_on_domain_edge_or_trim(name, tol):
    """A boundary edge (used by one face) lies on the domain edge (not on a closed seam
    or a pole, whose vertices must be welded) or, on a trimmed surface, within the
    chord band of a trim curve: chords deviate <= tol in 3-D, so <= tol / sigma_min in
    UV (sigma_min = smallest singular value of [S_u S_v]); ``classify_uv`` reports
    ON_BOUNDARY for sure within a quarter of its band, so the band is 4 tol / sigma_min."""
    _, parts = per_surface(name, tol)
    for what, s, F, UV, clean in parts:
        edges = naive.surface_edges(s)
        r = edge_report(F)
        bnd = np.nonzero(r["count"][r["edge_of"]] == 1)[0]
        if not len(bnd):
            continue
        fb, cb = bnd // 3, bnd % 3
        mid = 0.5 * (UV[fb, cb] + UV[fb, (cb + 1) % 3])
        (u0, u1), (v0, v1) = s.domain
        eps = 1e-9 * max(u1 - u0, v1 - v0)
        on = {"u0": np.abs(mid[:, 0] - u0) <= eps, "u1": np.abs(mid[:, 0] - u1) <= eps,
              "v0": np.abs(mid[:, 1] - v0) <= eps, "v1": np.abs(mid[:, 1] - v1) <= eps}
        welded = set(edges["poles"])
        welded |= {"u0", "u1"} if edges["closed_u"] else set()
        welded |= {"v0", "v1"} if edges["closed_v"] else set()
        for e in sorted(welded):
            assert not on[e].any(), (f"{what}: {int(on[e].sum())} boundary edges on the "
                                     f"closed seam / pole {e}")
        rest = ~(on["u0"] | on["u1"] | on["v0"] | on["v1"])
        if not rest.any():
            continue
        assert s.trim, (f"{what}: boundary edge off the domain edge on an untrimmed "
                        f"surface at uv {mid[rest][:3].tolist()}")
        band = 4 * tol / _sigma_min(s, mid[rest])
        cls = np.array([s.classify_uv(p, tol=float(w)) for p, w in zip(mid[rest], band)])
        off = cls != ON_BOUNDARY
        assert not off.any(), (f"{what}: {int(off.sum())} boundary edge midpoints neither "
                               f"on the domain edge nor on a trim, e.g. "
                               f"{mid[rest][off][:3].tolist()}")


@pytest.mark.parametrize("name, tol", CLEAN_CASES)
def test_no_near_zero_area_faces(name, tol):
    """Every face has area > 1e-12 size^2."""
    mesh, parts = per_surface(name, tol)
    for what, s, F, UV, clean in parts:
        area = face_areas(mesh.vertices, F)
        small = area <= 1e-12 * s.size ** 2
        j = int(np.argmin(area))
        assert not small.any(), (f"{what}: {int(small.sum())} faces with area <= "
                                 f"{1e-12 * s.size ** 2:.3g}, smallest {area[j]:.3g} at uv "
                                 f"{UV[j].tolist()}")


@pytest.mark.parametrize("name, tol", CLEAN_CASES)
def test_face_normals_agree_with_surface_normals(name, tol):
    """(V1 - V0) x (V2 - V0) . N(centroid UV) > 0 on every face away from poles."""
    mesh, parts = per_surface(name, tol)
    for what, s, F, UV, clean in parts:
        assert clean.mean() > 0.95
        T = mesh.vertices[F[clean]]
        n_face = np.cross(T[:, 1] - T[:, 0], T[:, 2] - T[:, 0])
        dots = np.einsum("ij,ij->i", n_face, s.normals(UV[clean].mean(axis=1)))
        k = int(np.argmin(dots))
        assert dots[k] > 0, (f"{what}: {int((dots <= 0).sum())} faces against the surface "
                             f"normal, e.g. face uv {UV[clean][k].tolist()}")


UNTRIMMED = [n for n in NAMES if not any(s.trim for s in samples.load(n))]


@pytest.mark.parametrize("tol", [1e-2, 1e-3])
def test_no_sliver_edges_on_untrimmed_surfaces(tol):
    """(Beyond the issue's list; pins down the cause of near-zero-area faces and flipped
    normals.)  On an untrimmed surface every vertex is a corner of a refinement cell, and
    an edge 100x shorter than tol never helps meet the chord tolerance; on the bundled
    cases the legitimate shortest edges are > 10 tol.  A shorter edge means a vertex
    placed next to another one (e.g. one lattice unit, span * 2**-24, off its lattice
    point), leaving a sliver triangle.  Checked on every untrimmed case; the message
    lists them all."""
    bad = []
    for name in UNTRIMMED:
        mesh, parts = per_surface(name, tol)
        for what, s, F, UV, clean in parts:
            T = mesh.vertices[F]
            L = np.linalg.norm(T - np.roll(T, 1, axis=1), axis=2).min(axis=1)
            short = L < 1e-2 * tol
            if short.any():
                j = int(np.argmin(L))
                bad.append(f"{what}: {int(short.sum())} faces, shortest edge {L[j]:.3g} in "
                           f"face uv {np.round(UV[j], 10).tolist()}")
    assert not bad, "faces with an edge shorter than tol/100:\n" + "\n".join(bad)


@pytest.mark.parametrize("name, chi, volume", [
    ("sphere", 2, 4 / 3 * math.pi * 10.0 ** 3),
    ("torus", 0, 2 * math.pi ** 2 * 20 * 5 ** 2)])
@pytest.mark.parametrize("tol", [1e-2, 1e-3])
def test_closed_surfaces_are_watertight(name, chi, volume, tol):
    """Watertight, Euler characteristic 2 (sphere) / 0 (torus), and the enclosed
    volume within the delta-shell bound |V_mesh - V| <= delta A (first order)."""
    case, mesh = mesh_of(name, tol)
    tm = mesh.to_trimesh()
    assert tm.is_watertight
    assert tm.is_winding_consistent
    assert euler_characteristic(mesh.faces) == chi
    assert boundary_loops(mesh.faces) == 0
    assert abs(abs(tm.volume) - volume) <= tol * case.truth["area"]


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


def plane(a, b, trim, frame=None):
    """A bilinear plane a x b (3-D = diag(a, b) x UV), optionally rotated by ``frame``."""
    P = np.array([[[0, 0, 0], [0, b, 0]], [[a, 0, 0], [a, b, 0]]], float)
    if frame is not None:
        P = P @ frame.T
    return Surface(1, 1, [0, 0, 1, 1], [0, 0, 1, 1], P, trim=trim)


def circle_dict(c, r):
    """An exact rational quadratic circle in UV, counter-clockwise, 4 quarters."""
    unit = np.array([[1, 0], [1, 1], [0, 1], [-1, 1], [-1, 0], [-1, -1], [0, -1], [1, -1],
                     [1, 0]], float)
    return {"degree": 2, "knots": [0, 0, 0, .25, .25, .5, .5, .75, .75, 1, 1, 1],
            "control_points": (np.asarray(c) + r * unit).tolist(),
            "weights": [1, S2, 1, S2, 1, S2, 1, S2, 1]}


def rotation(a, b, c):
    ca, sa, cb, sb, cc, sc = np.cos(a), np.sin(a), np.cos(b), np.sin(b), np.cos(c), np.sin(c)
    Rz = np.array([[ca, -sa, 0], [sa, ca, 0], [0, 0, 1]])
    Ry = np.array([[cb, 0, sb], [0, 1, 0], [-sb, 0, cb]])
    Rx = np.array([[1, 0, 0], [0, cc, -sc], [0, sc, cc]])
    return Rz @ Ry @ Rx


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


def regular_surface(s, relief=0.5):
    """A regular surface built from a random one: its degrees, knots and weights, its
    control points' z (scaled by ``relief``) over a regular 100 x 100 grid, x and y
    jittered by 3% of the random control points (less than the grid spacing, so each
    row and column of the net stays ordered and the surface is, in practice, a graph
    over the plane: no folds, collapsed rows or self-touching boundary)."""
    nu, nv = s.shape
    gu, gv = np.meshgrid(np.linspace(0, 100, nu), np.linspace(0, 100, nv), indexing="ij")
    P = np.stack([gu, gv, np.zeros_like(gu)], axis=-1)
    R = s.control_points
    P[..., 0] += 0.03 * R[..., 0]
    P[..., 1] += 0.03 * R[..., 1]
    P[..., 2] = relief * R[..., 2]
    return P


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


@pytest.mark.parametrize("tol", [1e-2, 1e-3])
def test_tiny_trim_loop_is_a_hole(tol):
    """A hole of radius 1e-4 in UV (0.01 in 3-D) in a 100 x 100 plane stays a hole."""
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
    with pytest.raises(InvalidInputError) as exc:
        tessellate(bad, 1e-2)
    assert exc.value.field == "surfaces"


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


# ======================================================================== 8. fast paths
def test_uniform_grid_and_adaptive_paths_both_hold_tol(monkeypatch):
    """A small untrimmed surface is meshed as one measured uniform grid; with the grid
    path switched off the adaptive path meshes it instead: both meshes pass the
    independent sampler and have comparable sizes."""
    import importlib

    T = importlib.import_module("geomkit.tessellate")  # the module, not the function
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
    from geomkit import _quadtree as qt

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
    from geomkit import _quadtree as qt

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

    _Measured = importlib.import_module("geomkit.tessellate")._Measured
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
    from geomkit._kernels.tess import closest_on_triangle

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
