"""Surface / trim validation: every bad field raises a clear, field-naming geomkit error,
and the valid edge cases (unclamped knots, unit weights, numpy polylines, chained NURBS
trim pieces) are accepted and behave like their canonical forms.

Unclamped knot vectors are checked against a brute-force Cox–de Boor evaluation written
here (no geomdl), straight from the definition of the B-spline basis.
"""

from __future__ import annotations

import numpy as np
import pytest

import geomkit
from geomkit import (GeomkitError, InvalidSurfaceError, InvalidTrimError, Surface,
                     TrimCurve, TrimLoop, classify_uv, INSIDE, OUTSIDE)
from geomkit.nurbs.trimming import evaluate_trim_curve

from helpers.trims import S2, circle_dict, circle_quarters, unit_plate

# --------------------------------------------------------------------------- helpers
RNG = np.random.default_rng(20240611)
NU, NV = 4, 3
P0 = np.stack(np.meshgrid(np.arange(NU, dtype=float), np.arange(NV, dtype=float),
                          indexing="ij"), axis=-1)
P0 = np.concatenate([P0, RNG.normal(size=(NU, NV, 1))], axis=-1)  # (4, 3, 3)
W0 = RNG.uniform(0.5, 2.0, size=(NU, NV))
KU = [0, 0, 0, 0.5, 1, 1, 1]  # 4 control points, degree 2
KV = [0, 0, 0, 1, 1, 1]  # 3 control points, degree 2


def base(**over):
    args = dict(degree_u=2, degree_v=2, knots_u=KU, knots_v=KV, control_points=P0,
                weights=W0)
    args.update(over)
    return args


def with_value(arr, index, value):
    a = np.array(arr, dtype=float)
    a[index] = value
    return a


def expect(exc_cls, field, phrases, fn, *a, **kw):
    with pytest.raises(exc_cls) as info:
        fn(*a, **kw)
    e = info.value
    assert type(e) is exc_cls, f"raised {type(e).__name__}, expected exactly {exc_cls.__name__}"
    assert isinstance(e, GeomkitError) and isinstance(e, ValueError)
    assert e.field == field, f"field {e.field!r} != {field!r} ({e})"
    msg = str(e)
    assert msg.startswith(f"{field}: "), msg
    for ph in ([phrases] if isinstance(phrases, str) else phrases):
        assert ph in msg, f"{ph!r} not in message {msg!r}"
    return e


# ------------------------------------------------------------ invalid surface fields
P6 = np.concatenate([P0, P0[:2] + 10.0])  # 6 rows
P2 = P0[:2]  # 2 rows

