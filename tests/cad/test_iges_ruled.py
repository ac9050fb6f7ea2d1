"""IGES 118 form 0: rulings join points at equal relative *arc length*.

geomkit builds a ruled surface joining equal relative parameters (form 1).  The two
agree where both curves run at constant speed in their parameters (lines, circular
arcs): then form 0 is read, and the surface is the closed form (a cone frustum between
two coaxial arcs).  Between curves that do not (ellipse arcs of different shape, a
B-spline whose speed varies), there is no exact NURBS: the face is refused with a
message naming form 0, or listed with ``skip_unsupported`` — never read as a different
surface (before this, form 0 was read as form 1 whatever the curves)."""

from __future__ import annotations

import math

import numpy as np
import pytest

import geomkit
from geomkit.errors import FileFormatError
from geomkit.nurbs.evaluation import evaluate
from geomkit.cad.iges.reader import read_iges

from helpers.igeswrite import de, write_iges


def _arc(r, z, a0, a1):
    """Entity 100: circular arc of radius r at height z, centre on the z axis, from
    angle a0 to a1 (counter-clockwise)."""
    return (100, [z, 0.0, 0.0, r * math.cos(a0), r * math.sin(a0),
                  r * math.cos(a1), r * math.sin(a1)])


def _full(s):
    return geomkit.Surface(s.degree_u, s.degree_v, s.knots_u, s.knots_v, s.control_points,
                           s.weights)


@pytest.mark.parametrize("form", [0, 1])
def test_form0_between_coaxial_arcs_is_the_cone(tmp_path, form):
    path = tmp_path / "cone.igs"
    write_iges(path, [_arc(4.0, 0.0, 0.3, 2.5), _arc(2.0, 3.0, 0.3, 2.5),
                      (118, [de(0), de(1), 0, 0], form)])
    res = read_iges(path)
    (s,) = res.surfaces
    assert s.approx_error == 0.0
    # closed form: the ruling at angle th joins (4 cos th, 4 sin th, 0) and
    # (2 cos th, 2 sin th, 3); equal arc length = equal angle on both arcs
    rng = np.random.default_rng(1)
    th, v = 0.3 + 2.2 * rng.random(40), rng.random(40)
    r = 4.0 - 2.0 * v
    X = np.column_stack([r * np.cos(th), r * np.sin(th), 3.0 * v])
    assert geomkit.project_points([_full(s)], X).distance.max() <= 1e-12
    (u0, u1), (v0, v1) = s.domain
    Y = evaluate(s, rng.random((40, 2)) * [u1 - u0, v1 - v0] + [u0, v0])
    rr = np.hypot(Y[:, 0], Y[:, 1])
    assert np.abs(rr - (4.0 - 2.0 * Y[:, 2] / 3.0)).max() <= 1e-12


def _ellipse(a, b, z, t0, t1):
    return (104, [1 / a ** 2, 0.0, 1 / b ** 2, 0.0, 0.0, -1.0, z,
                  a * math.cos(t0), b * math.sin(t0), a * math.cos(t1), b * math.sin(t1)], 1)


def test_form0_between_ellipses_of_different_shape_is_refused(tmp_path):
    path = tmp_path / "ruled0.igs"
    write_iges(path, [_ellipse(4, 2, 0.0, 0.3, 2.0), _ellipse(2, 1.5, 5.0, 0.3, 2.0),
                      (118, [de(0), de(1), 0, 1], 0),
                      (110, [0.0, 0.0, 9.0, 1.0, 0.0, 9.0]),
                      (110, [0.0, 1.0, 9.0, 1.0, 1.0, 9.0]),
                      (118, [de(3), de(4), 0, 1], 0)])  # a square: two lines, form 0
    with pytest.raises(FileFormatError, match=r"118@5: .*form 0 .*no exact NURBS"):
        read_iges(path)
    res = read_iges(path, skip_unsupported=True)
    assert [s.name for s in res.surfaces] == ["118@11"]
    assert [str(x).split(":")[0] for x in res.skipped] == ["118@5"]
    assert "form 0" in str(res.skipped[0])
    # the same curves as form 1 (equal entity parameter) are exact
    path1 = tmp_path / "ruled1.igs"
    write_iges(path1, [_ellipse(4, 2, 0.0, 0.3, 2.0), _ellipse(2, 1.5, 5.0, 0.3, 2.0),
                       (118, [de(0), de(1), 0, 1], 1)])
    assert len(read_iges(path1).surfaces) == 1


def test_form0_between_similar_ellipses_is_refused(tmp_path):
    """Two ellipses of the same shape (one scaled by 0.5): their relative arc length
    is the same function of the angle, but neither runs at constant speed, so form 0
    still needs arc-length parameters: refused (conservative), not read as form 1."""
    path = tmp_path / "ruled_sim.igs"
    write_iges(path, [_ellipse(4, 2, 0.0, 0.3, 2.0), _ellipse(2, 1, 5.0, 0.3, 2.0),
                      (118, [de(0), de(1), 0, 1], 0)])
    with pytest.raises(FileFormatError, match="form 0"):
        read_iges(path)


def test_form0_between_splines_of_varying_and_constant_speed(tmp_path):
    """126 quadratic B-splines on straight lines.  The first one's middle control point
    is off centre (its speed varies), the second one's centred (constant speed):
    form 0 is refused; with both centred the same file reads, and so does form 1."""
    def spline(mid, y, z):
        return (126, [2, 2, 1, 0, 1, 0, 0, 0, 0, 1, 1, 1, 1, 1, 1,
                      0.0, y, z, mid, y, z, 4.0, y, z, 0.0, 1.0, 0.0, 0.0, 1.0])
    for mid, form, ok in ((0.5, 0, False), (2.0, 0, True), (0.5, 1, True)):
        path = tmp_path / f"ruled_{mid}_{form}.igs"
        write_iges(path, [spline(mid, 0.0, 0.0), spline(2.0, 3.0, 1.0),
                          (118, [de(0), de(1), 0, 1], form)])
        if ok:
            (s,) = read_iges(path).surfaces
            uv = np.random.default_rng(2).random((20, 2))
            (u0, u1), (v0, v1) = s.domain
            Y = evaluate(s, uv * [u1 - u0, v1 - v0] + [u0, v0])
            assert np.abs(Y[:, 1] - 3.0 * Y[:, 2]).max() <= 1e-12  # the plane y = 3 z
        else:
            with pytest.raises(FileFormatError, match="form 0"):
                read_iges(path)
