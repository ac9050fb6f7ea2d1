"""Probe safety (geomkit.probe_clearance): certified stylus clearance along a path.

Oracles are independent of the NURBS machinery: the torus' closed-form distance
function (|(hypot(x, y) - 20, z)| - 5) minimised over densely sampled stylus axis
points and motion parameters, and the trimmed plate's hole geometry."""

from __future__ import annotations

import math

import numpy as np
import pytest

import geomkit
from geomkit import InvalidInputError, Stylus, probe_clearance
from geomkit.jobs.clearance import _frame_with_z, read_path


@pytest.fixture(scope="module")
def torus():
    return geomkit.samples.load_case("torus").surfaces


@pytest.fixture(scope="module")
def plate():
    return geomkit.samples.load_case("plate_with_hole").surfaces


def torus_distance(P):
    P = np.atleast_2d(P)
    return np.hypot(np.hypot(P[:, 0], P[:, 1]) - 20.0, P[:, 2]) - 5.0


def capsule_gap(A, B, r, n=4001):
    t = np.linspace(0.0, 1.0, n)[:, None]
    return float(torus_distance(A + t * (B - A)).min()) - r


STYLUS = Stylus(tip_radius=1.0, shaft_radius=0.5, shaft_length=20.0,
                extension_radius=2.0, extension_length=30.0)


def test_straight_moves_over_the_torus_match_the_closed_form(torus):
    path = np.array([[-30, 0, 10.0], [30, 0, 10.0], [30, 0, 3.0], [30, 0, -3.0],
                     [35, 20, 0.0]])
    r = probe_clearance(torus, STYLUS, path, tol=1e-9)
    for i in range(len(path) - 1):
        s = np.linspace(0, 1, 3001)[:, None]
        tips = path[i] + s * (path[i + 1] - path[i])
        want = float(torus_distance(tips).min()) - 1.0  # the tip is closest here
        assert r.lower_bound[i] <= want + 1e-9 and r.clearance[i] >= want - 1e-6
        assert r.clearance[i] - r.lower_bound[i] <= 1e-9 * (1 + 1e-6)
        assert r.certified[i] and r.passed[i] and np.isnan(r.first_contact[i])
        # the reported closest part point is on the torus, at the reported gap
        assert abs(torus_distance(r.point_part[i])[0]) < 1e-9
        tip = path[i] + r.parameter[i] * (path[i + 1] - path[i])
        assert abs(np.linalg.norm(tip - r.point_part[i]) - 1.0 - r.clearance[i]) < 1e-8
    assert r.component_names == ("tip", "shaft", "extension")
    assert r.ok and r.motion[0] == "translation"
    # shaft of segment 1: a vertical capsule from the tip up 20, at x = 30 -> 20 - 5 - 0.5
    assert abs(r.per_component[0, 1] - 4.5) < 1e-9
    assert abs(r.parameter[2] - 0.5) < 1e-9 and abs(r.clearance[2] - 4.0) < 1e-9


def test_plunge_first_contact_parameter_and_point(torus):
    r = probe_clearance(torus, STYLUS, [[20, 0, 10.0], [20, 0, 0.0]], contact_tol=1e-10)
    assert not r.ok and r.contact[0] and r.clearance[0] == 0.0
    assert abs(r.first_contact[0] - 0.4) < 1e-9  # tip centre at z = 6 touches z = 5
    assert np.allclose(r.point_part[0], [20, 0, 5], atol=1e-6)
    assert np.allclose(r.point_stylus[0], [20, 0, 5], atol=1e-6)
    assert r.component_names[r.component[0]] == "tip"


def test_margin_decides_pass_and_fail(torus):
    path = [[-30, 0, 10.0], [30, 0, 10.0]]
    assert probe_clearance(torus, STYLUS, path, margin=3.999).ok
    assert not probe_clearance(torus, STYLUS, path, margin=4.001).ok