SURFACE_CASES = {
    # knot vector length: message states the rule and the numbers
    "knots_u_too_short": (dict(knots_u=[0, 0, 0, 1, 1, 1]), "knots_u",
                          ["length 6", "n + p + 1", "4 + 2 + 1 = 7"]),
    "knots_u_too_long": (dict(knots_u=[0, 0, 0, 0.3, 0.6, 1, 1, 1]), "knots_u",
                         ["length 8", "n + p + 1", "= 7"]),
    "knots_v_wrong_length": (dict(knots_v=[0, 0, 0, 0.5, 1, 1, 1]), "knots_v",
                             ["length 7", "n + p + 1", "3 + 2 + 1 = 6"]),
    "knots_u_decreasing": (dict(knots_u=[0, 0, 0.6, 0.5, 1, 1, 1]), "knots_u",
                           ["non-decreasing", "knot[3]", "knot[2]"]),
    "knots_v_decreasing": (dict(knots_v=[0, 0, 1, 0.9, 1, 1]), "knots_v", "non-decreasing"),
    "knots_u_interior_multiplicity": (
        dict(knots_u=[0, 0, 0, 0.5, 0.5, 0.5, 1, 1, 1], control_points=P6,
             weights=np.ones((6, NV))),
        "knots_u", ["interior knot", "multiplicity 3 > degree 2"]),
    "knots_u_empty_domain": (dict(knots_u=[0.0] * 7), "knots_u", "empty parameter domain"),
    "knots_v_empty_domain": (dict(knots_v=[2.0] * 6), "knots_v", "empty parameter domain"),
    "knots_u_collapsed_domain": (dict(knots_u=[0, 0, 1, 1, 1, 2, 2]), "knots_u",
                                 "empty parameter domain"),
    "degree_u_zero": (dict(degree_u=0, knots_u=[0, 0, 0.5, 1, 1]), "degree_u", "must be >= 1"),
    "degree_v_zero": (dict(degree_v=0), "degree_v", "must be >= 1"),
    "degree_u_negative": (dict(degree_u=-1), "degree_u", "must be >= 1"),
    "degree_u_fraction": (dict(degree_u=1.5), "degree_u", "expected an integer"),
    "degree_v_string": (dict(degree_v="2"), "degree_v", "expected an integer"),
    "degree_u_bool": (dict(degree_u=True), "degree_u", "expected an integer"),
    "degree_u_none": (dict(degree_u=None), "degree_u", "expected an integer"),
    "degree_u_nan": (dict(degree_u=float("nan")), "degree_u", "expected an integer"),
    "cp_2d_coords": (dict(control_points=P0[..., :2]), "control_points",
                     ["expected shape (n, n, 3)", "(4, 3, 2)"]),
    "cp_flat": (dict(control_points=P0.reshape(-1, 3)), "control_points",
                "expected shape (n, n, 3)"),
    "cp_4d_array": (dict(control_points=P0[..., None]), "control_points",
                    "expected shape (n, n, 3)"),
    "cp_ragged": (dict(control_points=[[[0, 0, 0], [0, 1, 0]], [[1, 0, 0], [1, 1]]]),
                  "control_points", "expected numbers"),
    "cp_text": (dict(control_points="abc"), "control_points", "expected numbers"),
    "cp_too_few_rows": (dict(control_points=P2, knots_u=[0, 0, 0, 1, 1], weights=None),
                        "control_points", ["2 rows", "degree_u 2", "at least 3"]),
    "cp_too_few_cols": (dict(degree_v=3, knots_v=[0, 0, 0, 0, 1, 1, 1]), "control_points",
                        ["3 columns", "degree_v 3", "at least 4"]),
    "cp_nan": (dict(control_points=with_value(P0, (1, 2, 0), np.nan)), "control_points",
               ["non-finite", "nan", "(1, 2, 0)"]),
    "cp_inf": (dict(control_points=with_value(P0, (3, 0, 2), np.inf)), "control_points",
               ["non-finite", "inf", "(3, 0, 2)"]),
    "cp_neg_inf": (dict(control_points=with_value(P0, (0, 0, 1), -np.inf)), "control_points",
                   "non-finite"),
    "knots_u_nan": (dict(knots_u=with_value(KU, 3, np.nan)), "knots_u",
                    ["non-finite", "nan", "(3,)"]),
    "knots_v_inf": (dict(knots_v=with_value(KV, 5, np.inf)), "knots_v", ["non-finite", "inf"]),
    "weights_nan": (dict(weights=with_value(W0, (2, 1), np.nan)), "weights",
                    ["non-finite", "(2, 1)"]),
    "weights_inf": (dict(weights=with_value(W0, (0, 2), np.inf)), "weights", "non-finite"),
    "weights_zero": (dict(weights=with_value(W0, (2, 1), 0.0)), "weights",
                     ["must be > 0", "weight[2][1]"]),
    "weights_negative": (dict(weights=with_value(W0, (3, 0), -0.5)), "weights",
                         ["must be > 0", "weight[3][0]", "-0.5"]),
    "weights_all_negative": (dict(weights=-W0), "weights", "must be > 0"),
    "weights_transposed": (dict(weights=W0.T), "weights", ["expected shape (4, 3)", "(3, 4)"]),
    "weights_flat": (dict(weights=W0.ravel()), "weights", ["expected shape (4, 3)", "(12,)"]),
    "weights_3d": (dict(weights=W0[..., None]), "weights", "expected shape (4, 3)"),
}


@pytest.mark.parametrize("over, field, phrases", list(SURFACE_CASES.values()),
                         ids=list(SURFACE_CASES))
def test_invalid_surface_field(over, field, phrases):
    expect(InvalidSurfaceError, field, phrases, Surface, **base(**over))


