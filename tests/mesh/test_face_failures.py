"""One face never sinks a model: a face whose triangulation fails is left out of the
mesh with a warning and a stats entry naming it, the other faces are meshed exactly as
alone; a single surface that fails raises MeshingError (a GeomkitError) naming the
cause; and a cut cell that GEOS cannot triangulate in the batch is triangulated alone
(the result still measured within the tolerance)."""

from __future__ import annotations

import importlib
import warnings

import numpy as np
import pytest
import shapely

import geomkit
from geomkit import samples
from geomkit.errors import FaceFailedWarning, GeomkitError, MeshingError

T = importlib.import_module("geomkit.mesh.tessellate")


def _failing_on(monkeypatch, bad_names):
    real = T._tessellate_one

    def one(s, *a, **k):
        if s.name in bad_names:
            raise shapely.errors.GEOSException(
                "IllegalStateException: Unable to find a convex corner")
        return real(s, *a, **k)
    monkeypatch.setattr(T, "_tessellate_one", one)


def _named(s, name):
    return geomkit.Surface(s.degree_u, s.degree_v, s.knots_u, s.knots_v, s.control_points,
                           s.weights, list(s.trim) or None, name=name)


def test_a_failing_face_is_left_out_and_named(monkeypatch):
    parts = [_named(samples.load("sphere")[0], "a"),
             _named(samples.load("plate_with_hole")[0], "b"),
             _named(samples.load("torus")[0], "c")]
    alone = [geomkit.tessellate(s, 1e-2) for s in (parts[0], parts[2])]
    _failing_on(monkeypatch, {"b"})
    with pytest.warns(FaceFailedWarning, match=r"surface 1 \(b\).*convex corner"):
        m = geomkit.tessellate(parts, 1e-2)
    assert set(np.unique(m.face_surface)) == {0, 2}
    assert "failed" in m.stats["surfaces"][1] and "convex corner" in m.stats["surfaces"][1]["failed"]
    assert len(m.faces) == sum(len(a.faces) for a in alone)
    assert m.max_deviation <= 1e-2


def test_every_face_failing_raises_one_error(monkeypatch):
    parts = [_named(samples.load("sphere")[0], "a"), _named(samples.load("torus")[0], "b")]
    _failing_on(monkeypatch, {"a", "b"})
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", FaceFailedWarning)
        with pytest.raises(MeshingError, match="no surface could be triangulated"):
            geomkit.tessellate(parts, 1e-2)


def test_a_single_failing_surface_raises_a_geomkit_error(monkeypatch):
    s = _named(samples.load("sphere")[0], "a")
    _failing_on(monkeypatch, {"a"})
    with pytest.raises(MeshingError, match="GEOSException.*convex corner") as e:
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