def test_reversed_path_same_clearance(torus):
    path = np.array([[-25, 3, 9.0], [28, -4, 12.0]])
    a = probe_clearance(torus, STYLUS, path, tol=1e-10)
    b = probe_clearance(torus, STYLUS, path[::-1], tol=1e-10)
    assert abs(a.clearance[0] - b.clearance[0]) < 1e-9


def test_rotation_about_a_fixed_line_against_a_dense_oracle(torus):
    # the stylus pivots about its tip centre at the torus' centre, from +z down toward +x
    st = Stylus(tip_radius=1.0, shaft_radius=0.5, shaft_length=15.5)
    T0 = np.eye(4)
    T1 = np.eye(4)
    T1[:3, :3] = _frame_with_z(np.array([1.0, 0.0, 0.0]))
    # 90 deg about -y takes +x to +z: the relative motion turns the axis in the xz-plane
    T0[:3, :3] = np.array([[0.0, 0, -1], [0, 1, 0], [1, 0, 0]]) @ T1[:3, :3]
    r = probe_clearance(torus, st, np.array([T0, T1]), tol=1e-9, contact_tol=1e-10)
    assert r.motion == ("rotation",)
    z0 = T0[:3, 2]
    z1 = T1[:3, 2]
    ang = math.acos(np.clip(z0 @ z1, -1, 1))
    k = np.cross(z0, z1) / np.linalg.norm(np.cross(z0, z1))

    def axis_at(phi):
        d = (z0 * math.cos(phi) + np.cross(k, z0) * math.sin(phi)
             + k * (k @ z0) * (1 - math.cos(phi)))
        return np.zeros(3), 15.5 * d

    # first contact: the shaft capsule reaches the tube; bisection on the dense oracle
    lo, hi = 0.0, ang
    assert capsule_gap(*axis_at(hi), 0.5) < 0 < capsule_gap(*axis_at(lo), 0.5)
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        if min(capsule_gap(*axis_at(p), 0.5) for p in np.linspace(0, mid, 50)) <= 0:
            hi = mid
        else:
            lo = mid
    assert abs(r.first_contact[0] - hi / ang) < 1e-6
    assert r.component_names[r.component[0]] == "shaft" and r.contact[0]


def test_clear_rotation_gap(torus):
    st = Stylus(tip_radius=1.0, shaft_radius=0.5, shaft_length=10.0)
    T0 = np.eye(4)
    T0[:3, :3] = _frame_with_z(np.array([1.0, 0, 0]))
    T1 = np.eye(4)
    T1[:3, :3] = _frame_with_z(np.array([0.0, 1, 0]))
    r = probe_clearance(torus, st, np.array([T0, T1]), tol=1e-9)
    assert abs(r.clearance[0] - 4.5) < 1e-8 and r.lower_bound[0] <= 4.5 <= r.clearance[0]


def test_trim_edge_of_the_plate_hole(plate):
    st = Stylus(1.0, 0.5, 20.0)
    # straight down through the hole, 5 off its axis: nearest material is the hole edge
    r = probe_clearance(plate, st, [[55, 50, 10.0], [55, 50, -10.0]], tol=1e-6)
    assert r.ok
    assert r.lower_bound[0] <= 14.0 + 1e-9 <= r.clearance[0] + 2e-9
    # the gap is attained exactly; the lower bound of a minimum on a trim curve may stay
    # loose (surface_distance's documented shortfall) and is then flagged
    assert abs(r.clearance[0] - 14.0) < 1e-6
    assert r.certified[0] == (r.clearance[0] - r.lower_bound[0] <= 1e-6 * (1 + 1e-9))
    # beside the hole the tip lands on the plate: contact when the centre is at z = 1
    r = probe_clearance(plate, st, [[80, 50, 10.0], [80, 50, -10.0]], contact_tol=1e-10)
    assert abs(r.first_contact[0] - 0.45) < 1e-9 and not r.ok