def test_base_arguments_are_valid():
    # guards the table above: each case differs from a valid surface in one field only
    s = Surface(**base())
    assert s.shape == (NU, NV) and s.is_rational
    s6 = Surface(**base(knots_u=[0, 0, 0, 0.25, 0.5, 0.75, 1, 1, 1], control_points=P6,
                        weights=np.ones((6, NV))))
    assert s6.shape == (6, NV)
    s2 = Surface(**base(control_points=P2, knots_u=[0, 0, 1, 1], degree_u=1, weights=None))
    assert s2.shape == (2, NV)


def test_messages_show_plain_numbers():
    bad = []
    for name, (over, field, _) in SURFACE_CASES.items():
        try:
            Surface(**base(**over))
        except InvalidSurfaceError as e:
            if "np." in str(e):
                bad.append(f"{name}: {e}")
    assert not bad, "\n".join(bad)


# --------------------------------------------------------------------- invalid trims
SQUARE = [[0.1, 0.1], [0.9, 0.1], [0.9, 0.9], [0.1, 0.9], [0.1, 0.1]]


def seg(a, b):
    return {"degree": 1, "knots": [0, 0, 1, 1], "control_points": [list(a), list(b)]}


open_circle = circle_dict()
open_circle["control_points"][-1] = [0.7, 0.51]

