"""A plane through a cone's apex: the tracer finds hundreds of pieces that are all
the apex; they are one point, kept once, before the ends are joined (NIST CTC-01
AP242 at z = -25 took 326 s in the pairwise join, one face 21 s)."""

import warnings

import numpy as np

import geomkit
from geomkit.section.joins import merge_point_curves
from helpers.paths import DATA


def _curve(X, closed=False):
    X = np.asarray(X, float)
    return {"X": X, "uv": np.zeros((len(X), 2)), "sid": np.zeros(len(X), int),
            "closed": closed, "chord": 0.0}


def test_point_pieces_kept_once_per_spot():
    rng = np.random.default_rng(0)
    apex = np.array([1.0, 2.0, 3.0])
    pts = [_curve(apex + 1e-9 * rng.normal(size=(2, 3))) for _ in range(300)]
    other = [_curve(np.array([5.0, 5.0, 5.0]) + 1e-9 * rng.normal(size=(2, 3)))
             for _ in range(3)]
    line = _curve(np.linspace(apex, apex + [10.0, 0, 0], 50))
    ring = _curve([apex, apex, apex], closed=True)   # closed: never merged
    curves = [line] + pts[:150] + other + pts[150:] + [ring]
    out = merge_point_curves(curves, 1e-6)
    assert out[0] is line and out[-1] is ring
    assert out[1] is pts[0] and out[2] is other[0]
    assert len(out) == 4
    # nothing to merge: the same list
    assert merge_point_curves([line, ring], 1e-6) == [line, ring]


def test_section_through_a_cone_apex_on_a_real_part():
    from geomkit.cad.step import read_step

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        case = read_step(DATA / "parts" / "nist_ctc_01_ap242.stp", cache=False)
    s = case.surfaces[56]
    apex = s.control_points[0, 0]
    assert np.ptp(s.control_points[0], axis=0).max() == 0 and apex[2] == -25.0
    tol = 1e-4 * 800
    sec = geomkit.plane_section([s], [0, 0, 1, 25.0], tol=tol, gap=case.edge_gap)
    assert len(sec.curves) == 1
    X = np.asarray(sec.curves[0])
    assert np.abs(X[:, 2] + 25.0).max() <= tol
    assert geomkit.project_points(s, X).distance.max() <= 1e-6 * s.size
    assert np.linalg.norm(X - apex, axis=1).min() <= tol
    assert np.linalg.norm(X.max(axis=0) - X.min(axis=0)) > 10.0
