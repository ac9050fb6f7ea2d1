"""Orientation and position against analytic values on posed constructed parts."""

from __future__ import annotations

import json
import math
import sys
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings, strategies as st

sys.path.insert(0, str(Path(__file__).resolve().parent))
import gdtcases as C  # noqa: E402

from geomkit.errors import InvalidInputError  # noqa: E402
from geomkit.gdt import (Datum, angularity, datum_frame, mmc_bonus,  # noqa: E402
                         parallelism, perpendicularity, position)


def frame(R, t):
    """A|B|C of the box [0,100]x[0,60]x[0,40]: datum axes x=-X, y=Y, z=-Z, origin 0."""
    A, B, Cc, _ = C.box_faces()
    return datum_frame(Datum("A", "plane", C.place(A, R, t), normal=R @ [0, 0, -1.0]),
                       Datum("B", "plane", C.place(B, R, t), normal=R @ [-1.0, 0, 0]),
                       Datum("C", "plane", C.place(Cc, R, t), normal=R @ [0, -1.0, 0]))


def plane_pts(origin, e_s, e_y, l, w, n=(6, 4)):
    s, y = C.grid(n[0], n[1], l, w)
    return np.asarray(origin) + s[:, None] * e_s + y[:, None] * e_y


def tilted_cylinder(r, L, theta, base, tilt_axis="y", n_theta=12, n_z=5):
    """Cylinder of radius r, length L, axis +Z turned by theta about X or Y, base at
    ``base``."""
    P = C.cylinder(r, 0.0, L, n_theta=n_theta, n_z=n_z)
    c, s = math.cos(theta), math.sin(theta)
    M = (np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]]) if tilt_axis == "y"
         else np.array([[1, 0, 0], [0, c, -s], [0, s, c]]))
    return P @ M.T + base, M @ [0, 0, 1.0]


SEEDS = range(3)


@pytest.mark.parametrize("seed", SEEDS)
def test_parallelism_tilted_plane(seed):
    R, t = C.pose(seed)
    f = frame(R, t)
    th = 1e-3
    P = plane_pts([0, 0, 40.0], np.array([math.cos(th), 0, math.sin(th)]),
                  np.array([0, 1.0, 0]), 100.0 / math.cos(th), 60.0)
    ch = parallelism(C.place(P, R, t), 0.2, f, "A")
    assert ch.measured == pytest.approx(100 * math.tan(th), rel=1e-9)
    assert ch.passed and ch.datums == ("A",)
    json.dumps(ch.to_dict())


@pytest.mark.parametrize("seed", SEEDS)
def test_perpendicularity_plane_free_rotation_and_fixed(seed):
    R, t = C.pose(seed)
    f = frame(R, t)
    th = 2e-3
    P = plane_pts([100.0, 0, 0], np.array([math.sin(th), 0, math.cos(th)]),
                  np.array([0, 1.0, 0]), 40.0 / math.cos(th), 60.0)
    Pp = C.place(P, R, t)
    ch = perpendicularity(Pp, 0.05, f, "A")
    assert ch.measured == pytest.approx(40 * math.tan(th), rel=1e-9)
    fixed = perpendicularity(Pp, 0.05, f, "A", direction=R @ [1.0, 0, 0])
    assert fixed.measured == pytest.approx(40 * math.tan(th), rel=1e-9)
    # perpendicular to C (normal y) alone: the zone turns about y onto the tilted
    # face, width 0; fixed to the nominal normal x: 40 tan(th) again
    assert perpendicularity(Pp, 0.05, f, "C").measured < 1e-12
    fixed = perpendicularity(Pp, 0.05, f, "C", direction=R @ [1.0, 0, 0])
    assert fixed.measured == pytest.approx(40 * math.tan(th), rel=1e-9)


@pytest.mark.parametrize("seed", SEEDS)
def test_angularity_plane(seed):
    R, t = C.pose(seed)
    f = frame(R, t)
    g, dl, l = math.radians(30.0), 1e-3, 50.0
    P = plane_pts([0, 0, 40.0], np.array([math.cos(g + dl), 0, math.sin(g + dl)]),
                  np.array([0, 1.0, 0]), l, 60.0)
    ch = angularity(C.place(P, R, t), 0.1, f, 30.0, "A")
    assert ch.measured == pytest.approx(l * math.sin(dl), rel=1e-7)
    fixed = angularity(C.place(P, R, t), 0.1, f, 30.0, "A", direction=R @ [-0.5, 0, 0.86])
    assert fixed.measured == pytest.approx(l * math.sin(dl), rel=1e-9)