TRIM_CASES = {
    "open_polyline": ([SQUARE[:-1]], "trim[0]", ["loop is open", "closure tolerance"]),
    "open_polyline_by_1e-5": ([SQUARE[:-1] + [[0.1, 0.1 + 1e-5]]], "trim[0]", "loop is open"),
    "open_nurbs_loop": ([open_circle], "trim[0]", ["loop is open", "0.01"]),
    "open_second_loop": ([SQUARE, SQUARE[:-1]], "trim[1]", "loop is open"),
    "chain_gap": ([[seg((.2, .2), (.8, .2)), seg((.8, .2), (.5, .8)), seg((.5, .81), (.2, .2))]],
                  "trim[0]", ["piece 1", "piece 2", "0.01"]),
    "chain_wrong_order": ([[seg((.2, .2), (.8, .2)), seg((.5, .8), (.2, .2)),
                            seg((.8, .2), (.5, .8))]], "trim[0]", ["piece 0", "piece 1"]),
    "chain_quarters_missing_one": ([circle_quarters()[:3]], "trim[0]", ["piece 2", "piece 0"]),
    "zero_area_back_and_forth": ([[[.1, .1], [.9, .9], [.1, .1]]], "trim[0]",
                                 "degenerate loop"),
    "collinear_points": ([[[.1, .1], [.5, .5], [.9, .9], [.1, .1]]], "trim[0]",
                         "degenerate loop"),
    "collinear_horizontal": ([[[.1, .5], [.3, .5], [.9, .5], [.1, .5]]], "trim[0]",
                             "degenerate loop"),
    "single_repeated_point": ([[[.3, .3], [.3, .3], [.3, .3]]], "trim[0]", "degenerate"),
    "single_point": ([[[.3, .3]]], "trim[0]", "at least 2 points"),
    "loop_of_no_pieces": ([TrimLoop(())], "trim[0]", "no pieces"),
    "degenerate_nurbs_loop": ([{"degree": 2, "knots": [0, 0, 0, 1, 1, 1],
                                "control_points": [[.5, .2], [.5, .8], [.5, .2]]}],
                              "trim[0]", "degenerate loop"),
    "polyline_outside_domain": ([[[.5, .5], [1.5, .5], [1.5, 1.5], [.5, .5]]], "trim[0]",
                                ["leaves the parameter domain", "[0.0, 1.0] x [0.0, 1.0]"]),
    "polyline_negative_uv": ([[[-.2, .5], [.5, .2], [.5, .8], [-.2, .5]]], "trim[0]",
                             "leaves the parameter domain"),
    "nurbs_loop_outside_domain": ([circle_dict((0.5, 0.5), 0.6)], "trim[0]",
                                  "leaves the parameter domain"),
    "second_loop_outside": ([SQUARE, circle_dict((0.95, 0.5), 0.1)], "trim[1]",
                            "leaves the parameter domain"),
    "dict_missing_degree": ([{"knots": [0, 0, 1, 1], "control_points": [[0, 0], [1, 1]]}],
                            "trim[0]", "missing degree"),
    "dict_missing_knots": ([{"degree": 1, "control_points": [[0, 0], [1, 1]]}],
                           "trim[0]", "missing knots"),
    "dict_missing_control_points": ([{"degree": 2, "knots": [0, 0, 0, 1, 1, 1]}],
                                    "trim[0]", "missing control_points"),
    "dict_missing_all": ([{}], "trim[0]", "missing degree, knots, control_points"),
    "chained_piece_missing_field": ([[seg((.2, .2), (.8, .2)), {"degree": 1}]], "trim[0][1]",
                                    "missing knots, control_points"),
    "polyline_3d_points": ([[[.1, .1, 0], [.9, .1, 0], [.5, .9, 0], [.1, .1, 0]]], "trim[0]",
                           ["expected shape (n, 2)", "(4, 3)"]),
    "polyline_1d_points": ([[.1, .9, .5, .1]], "trim[0]", "expected shape (n, 2)"),
    "nurbs_3d_points": ([{"degree": 1, "knots": [0, 0, .3, .6, 1, 1],
                          "control_points": [[.1, .1, 0], [.9, .1, 0], [.5, .9, 0], [.1, .1, 0]]}],
                        "trim[0].control_points", ["expected shape (n, 2)", "(4, 3)"]),
    "nurbs_bad_knot_count": ([{"degree": 2, "knots": [0, 0, 1, 1],
                               "control_points": [[.2, .2], [.8, .2], [.2, .2]]}],
                             "trim[0].knots", "n + p + 1"),
    "nurbs_degree_zero": ([{"degree": 0, "knots": [0, 1], "control_points": [[.2, .2]]}],
                          "trim[0].degree", "must be >= 1"),
    "nurbs_too_few_points": ([{"degree": 3, "knots": [0, 0, 0, 0, 1, 1, 1],
                               "control_points": [[.2, .2], [.8, .2], [.2, .2]]}],
                             "trim[0].control_points", "at least 4"),
    "nurbs_zero_weight": ([dict(circle_dict(), weights=[1, 0, 1, S2, 1, S2, 1, S2, 1])],
                          "trim[0].weights", ["must be > 0", "weight[1]"]),
    "nurbs_negative_weight": ([dict(circle_dict(), weights=[1, S2, 1, -S2, 1, S2, 1, S2, 1])],
                              "trim[0].weights", ["must be > 0", "weight[3]"]),
    "nurbs_nan_weight": ([dict(circle_dict(), weights=[1, S2, 1, S2, np.nan, S2, 1, S2, 1])],
                         "trim[0].weights", "non-finite"),
    "nurbs_weights_wrong_shape": ([dict(circle_dict(), weights=[1, S2, 1])],
                                  "trim[0].weights", ["expected shape (9", "got (3,)"]),
    "nurbs_nan_point": ([{"degree": 1, "knots": [0, 0, .5, 1, 1],
                          "control_points": [[.2, .2], [np.nan, .2], [.2, .2]]}],
                        "trim[0].control_points", "non-finite"),
    "polyline_inf_point": ([[[.2, .2], [np.inf, .2], [.5, .8], [.2, .2]]], "trim[0]",
                           "non-finite"),
    "trim_not_a_list": (5, "trim", "expected a list of loops"),
    "mixed_chain_item": ([[seg((.2, .2), (.8, .2)), [[.8, .2], [.2, .2]]]], "trim[0][1]",
                         "expected a polyline or a NURBS curve dict"),
}


@pytest.mark.parametrize("trim, field, phrases", list(TRIM_CASES.values()),
                         ids=list(TRIM_CASES))
def test_invalid_trim(trim, field, phrases):
    e = expect(InvalidTrimError, field, phrases, unit_plate, trim)
    assert isinstance(e, InvalidSurfaceError)  # documented subclass


