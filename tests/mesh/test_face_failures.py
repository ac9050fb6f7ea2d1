"""One face never sinks a model: a face whose triangulation fails is meshed by the
fallback route (the untrimmed surface's cells kept inside its trim loops, every
triangle measured within the tolerance), with a warning and a stats entry naming it;
a face the fallback cannot mesh either is left out, named the same way, the other
faces meshed exactly as alone; a single surface that fails both ways raises
MeshingError (a GeomkitError) naming both causes; and a cut cell that GEOS cannot
triangulate in the batch is triangulated alone (the result still measured within the
tolerance)."""

from __future__ import annotations

import importlib
import warnings

import numpy as np
import pytest
import shapely

import geomkit
from geomkit import samples
from geomkit.errors import FaceFailedWarning, GeomkitError, MeshingError
from helpers.paths import DATA

T = importlib.import_module("geomkit.mesh.tessellate")


def _failing_on(monkeypatch, bad_names, fallback_too=True):
    """Faces named ``bad_names`` raise as GEOS does on the primary route, and on the
    fallback route too unless ``fallback_too`` is False."""
    real = T._tessellate_one

    def one(s, *a, fallback=None, **k):
        if s.name in bad_names and (fallback is None or fallback_too):
            raise shapely.errors.GEOSException(
                "IllegalStateException: Unable to find a convex corner")
        return real(s, *a, fallback=fallback, **k)
    monkeypatch.setattr(T, "_tessellate_one", one)


def _named(s, name):
    return geomkit.Surface(s.degree_u, s.degree_v, s.knots_u, s.knots_v, s.control_points,
                           s.weights, list(s.trim) or None, name=name)


def test_a_face_failing_both_routes_is_left_out_and_named(monkeypatch):
    parts = [_named(samples.load("sphere")[0], "a"),
             _named(samples.load("plate_with_hole")[0], "b"),
             _named(samples.load("torus")[0], "c")]
    alone = [geomkit.tessellate(s, 1e-2) for s in (parts[0], parts[2])]
    _failing_on(monkeypatch, {"b"})
    with pytest.warns(FaceFailedWarning, match=r"surface 1 \(b\).*convex corner"):
        m = geomkit.tessellate(parts, 1e-2)
    assert set(np.unique(m.face_surface)) == {0, 2}
    why = m.stats["surfaces"][1]["failed"]
    assert "convex corner" in why and "the fallback failed too" in why
    assert len(m.faces) == sum(len(a.faces) for a in alone)
    assert m.max_deviation <= 1e-2


def test_every_face_failing_raises_one_error(monkeypatch):
    parts = [_named(samples.load("sphere")[0], "a"), _named(samples.load("torus")[0], "b")]
    _failing_on(monkeypatch, {"a", "b"})
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", FaceFailedWarning)
        with pytest.raises(MeshingError, match="no surface could be triangulated"):
            geomkit.tessellate(parts, 1e-2)


def test_a_single_surface_failing_both_routes_raises_a_geomkit_error(monkeypatch):
    s = _named(samples.load("sphere")[0], "a")
    _failing_on(monkeypatch, {"a"})
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # no warning: the error says it all
        with pytest.raises(MeshingError, match="GEOSException.*convex corner.*fallback "
                           "failed too") as e:
            geomkit.tessellate(s, 1e-2)
    assert isinstance(e.value, GeomkitError)


def test_cut_cells_fall_back_to_one_piece_at_a_time(monkeypatch):
    """GEOS refuses the batch (as on nearly collinear trim points): each piece is then
    triangulated alone; the mesh is the same region and holds the tolerance."""
    b = samples.load("sphere")[0]      # a curved face trimmed by a circle: cut cells
    (u0, u1), (v0, v1) = b.domain
    a = np.linspace(0.0, 2 * np.pi, 65)
    loop = np.c_[(u0 + u1) / 2 + 0.3 * (u1 - u0) * np.cos(a),
                 (v0 + v1) / 2 + 0.3 * (v1 - v0) * np.sin(a)]
    loop[-1] = loop[0]
    s = geomkit.Surface(b.degree_u, b.degree_v, b.knots_u, b.knots_v, b.control_points,
                        b.weights, [loop])
    ref = geomkit.tessellate(s, 1e-3)
    real = shapely.constrained_delaunay_triangles
    calls = {"batch": 0}

    def cdt(g):
        if isinstance(g, np.ndarray) and g.size > 1:
            calls["batch"] += 1
            raise shapely.errors.GEOSException("IllegalStateException: Unable to find a "
                                               "convex corner")
        return real(g)
    monkeypatch.setattr(shapely, "constrained_delaunay_triangles", cdt)
    m = geomkit.tessellate(s, 1e-3)
    assert calls["batch"] > 0
    assert m.max_deviation <= 1e-3
    assert abs(m.area - ref.area) <= 1e-9 * ref.area


# ------------------------------------------------------------------ the fallback route
F = importlib.import_module("geomkit.mesh.fallback")
CTC01 = DATA / "parts" / "nist_ctc_01_ap203.stp"
FACES = (14, 19, 24)  # a plane with two holes, a trimmed cylinder, a plane with slots


@pytest.fixture(scope="module")
def ctc01():
    from geomkit.cad.step import read_step

    S = read_step(CTC01, reader="geomkit").surfaces
    B = np.array([s.bounds for s in S])
    size = float(np.linalg.norm(B[:, 1].max(axis=0) - B[:, 0].min(axis=0)))
    return S, 1e-3 * size


