"""A Surface pickles as one buffer and comes back equal bit for bit, read-only, and
answering as the original (the read cache and Dask workers rely on it)."""

import pickle
from pathlib import Path

import numpy as np
import pytest

import geomkit
from geomkit.nurbs.surface import Surface, TrimCurve

DATA = Path(__file__).resolve().parents[1] / "data"


def _same(a, b):
    assert a.dtype == b.dtype and a.shape == b.shape
    assert np.array_equal(a, b)
    assert not b.flags.writeable and b.flags.c_contiguous


def _check(s):
    t = pickle.loads(pickle.dumps(s, protocol=pickle.HIGHEST_PROTOCOL))
    assert type(t) is Surface
    assert (t.degree_u, t.degree_v, t.name, t.approx_error) == \
        (s.degree_u, s.degree_v, s.name, s.approx_error)
    for k in ("knots_u", "knots_v", "control_points", "_Pw"):
        _same(getattr(s, k), getattr(t, k))
    assert (s.weights is None) == (t.weights is None)
    if s.weights is not None:
        _same(s.weights, t.weights)
    assert len(t.trim) == len(s.trim)
    for la, lb in zip(s.trim, t.trim):
        assert len(la.pieces) == len(lb.pieces)
        for a, b in zip(la.pieces, lb.pieces):
            assert isinstance(b, TrimCurve) and a.degree == b.degree
            for k in ("knots", "control_points", "weights"):
                _same(getattr(a, k), getattr(b, k))
    return t


def test_trimmed_rational_part_faces_round_trip():
    from geomkit.cad.step import read_step

    case = read_step(DATA / "parts" / "nist_ctc_01_ap203.stp", cache=False)
    kinds = {(s.weights is not None, bool(s.trim)) for s in case.surfaces}
    assert (True, True) in kinds and (False, True) in kinds
    rng = np.random.default_rng(0)
    for s in case.surfaces[:40]:
        t = _check(s)
        (u0, u1), (v0, v1) = s.domain
        uv = np.column_stack([rng.uniform(u0, u1, 50), rng.uniform(v0, v1, 50)])
        assert np.array_equal(s.evaluate(uv), t.evaluate(uv))
        if s.trim:
            assert np.array_equal(s.classify_uv(uv), t.classify_uv(uv))


def test_untrimmed_and_approximate_surface_round_trip():
    P = np.zeros((3, 4, 3))
    P[..., 0], P[..., 1] = np.meshgrid(np.arange(3.0), np.arange(4.0), indexing="ij")
    P[..., 2] = np.arange(12.0).reshape(3, 4) ** 0.5
    s = Surface(2, 3, [0, 0, 0, 1, 1, 1], [0, 0, 0, 0, 1, 1, 1, 1], P, name="bump",
                approx_error=1e-7)
    s.evaluate([[0.5, 0.5]])
    t = _check(s)
    assert t.trim == () and t.weights is None
    assert t._cache == {}
    with pytest.raises(ValueError):
        t.control_points[0, 0, 0] = 1.0


@pytest.mark.parametrize("name", sorted(p.name for p in (DATA / "cases").glob("*.json")))
def test_case_surfaces_round_trip(name):
    for s in geomkit.load(DATA / "cases" / name):
        _check(s)