def test_nurbs_loop_leaving_domain_between_samples():
    # quadratic Bézier v(t) = 1.0005 - 2 (t - t*)^2 with t* = 0.5 + 1/48: its maximum
    # lies half-way between the validation samples t = 12/24 and t = 13/24
    ts = 0.5 + 1 / 48
    v = lambda t: 1.0005 - 2 * (t - ts) ** 2  # noqa: E731
    b0, b2 = v(0.0), v(1.0)
    b1 = (b0 + b2 + 2.0) / 2  # b0 - 2 b1 + b2 = -2
    arc = {"degree": 2, "knots": [0, 0, 0, 1, 1, 1],
           "control_points": [[0.2, b0], [0.5, b1], [0.8, b2]]}
    chord = seg((0.8, b2), (0.2, b0))
    curve = TrimCurve.create(2, [0, 0, 0, 1, 1, 1], arc["control_points"])
    top = evaluate_trim_curve(curve, [ts])[0, 0]
    assert top[1] == pytest.approx(1.0005, abs=1e-12)  # the curve really leaves [0, 1]
    with pytest.raises(InvalidTrimError, match="leaves the parameter domain"):
        unit_plate([[arc, chord]])


def test_trim_errors_are_reported_per_loop_not_swallowed():
    # a valid outer loop followed by a bad hole: the error names the hole
    expect(InvalidTrimError, "trim[1]", "degenerate", unit_plate,
           [SQUARE, [[.3, .3], [.6, .6], [.3, .3]]])


# -------------------------------------------------------------- valid edge cases
def _basis(i, p, U, u):
    """Cox–de Boor recursion, straight from the definition (half-open spans)."""
    if p == 0:
        return 1.0 if U[i] <= u < U[i + 1] else 0.0
    out = 0.0
    if U[i + p] > U[i]:
        out += (u - U[i]) / (U[i + p] - U[i]) * _basis(i, p - 1, U, u)
    if U[i + p + 1] > U[i + 1]:
        out += (U[i + p + 1] - u) / (U[i + p + 1] - U[i + 1]) * _basis(i + 1, p - 1, U, u)
    return out


def brute_surface_point(p, q, U, V, P, W, u, v):
    """S(u, v) = sum N_i,p(u) N_j,q(v) w_ij P_ij / sum N N w, for u, v inside the
    half-open domain [U[p], U[n]) x [V[q], V[m])."""
    nu, nv = P.shape[:2]
    Nu = np.array([_basis(i, p, U, u) for i in range(nu)])
    Nv = np.array([_basis(j, q, V, v) for j in range(nv)])
    B = np.outer(Nu, Nv) * W
    assert abs(np.outer(Nu, Nv).sum() - 1.0) < 1e-12  # partition of unity on the domain
    return np.einsum("ij,ijk->k", B, P) / B.sum()


def brute_curve_point(p, U, P, W, t):
    n = P.shape[0]
    N = np.array([_basis(i, p, U, t) for i in range(n)]) * W
    return N @ P / N.sum()


UNCLAMPED = [
    # (id, degree_u, knots_u, degree_v, knots_v, marks)
    ("u_left_unclamped", 2, [0, 1, 2, 3, 4, 4, 4], 2, [0, 0, 0, 1, 1, 1], ()),
    ("v_left_unclamped", 2, [0, 0, 0, 0.5, 1, 1, 1], 2, [-3, -1, 0, 2, 2, 2], ()),
    ("u_deg1_uniform", 1, [0, 1, 2, 3, 4, 5], 2, [0, 0, 0, 1, 1, 1], ()),
    ("u_left_mult_p", 2, [0, 1, 1, 2, 3, 3, 3], 2, [0, 0, 0, 1, 1, 1], ()),
    ("u_right_mult_p", 2, [0, 0, 0, 1, 2, 2, 3], 2, [0, 0, 0, 1, 1, 1], ()),
    ("u_right_unclamped", 2, [0, 0, 0, 1, 2, 3, 4], 2, [0, 0, 0, 1, 1, 1], ()),
    ("u_uniform_unclamped", 2, [0, 1, 2, 3, 4, 5, 6], 2, [0, 0, 0, 1, 1, 1], ()),
    ("v_uniform_unclamped", 2, [0, 0, 0, 0.5, 1, 1, 1], 2, [0, 1, 2, 3, 4, 5],
     ()),
    ("both_unclamped_irregular", 2, [0, .5, 1.2, 2, 3, 3.1, 4.5], 2, [-1, 0, 1, 2, 3, 4.2],
     ()),
]