@pytest.mark.parametrize("seed", SEEDS)
def test_axis_orientation(seed):
    R, t = C.pose(seed)
    f = frame(R, t)
    th, L = 1e-3, 30.0
    P, _ = tilted_cylinder(5.0, L, th, [50.0, 30.0, 5.0])
    ch = perpendicularity(C.place(P, R, t), 0.05, f, "A", feature="axis")
    assert ch.measured == pytest.approx(L * math.sin(th), rel=1e-8)
    assert ch.tolerance["diameter"] is True
    # a horizontal bore along x tilted up by th: parallel to A, two-plane zone
    Q, _ = tilted_cylinder(5.0, L, math.pi / 2 - th, [10.0, 30.0, 20.0])
    ch = parallelism(C.place(Q, R, t), 0.05, f, "A", feature="axis")
    assert ch.measured == pytest.approx(L * math.sin(th), rel=1e-8)
    assert ch.tolerance["diameter"] is False


def test_axis_parallel_to_datum_axis():
    shaft = C.cylinder(8.0, 0.0, 40.0)
    f = datum_frame(Datum("A", "cylinder", shaft, feature="external"))
    th, L = 2e-3, 25.0
    P, _ = tilted_cylinder(3.0, L, th, [20.0, 0.0, 5.0], tilt_axis="x")
    ch = parallelism(P, 0.06, f, "A", feature="axis")
    assert ch.measured == pytest.approx(L * math.sin(th), rel=1e-8) and ch.passed


@pytest.mark.parametrize("seed", SEEDS)
def test_position_hole_offset(seed):
    R, t = C.pose(seed)
    f = frame(R, t)
    dx, dy = 0.03, -0.04
    P = C.cylinder(5.0, 0.0, 40.0, center=(50 + dx, 30 + dy))
    ch = position(C.place(P, R, t), 0.12, f, nominal=(-50.0, 30.0, 0.0))
    assert ch.measured == pytest.approx(2 * math.hypot(dx, dy), abs=1e-9)
    assert ch.passed and ch.datums == ("A", "B", "C")
    assert not position(C.place(P, R, t), 0.09, f, nominal=(-50.0, 30.0, 0.0)).passed
    rect = position(C.place(P, R, t), (0.07, 0.09), f, nominal=(-50.0, 30.0, 0.0))
    assert rect.measured == pytest.approx((2 * dx, 2 * abs(dy)), abs=1e-9)
    assert rect.passed
    assert not position(C.place(P, R, t), (0.07, 0.07), f, nominal=(-50, 30, 0)).passed
    json.dumps(ch.to_dict())


def test_position_tilted_hole_uses_end_points():
    f = frame(np.eye(3), np.zeros(3))
    th, L = 1e-3, 40.0
    P, _ = tilted_cylinder(5.0, L, th, [50.0, 30.0, 0.0])
    ch = position(P, 0.1, f, nominal=(-50.0, 30.0, 0.0), method="lsq")
    assert ch.measured == pytest.approx(2 * L * math.sin(th), rel=1e-8)


@pytest.mark.parametrize("feature, r, limits, material, bonus", [
    ("hole", 5.1, (10.0, 10.4), "MMC", 0.2),
    ("hole", 5.1, (10.0, 10.4), "LMC", 0.2),
    ("shaft", 4.95, (9.8, 10.0), "MMC", 0.1),
    ("shaft", 4.95, (9.8, 10.0), "LMC", 0.1),
    ("hole", 4.95, (10.0, 10.4), "MMC", -0.1),          # undersize hole: fails
])
def test_position_material_bonus(feature, r, limits, material, bonus):
    f = frame(np.eye(3), np.zeros(3))
    P = C.cylinder(r, 0.0, 40.0, center=(50.1, 30.0))
    ch = position(P, 0.15, f, nominal=(-50.0, 30.0, 0.0), feature=feature,
                  material=material, size_limits=limits)
    assert ch.measured == pytest.approx(0.2, abs=1e-9)
    assert ch.tolerance["bonus"] == pytest.approx(bonus, abs=1e-9)
    assert ch.tolerance["total"] == pytest.approx(0.15 + max(bonus, 0), abs=1e-9)
    assert ch.passed == (bonus >= 0)
    assert ch.details["size_ok"] == (bonus >= 0)
    assert not position(P, 0.15, f, nominal=(-50.0, 30.0, 0.0), feature=feature).passed