def test_point_path_axis(torus):
    # stylus pointing sideways (+x) from a tip left of the torus: the shaft lies along x
    r = probe_clearance(torus, Stylus(1.0, 0.5, 30.0), [[-40, 0, 0.0], [-40, 0, 1.0]],
                        axis=(1, 0, 0))
    assert not r.ok and r.first_contact[0] == 0.0  # the shaft already crosses the tube


@pytest.mark.parametrize("kwargs, field", [
    (dict(stylus=dict(tip_radius=-1, shaft_radius=1, shaft_length=1)), "stylus.tip_radius"),
    (dict(stylus=dict(tip_radius=1, shaft_radius=1, shaft_length=0)), "stylus.shaft_length"),
    (dict(stylus=dict(tip_radius=1, shaft_radius=1, shaft_length=1, extension_radius=2)),
     "stylus.extension"),
    (dict(stylus=dict(tip_radius=float("nan"), shaft_radius=1, shaft_length=1)),
     "stylus.tip_radius"),
])
def test_bad_stylus(kwargs, field):
    with pytest.raises(InvalidInputError) as e:
        Stylus(**kwargs["stylus"])
    assert field in str(e.value)


def test_bad_stylus_dict():
    with pytest.raises(InvalidInputError, match="unknown key"):
        Stylus.from_dict({"tip_radius": 1, "shaft_radius": 1, "shaft_length": 1, "tip": 2})
    with pytest.raises(InvalidInputError, match="missing"):
        Stylus.from_dict({"tip_radius": 1})


def test_bad_paths(torus):
    with pytest.raises(InvalidInputError, match="at least 2"):
        probe_clearance(torus, STYLUS, [[0, 0, 10.0]])
    with pytest.raises(InvalidInputError, match="shape"):
        probe_clearance(torus, STYLUS, np.zeros((3, 2)))
    with pytest.raises(InvalidInputError, match="finite|NaN"):
        probe_clearance(torus, STYLUS, [[0, 0, 10.0], [np.nan, 0, 1]])
    bad = np.tile(np.eye(4), (2, 1, 1))
    bad[1, 0, 0] = 2.0
    with pytest.raises(InvalidInputError, match="rigid"):
        probe_clearance(torus, STYLUS, bad)
    screw = np.tile(np.eye(4), (2, 1, 1))
    screw[1, :3, :3] = [[0, -1, 0], [1, 0, 0], [0, 0, 1]]  # 90 deg about z
    screw[1, 2, 3] = 5.0  # and 5 along z: a screw
    with pytest.raises(InvalidInputError, match="screw"):
        probe_clearance(torus, STYLUS, screw)
    with pytest.raises(InvalidInputError, match="Stylus"):
        probe_clearance(torus, {"tip_radius": 1}, [[0, 0, 10.0], [1, 0, 10]])
    with pytest.raises(InvalidInputError, match="part"):
        probe_clearance("torus", STYLUS, [[0, 0, 10.0], [1, 0, 10]])


def test_read_path_formats(tmp_path):
    (tmp_path / "p.json").write_text('{"points": [[0, 0, 1], [1, 2, 3]]}')
    assert read_path(tmp_path / "p.json").shape == (2, 3)
    (tmp_path / "q.json").write_text('{"poses": [%s, %s]}' % ((np.eye(4).tolist(),) * 2))
    assert read_path(tmp_path / "q.json").shape == (2, 4, 4)
    (tmp_path / "p.csv").write_text("x,y,z\n0,0,1\n1,2,3\n")
    assert read_path(tmp_path / "p.csv").shape == (2, 3)
    (tmp_path / "bad.json").write_text('{"points": [[0, 0, 1], [1, 2, 3]], "poses": []}')
    with pytest.raises(InvalidInputError, match="exactly one"):
        read_path(tmp_path / "bad.json")
    (tmp_path / "broken.json").write_text('{"points": [[0, 0')
    with pytest.raises(InvalidInputError, match="JSON"):
        read_path(tmp_path / "broken.json")