@pytest.mark.parametrize("rational", [False, True], ids=["bspline", "nurbs"])
@pytest.mark.parametrize(
    "p, U, q, V", [pytest.param(*c[1:5], id=c[0], marks=c[5]) for c in UNCLAMPED])
def test_unclamped_knots_evaluate_like_cox_de_boor(p, U, q, V, rational):
    U, V = np.asarray(U, float), np.asarray(V, float)
    nu, nv = len(U) - p - 1, len(V) - q - 1
    rng = np.random.default_rng(7)
    P = rng.normal(size=(nu, nv, 3))
    W = rng.uniform(0.3, 3.0, size=(nu, nv)) if rational else np.ones((nu, nv))
    s = Surface(p, q, U, V, P, W if rational else None)
    # the domain is [U[p], U[n]] x [V[q], V[m]] and the stored vectors are clamped
    assert s.domain == ((U[p], U[nu]), (V[q], V[nv]))
    for K, d in ((s.knots_u, p), (s.knots_v, q)):
        assert np.all(K[: d + 1] == K[0]) and np.all(K[-d - 1:] == K[-1])
    (u0, u1), (v0, v1) = s.domain
    uv = np.column_stack([np.r_[u0, rng.uniform(u0, u1, 10), np.nextafter(u1, u0)],
                          np.r_[v0, rng.uniform(v0, v1, 10), np.nextafter(v1, v0)]])
    got = s.evaluate(uv)
    want = np.array([brute_surface_point(p, q, U, V, P, W, u, v) for u, v in uv])
    np.testing.assert_allclose(got, want, rtol=0, atol=1e-12 * (1 + np.abs(P).max()))


def test_unclamped_sample_surface_is_clamped_equivalent():
    # The outermost knots U[0] and U[-1] never influence a curve on its domain, so the
    # clamped freeform sample with U[0], U[-1] moved outwards (multiplicity p at the
    # domain ends: unclamped, no knot insertion needed) is the same surface.
    s = geomkit.samples.load("freeform_1")[0]
    U, V = np.array(s.knots_u), np.array(s.knots_v)
    U[0] -= 0.5
    V[0] -= 0.25
    V[-1] += 2.0
    s2 = Surface(s.degree_u, s.degree_v, U, V, s.control_points, s.weights)
    assert s2.domain == s.domain
    np.testing.assert_array_equal(s2.knots_u, s.knots_u)
    np.testing.assert_array_equal(s2.knots_v, s.knots_v)
    (u0, u1), (v0, v1) = s.domain
    uv = np.random.default_rng(1).uniform([u0, v0], [u1, v1], size=(50, 2))
    np.testing.assert_allclose(s2.evaluate(uv), s.evaluate(uv), rtol=0, atol=1e-12 * s.size)
    want = [brute_surface_point(s.degree_u, s.degree_v, U, V, s.control_points,
                                np.ones(s.shape), u, v) for u, v in uv[:10]]
    np.testing.assert_allclose(s2.evaluate(uv[:10]), want, rtol=0, atol=1e-12 * s.size)


def test_unclamped_closed_periodic_trim_loop_is_accepted():
    # the usual "periodic" closed cubic B-spline: uniform knots, first 3 points repeated;
    # it is exactly closed: C(3) = C(n) = (P0 + 4 P1 + P2) / 6
    th = np.linspace(0, 2 * np.pi, 9)[:-1]
    P = np.column_stack([0.5 + 0.3 * np.cos(th), 0.5 + 0.3 * np.sin(th)])
    P = np.vstack([P, P[:3]])
    U = np.arange(len(P) + 4, dtype=float)
    c = TrimCurve.create(3, U, P)
    start = (P[0] + 4 * P[1] + P[2]) / 6
    np.testing.assert_allclose(c.start, start, atol=1e-14)
    np.testing.assert_allclose(c.end, start, atol=1e-14)
    s = unit_plate([{"degree": 3, "knots": U, "control_points": P}])
    assert classify_uv(s, [0.5, 0.5]) == INSIDE