def test_mmc_bonus_arithmetic():
    assert mmc_bonus("hole", "MMC", 10.25, (10.0, 10.4)) == pytest.approx(0.25)
    assert mmc_bonus("shaft", "MMC", 9.9, (9.8, 10.0)) == pytest.approx(0.1)
    assert mmc_bonus("hole", "LMC", 10.25, (10.0, 10.4)) == pytest.approx(0.15)
    assert mmc_bonus("shaft", "LMC", 9.9, (9.8, 10.0)) == pytest.approx(0.1)


def test_position_point_sphere_circle():
    f = frame(np.eye(3), np.zeros(3))
    p = f.to_part([[-20.0, 10.0, 5.0]])[0] + [0.03, 0.04, 0.0]
    ch = position(p, 0.2, f, nominal=(-20.0, 10.0, 5.0), feature="point")
    assert ch.measured == pytest.approx(0.1, abs=1e-12)
    S, _ = C.octa_cube(4.0, 0.0)
    ch = position(S + p, 0.2, f, nominal=(-20.0, 10.0, 5.0), feature="sphere")
    assert ch.measured == pytest.approx(0.1, abs=1e-9)
    ring = C.cylinder(3.0, 5.0, 5.0, n_z=1, center=(20.03, 10.04))
    ring[:, 2] = -ring[:, 2]
    ch = position(ring, 0.2, f, nominal=(-20.0, 10.0, 99.0), feature="circle")
    assert ch.measured == pytest.approx(0.1, abs=1e-9)


@settings(deadline=None, max_examples=25)
@given(seed=st.integers(0, 10_000), dx=st.floats(-0.1, 0.1), dy=st.floats(-0.1, 0.1))
def test_position_invariant(seed, dx, dy):
    R, t = C.pose(seed, 1e3)
    f = frame(R, t)
    P = C.cylinder(5.0, 0.0, 40.0, center=(50 + dx, 30 + dy))
    P = P[np.random.default_rng(seed).permutation(len(P))]
    ch = position(C.place(P, R, t), 0.1, f, nominal=(-50.0, 30.0, 0.0))
    assert ch.measured == pytest.approx(2 * math.hypot(dx, dy), abs=1e-9)


@pytest.mark.parametrize("call, field, text", [
    (lambda f, P: parallelism(P, 0.1, f, "D"), "datum", "not defined"),
    (lambda f, P: parallelism(P, 0.0, f, "A"), "tol", "> 0"),
    (lambda f, P: parallelism(P, 0.1, None, "A"), "frame", "DatumFrame"),
    (lambda f, P: angularity(P, 0.1, f, 120.0, "A"), "angle", "[0, 90]"),
    (lambda f, P: parallelism(P, 0.1, f, "A", feature="cone"), "feature", "expected"),
    (lambda f, P: position(P, 0.1, f, (0, 0, 0), material="MMC"), "size_limits",
     "needs size_limits"),
    (lambda f, P: position(P, (0.1, 0.1), f, (0, 0, 0), axis=(1, 0, 0)), "axis",
     "rectangular"),
    (lambda f, P: position(P, 0.1, f, (0, 0, 0), feature="circle", material="MMC",
                           size_limits=(1, 2)), "material", "hole or a shaft"),
    (lambda f, P: position(P[:3], 0.1, f, (0, 0, 0)), "points", "at least 5"),
    (lambda f, P: position(P, 0.1, f, (0, 0, np.nan)), "nominal", "non-finite"),
])
def test_errors(call, field, text):
    f = frame(np.eye(3), np.zeros(3))
    P = C.cylinder(5.0, 0.0, 40.0, center=(50.0, 30.0))
    with pytest.raises(InvalidInputError) as e:
        call(f, P)
    assert e.value.field == field and text in str(e.value)
