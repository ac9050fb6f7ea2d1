"""PartProjector: faces in blocks built where the queries look, answers equal to one
Projector over every face; a face that fails never sinks a query of the model."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import geomkit
from geomkit import samples
from geomkit.cad.occ import HAVE_OCP
from geomkit.errors import FaceFailedWarning
from geomkit.mesh import tessellate as tess_mod
from geomkit.query import projection_part as pp_mod
from geomkit.query.projection import Projector
from geomkit.query.projection_part import (PartProjector, face_anchors, face_box,
                                           make_projector)
from geomkit.query.results import BEYOND
from helpers.paths import DATA


def _scene():
    """40 faces: the samples translated over a 4 x 10 grid (trimmed, rational, poles,
    creases, touching pairs)."""
    base = [s for name in ("sphere", "torus", "plate_with_hole", "crease", "saddle",
                           "heavy_weights", "cylinder_quarter", "freeform_1",
                           "sphere_plane_cut", "sphere_pair")
            for s in samples.load(name)]
    out = []
    for k in range(40):
        s = base[k % len(base)]
        d = s.to_dict()
        shift = np.array([(k % 4) * 30.0, (k // 4) * 30.0, 0.0])
        d["control_points"] = (np.asarray(d["control_points"]) + shift).tolist()
        out.append(geomkit.Surface.from_dict(d) if hasattr(geomkit.Surface, "from_dict")
                   else geomkit.Surface(**_kw(d)))
    return out


def _kw(d):
    return {k: d[k] for k in ("degree_u", "degree_v", "knots_u", "knots_v",
                              "control_points", "weights", "trim") if k in d}


@pytest.fixture(scope="module")
def scene():
    S = _scene()
    return S, Projector(S), PartProjector(S, block_faces=6)


def _points(S, n, spread, seed):
    rng = np.random.default_rng(seed)
    lo = np.min([face_box(s)[0] for s in S], axis=0)
    hi = np.max([face_box(s)[1] for s in S], axis=0)
    return lo + rng.uniform(size=(n, 3)) * (hi - lo) + rng.normal(size=(n, 3)) * spread


def test_boxes_hold_the_faces_and_anchors_lie_on_them():
    for s in _scene()[:10]:
        lo, hi = face_box(s)
        m = geomkit.tessellate(s, 1e-3 * s.size)
        assert (m.vertices >= lo - 1e-9).all() and (m.vertices <= hi + 1e-9).all()
        A = face_anchors(s)
        assert A.shape[0] >= 4
        pr = geomkit.project_points(s, A)
        assert np.nanmax(pr.distance) <= 1e-9 * s.size


def test_boxes_and_anchors_of_a_real_part():
    """Every face of a NIST part (planes, cylinders, cones, tori, B-splines, trims of
    many pieces): its box (from the trim pieces' control points) holds its mesh, its
    anchors lie on it."""
    from geomkit.cad.step import read_step

    case = read_step(DATA / "parts" / "nist_ctc_01_ap203.stp", cache=False)
    mesh = geomkit.tessellate(case.surfaces, 1e-3 * max(s.size for s in case.surfaces))
    for k, s in enumerate(case.surfaces):
        lo, hi = face_box(s)
        V = mesh.vertices[np.unique(mesh.faces[mesh.face_surface == k])]
        e = 1e-9 * s.size
        assert (V >= lo - e).all() and (V <= hi + e).all(), k
        A = face_anchors(s)
        assert A.shape[0] >= 2, k
        d = geomkit.project_points(s, A).distance
        assert np.nanmax(d) <= 1e-9 * s.size + s.approx_error, k


def test_same_answers_as_one_projector(scene):
    S, full, part = scene
    P = _points(S, 3000, 5.0, 0)
    a, b = full.project(P), part.project(P)
    size = full.size
    np.testing.assert_allclose(b.distance, a.distance, rtol=0, atol=1e-12 * size)
    assert (a.status == b.status).all()
    # feet on an edge shared by two faces are ties: the same distance either way
    assert (a.surface == b.surface).mean() > 0.99
    assert (b.lower_bound <= b.distance + 1e-12 * size).all()
    assert b.stats["blocks"] == len(part.blocks) > 4


def test_max_distance_and_far_points(scene):
    S, full, part = scene
    P = _points(S, 500, 40.0, 1)
    for md in (None, 2.0, 0.0):
        a, b = full.project(P, md), part.project(P, md)
        assert (a.status == b.status).all()
        ok = a.status != BEYOND
        np.testing.assert_allclose(b.distance[ok], a.distance[ok], rtol=0,
                                   atol=1e-12 * full.size)
        assert np.isnan(b.distance[~ok]).all()


def test_blocks_are_built_where_the_queries_look():
    S = _scene()
    part = PartProjector(S, block_faces=4)
    assert all(p is None for p in part.built)
    s = S[0]
    X = s.evaluate(np.array([[np.mean(s.domain[0]), np.mean(s.domain[1])]]))
    out = part.project(X + 0.01)
    assert out.stats["blocks_built"] < len(part.blocks) / 2
    assert out.surface[0] == 0 or np.isclose(out.distance[0], np.sqrt(3) * 0.01, atol=0.02)


def test_make_projector_by_face_count(monkeypatch):
    S = _scene()
    assert isinstance(make_projector(S), Projector)
    monkeypatch.setattr(pp_mod, "PART_FACES", 10)
    assert isinstance(make_projector(S), PartProjector)


@pytest.fixture
def one_face_fails(monkeypatch):
    """Tessellation and sectioning of surface 5 of the scene raise, as a GEOS or
    numerical failure would."""
    S = _scene()
    bad = S[5]
    real_tess = tess_mod._tessellate_one

    def tess(s, *a, **k):
        if s is bad:
            raise ValueError("injected failure")
        return real_tess(s, *a, **k)

    from geomkit.section import plane as plane_mod
    real_trace = plane_mod.trace_surface

    def trace(s, *a, **k):
        if s is bad:
            raise FloatingPointError("injected failure")
        return real_trace(s, *a, **k)

    monkeypatch.setattr(tess_mod, "_tessellate_one", tess)
    monkeypatch.setattr(plane_mod, "trace_surface", trace)
    return S


@pytest.mark.parametrize("kind", ["projector", "part"])
def test_a_failed_face_is_named_not_raised(one_face_fails, kind):
    S = one_face_fails
    P = _points(S, 300, 2.0, 3)
    with pytest.warns(FaceFailedWarning, match="injected failure"):
        pr = Projector(S) if kind == "projector" else PartProjector(S, block_faces=6)
        out = pr.project(P)
    assert set(out.stats["faces_failed"]) == {5}
    assert (out.surface != 5).all() and np.isfinite(out.distance).all()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", FaceFailedWarning)
        good = Projector([s for i, s in enumerate(S) if i != 5]).project(P)
    np.testing.assert_allclose(out.distance, good.distance, rtol=0, atol=1e-12 * pr.size)


def test_a_failed_face_does_not_sink_tessellate_section_or_deviation(one_face_fails):
    S = one_face_fails
    with pytest.warns(FaceFailedWarning):
        m = geomkit.tessellate(S, 0.05)
    assert "failed" in m.stats["surfaces"][5] and 5 not in set(m.face_surface.tolist())
    with pytest.warns(FaceFailedWarning, match="left out of the section"):
        sec = geomkit.plane_section(S, [0, 0, 1, -1.0], 1e-4)
    assert set(sec.failed) == {5} and len(sec.curves) > 0
    P = _points(S, 200, 1.0, 4)
    with pytest.warns(FaceFailedWarning):
        rep = geomkit.deviation(S, P)
    assert set(rep.stats["faces_failed"]) == {5}


@pytest.mark.occ
@pytest.mark.skipif(not HAVE_OCP, reason="reading STEP needs cadquery-ocp")
def test_real_part_blocks_equal_one_projector():
    """NIST CTC-01 (139 faces), blocks of 16: distances equal to one projector's."""
    S = geomkit.load_case(DATA / "parts" / "nist_ctc_01_ap203.stp").surfaces
    full, part = Projector(S), PartProjector(S, block_faces=16)
    V = full.mesh.vertices
    rng = np.random.default_rng(5)
    size = full.size
    P = V[rng.choice(len(V), 1500)] + rng.normal(size=(1500, 3)) * 0.02 * size
    a, b = full.project(P), part.project(P)
    np.testing.assert_allclose(b.distance, a.distance, rtol=0, atol=1e-12 * size)
    assert (a.status == b.status).all()
    assert (b.lower_bound <= b.distance + 1e-12 * size).all()