@pytest.mark.parametrize("U", [
    [0, 0, 0, 1, 2, 3, 3, 3],
    [-2, -1, 0, 1, 2, 3, 3, 3],
    [0, 0, 0, 1, 2, 3, 4, 5],
    [-2, -1, 0, 1, 2, 3, 4, 5],
], ids=["clamped", "left_unclamped", "right_unclamped", "both_unclamped"])
def test_unclamped_trim_curve_evaluates_like_cox_de_boor(U):
    U = np.asarray(U, float)
    p, n = 2, len(U) - 3
    rng = np.random.default_rng(3)
    P = rng.uniform(0.1, 0.9, size=(n, 2))
    W = rng.uniform(0.5, 2.0, size=n)
    c = TrimCurve.create(p, U, P, W)
    a, b = U[p], U[n]
    assert (c.knots[0], c.knots[-1]) == (a, b)
    t = np.r_[a, rng.uniform(a, b, 12), np.nextafter(b, a)]
    got = evaluate_trim_curve(c, t)[:, 0, :]
    want = np.array([brute_curve_point(p, U, P, W, x) for x in t])
    np.testing.assert_allclose(got, want, rtol=0, atol=1e-13)


def test_all_ones_weights_are_non_rational():
    s = Surface(**base(weights=np.ones((NU, NV))))
    ref = Surface(**base(weights=None))
    assert not s.is_rational and s.weights is None
    assert "weights" not in s.to_dict()
    np.testing.assert_array_equal(s.homogeneous, ref.homogeneous)
    uv = RNG.uniform(0, 1, size=(20, 2))
    np.testing.assert_array_equal(s.evaluate(uv), ref.evaluate(uv))
    # integer ones (as read from JSON) too; a single weight != 1 keeps it rational
    assert not Surface(**base(weights=[[1] * NV] * NU)).is_rational
    assert Surface(**base(weights=with_value(np.ones((NU, NV)), (1, 1), 1.5))).is_rational


def test_uniform_weights_other_than_one_stay_rational_and_equal_bspline():
    s = Surface(**base(weights=np.full((NU, NV), 3.0)))
    ref = Surface(**base(weights=None))
    assert s.is_rational
    uv = RNG.uniform(0, 1, size=(20, 2))
    np.testing.assert_allclose(s.evaluate(uv), ref.evaluate(uv), rtol=0, atol=1e-14)


def test_integral_float_degree_is_accepted():
    s = Surface(**base(degree_u=2.0, degree_v=np.int64(2)))
    assert s.degree_u == 2 and type(s.degree_u) is int and s.degree_v == 2


def test_surface_copies_and_freezes_its_input():
    P = P0.copy()
    W = W0.copy()
    U = np.array(KU, float)
    s = Surface(2, 2, U, KV, P, W)
    uv = [[0.3, 0.6]]
    before = s.evaluate(uv).copy()
    P += 5.0
    W[:] = 1.0
    U[3] = 0.9
    np.testing.assert_array_equal(s.evaluate(uv), before)
    for a in (s.control_points, s.weights, s.knots_u, s.knots_v, s.homogeneous):
        assert not a.flags.writeable and a.flags.c_contiguous and a.dtype == np.float64
        with pytest.raises(ValueError):
            a.flat[0] = 1.0


def test_clamped_input_is_stored_unchanged():
    s = Surface(**base())
    np.testing.assert_array_equal(s.knots_u, KU)
    np.testing.assert_array_equal(s.knots_v, KV)
    np.testing.assert_array_equal(s.weights, W0)
    np.testing.assert_allclose(s.control_points, P0, rtol=4e-16, atol=0)


def test_rational_control_points_are_stored_exactly():
    s = Surface(**base())
    np.testing.assert_array_equal(s.control_points, P0)


TRI = [[.2, .2], [.8, .2], [.5, .8], [.2, .2]]