def _face(m, j):
    """Surface j's triangles of mesh m: ``(area, outline length, face_uv)`` (the outline:
    edges used by one triangle only)."""
    F = m.faces[m.face_surface == j]
    V = m.vertices
    area = 0.5 * np.linalg.norm(np.cross(V[F[:, 1]] - V[F[:, 0]], V[F[:, 2]] - V[F[:, 0]]),
                                axis=1).sum()
    e = np.sort(np.concatenate([F[:, [0, 1]], F[:, [1, 2]], F[:, [2, 0]]]), axis=1)
    u, c = np.unique(e, axis=0, return_counts=True)
    b = u[c == 1]
    outline = np.linalg.norm(V[b[:, 0]] - V[b[:, 1]], axis=1).sum()
    return float(area), float(outline), m.face_uv[m.face_surface == j]


def test_a_failing_real_face_is_meshed_by_the_fallback(ctc01, monkeypatch):
    """NIST CTC-01 (AP203): three trimmed faces (planes with holes and slots, a
    trimmed cylinder) whose primary route raises come out of the fallback: present,
    every triangle within tol, named in a warning and the stats, covering the face's
    region (the primary mesh's UV centroids lie in the fallback's UV triangles) and
    overhanging it by at most the stated overhang along its outline."""
    S, tol = ctc01
    parts = [_named(S[i], f"f{i}") for i in FACES] + [_named(S[5], "ok")]
    ref = geomkit.tessellate(parts, tol)
    _failing_on(monkeypatch, {f"f{i}" for i in FACES}, fallback_too=False)
    with pytest.warns(FaceFailedWarning, match=r"surface 0 \(f14\) meshed by the fallback "
                      r"route.*convex corner"):
        m = geomkit.tessellate(parts, tol)
    assert set(np.unique(m.face_surface)) == {0, 1, 2, 3}
    assert m.max_deviation <= tol and (m.face_deviation <= tol).all()
    for j, i in enumerate(FACES):
        st = m.stats["surfaces"][j]
        assert "convex corner" in st["fallback"] and "failed" not in st
        assert 0 < st["fallback_overhang"] <= T.TRIM_TARGET * tol
        (a, outline, auv), (b, _, buv) = _face(ref, j), _face(m, j)
        assert a * (1 - 1e-9) <= b <= a + outline * st["fallback_overhang"], (i, a, b)
        # coverage in UV: the primary triangles' centroids are in the fallback's
        cover = shapely.union_all(shapely.polygons(buv))
        c = auv.mean(axis=1)
        assert shapely.contains_xy(cover, c[:, 0], c[:, 1]).all(), i
    # the face that did not fail is meshed as before
    np.testing.assert_array_equal(m.face_uv[m.face_surface == 3],
                                  ref.face_uv[ref.face_surface == 3])


def test_a_single_surface_takes_the_fallback(ctc01, monkeypatch):
    S, tol = ctc01
    s = _named(S[19], "cyl")
    _failing_on(monkeypatch, {"cyl"}, fallback_too=False)
    with pytest.warns(FaceFailedWarning, match=r"surface 0 \(cyl\) meshed by the fallback"):
        m = geomkit.tessellate(s, tol)
    assert len(m.faces) and m.max_deviation <= tol
    assert "convex corner" in m.stats["surfaces"][0]["fallback"]


def test_a_trim_that_cannot_be_built_is_stated(ctc01, monkeypatch):
    """The fallback needs the trim loops: when even they fail, the face is left out
    and the stats say the trim could not be built."""
    S, tol = ctc01
    parts = [_named(S[14], "plate"), _named(S[5], "ok")]
    _failing_on(monkeypatch, {"plate"}, fallback_too=False)

    def broken(*a, **k):
        raise FloatingPointError("injected: no polyline")
    monkeypatch.setattr(F, "TrimPolylines", broken)
    with pytest.warns(FaceFailedWarning, match=r"surface 0 \(plate\) left out.*trim loops "
                      r"could not be built.*injected"):
        m = geomkit.tessellate(parts, tol)
    assert set(np.unique(m.face_surface)) == {1}
    assert "trim loops could not be built" in m.stats["surfaces"][0]["failed"]


@pytest.mark.parametrize("face", [3, 19, 24])
def test_staircase_classes_match_the_region(ctc01, face):
    """The fallback's GEOS-free cell classes against shapely's region: a cell is
    crossed (2) exactly when its rectangle meets the region's boundary, else in (1) or
    out (0) as its centre is."""
    from geomkit.mesh.trim_polylines import TrimPolylines

    S, tol = ctc01
    s = S[face]
    trim = TrimPolylines(s, 0.5 * tol)
    stair = F.Staircase(trim.loops, trim.domain_loop)
    (u0, u1), (v0, v1) = s.domain
    rng = np.random.default_rng(face)
    lo = rng.random((4000, 2)) * [u1 - u0, v1 - v0] + [u0, v0]
    w = rng.random((4000, 2)) ** 3 * 0.2 * [u1 - u0, v1 - v0]
    uv = np.c_[lo[:, 0], lo[:, 0] + w[:, 0], lo[:, 1], lo[:, 1] + w[:, 1]]
    got = np.where(stair.crossed(uv), 2, 0)
    rest = got == 0
    P = np.c_[uv[rest, :2].mean(axis=1), uv[rest, 2:].mean(axis=1)]
    got[rest] = stair.inside(P)
    region = trim.region
    boxes = shapely.box(uv[:, 0], uv[:, 2], uv[:, 1], uv[:, 3])
    want = np.where(shapely.intersects(boxes, region.boundary), 2,
                    shapely.contains_xy(region, uv[:, :2].mean(axis=1),
                                        uv[:, 2:].mean(axis=1)).astype(int))
    assert (got == want).all(), np.nonzero(got != want)[0][:5]
    assert (want == 1).any() and (want == 2).any() and (want == 0).any()
