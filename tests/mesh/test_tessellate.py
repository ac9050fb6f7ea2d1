"""Tests of geomkit.tessellate: the chord tolerance holds, measured independently.

What is checked, and against what:

1. **Deviation** — an independent sampler (``tests/helpers/naive.py``,
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

Meshes of the bundled cases are built once per (case, tol) and shared between tests
(``tests/helpers/tesshelp.py``, with the mesh helpers).  This file holds sections 1-3;
section 4 is ``test_tessellate_trims.py``, sections 5-8 ``test_tessellate_cases.py``.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

import geomkit
from geomkit import ON_BOUNDARY, samples

from helpers import naive
from helpers.tesshelp import (FAST_1E4, NAMES, REL, assert_manifold_oriented, boundary_loops,
                              case_of, edge_report, euler_characteristic, face_areas, id_of,
                              mesh_of, surface_faces)


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
    bumped = geomkit.mesh.mesh.Mesh(V, mesh.faces, mesh.uv, mesh.vertex_surface,
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