@pytest.mark.parametrize("make", [
    lambda: [np.array(TRI)],
    lambda: [np.array(TRI, dtype=np.float32).astype(np.float64)],
    lambda: [[np.array(pt) for pt in TRI]],
    lambda: [tuple(tuple(pt) for pt in TRI)],
    lambda: [np.array(TRI, dtype=np.float32)],
], ids=["ndarray", "float64_copy", "list_of_arrays", "tuples", "float32"])
def test_polyline_given_with_numpy_arrays(make):
    s = unit_plate(make())
    (loop,) = s.trim
    assert loop.is_polyline and len(loop.pieces) == 1
    np.testing.assert_allclose(loop.pieces[0].control_points, TRI, atol=1e-7)
    np.testing.assert_array_equal(classify_uv(s, [[0.5, 0.4], [0.5, 0.9], [0.1, 0.1]]),
                                  [INSIDE, OUTSIDE, OUTSIDE])


def test_polyline_repeated_vertices_are_dropped():
    s = unit_plate([[[.2, .2], [.8, .2], [.8, .2], [.5, .8], [.2, .2]]])
    np.testing.assert_array_equal(s.trim[0].pieces[0].control_points, TRI)


def test_trim_loop_of_chained_nurbs_pieces():
    quarters = circle_quarters()
    s = unit_plate([SQUARE, quarters])
    outer, hole = s.trim
    assert len(hole.pieces) == 4 and not hole.is_polyline
    for a, b in zip(hole.pieces, hole.pieces[1:] + hole.pieces[:1]):
        np.testing.assert_array_equal(a.end, b.start)
    # mixed degrees in one chain: a rational arc closed by a straight piece
    arc = {"degree": 2, "knots": [0, 0, 0, 1, 1, 1],
           "control_points": [[.2, .5], [.5, .95], [.8, .5]], "weights": [1, 3, 1]}
    s2 = unit_plate([[arc, seg((.8, .5), (.2, .5))]])
    assert [c.degree for c in s2.trim[0].pieces] == [2, 1]
    np.testing.assert_array_equal(classify_uv(s2, [[.5, .6], [.5, .4], [.5, .93]]),
                                  [INSIDE, OUTSIDE, OUTSIDE])


def test_trim_objects_are_accepted_as_is():
    c = TrimCurve.create(2, circle_dict()["knots"], circle_dict()["control_points"],
                         circle_dict()["weights"])
    loop = TrimLoop((c,))
    for trim in ([c], [loop], c, loop, circle_dict()):
        s = unit_plate(trim)
        assert len(s.trim) == 1 and s.trim[0].pieces[0].degree == 2
        np.testing.assert_array_equal(classify_uv(s, [[.5, .5], [.1, .1]]), [INSIDE, OUTSIDE])


def test_closure_within_tolerance_is_accepted():
    # a gap far below CLOSURE_TOL * domain size is bridged, not rejected
    s = unit_plate([SQUARE[:-1] + [[0.1, 0.1 + 1e-9]]])
    assert classify_uv(s, [0.5, 0.5]) == INSIDE


@pytest.mark.parametrize("U", [[0, 0, 0, 0, 1, 1, 1], [0, 0, 0, 1, 1, 1, 1]],
                         ids=["left_mult_p+2", "right_mult_p+2"])
def test_end_knot_multiplicity_above_degree_plus_one(U):
    # either rejected with a clear error, or evaluated like the definition (the basis
    # function over the empty end span is identically zero)
    rng = np.random.default_rng(5)
    P = rng.normal(size=(4, 2, 3))
    try:
        s = Surface(2, 1, U, [0, 0, 1, 1], P)
    except InvalidSurfaceError as e:
        assert e.field == "knots_u" and "multiplicity" in str(e)
        return
    uv = np.array([[0.0, 0.5], [0.5, 0.5], [np.nextafter(1.0, 0.0), 0.5], [1.0, 0.5]])
    got = s.evaluate(uv)
    want = [brute_surface_point(2, 1, np.array(U, float), np.array([0, 0, 1, 1.]), P,
                                np.ones((4, 2)), u, v) for u, v in uv[:3]]
    np.testing.assert_allclose(got[:3], want, atol=1e-12)
    np.testing.assert_allclose(got[3], got[2], atol=1e-9)
