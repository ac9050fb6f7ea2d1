"""Datum reference frames: known frames of constructed parts, tangent-plane oracles,
rigid-motion / point-order invariance, error messages."""

from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings, strategies as st

sys.path.insert(0, str(Path(__file__).resolve().parent))
import gdtcases as C  # noqa: E402

from geomkit.errors import InvalidInputError  # noqa: E402
from geomkit.gdt import Datum, align_to_cad, datum_frame, frame_from_axes  # noqa: E402


def box_frame(R, t, perm=None, low=0.3):
    A, B, Cc, axes = C.box_faces(low=low)
    if perm is not None:
        A, B, Cc = (X[np.random.default_rng(perm).permutation(len(X))] for X in (A, B, Cc))
    f = datum_frame(Datum("A", "plane", C.place(A, R, t), normal=R @ [0, 0, -1.0]),
                    Datum("B", "plane", C.place(B, R, t), normal=R @ [-1.0, 0, 0]),
                    Datum("C", "plane", C.place(Cc, R, t), normal=R @ [0, -1.0, 0]))
    return f, axes


@pytest.mark.parametrize("seed", range(6))
def test_321_box_recovers_rigid_transform(seed):
    R, t = C.pose(seed)
    f, axes = box_frame(R, t)
    size = 100.0
    # part -> datum: q = axes @ R^T (p - t)
    assert np.abs(f.origin - t).max() < 1e-9 * size
    assert np.abs(f.axes - axes @ R.T).max() < 1e-12
    T = np.eye(4)
    T[:3, :3] = axes @ R.T
    T[:3, 3] = -axes @ R.T @ t
    assert np.abs(f.transform - T).max() < 1e-9 * size
    assert f.dof == {"A": ("tz", "rx", "ry"), "B": ("tx", "rz"), "C": ("ty",)}
    assert f.free == ()
    # the low points are 0.3 inside; every point on the material side
    for lab in "ABC":
        df = f.datum(lab)
        assert df.max_distance == pytest.approx(0.3, abs=1e-9)
    assert np.linalg.det(f.axes) == pytest.approx(1.0, abs=1e-14)
    json.dumps(f.to_dict())


def test_tangent_plane_touches_high_points_lsq_does_not():
    u, v = C.grid(5, 5, 10.0, 10.0)
    P = np.column_stack([u, v, np.zeros_like(u)])
    P[12, 2] = -0.5                                   # one low point, in the middle
    f = datum_frame(Datum("A", "plane", P, normal=(0, 0, 1)))
    a = f.datum("A")
    assert np.abs(a.direction - [0, 0, 1]).max() < 1e-14
    assert abs(a.point[2]) < 1e-14                   # touches the high points
    assert a.max_distance == pytest.approx(0.5, abs=1e-14)
    assert f.free == ("tx", "ty", "rz")
    g = datum_frame(Datum("A", "plane", P, method="lsq", normal=(0, 0, 1)))
    assert g.datum("A").point[2] == pytest.approx(-0.5 / 25, abs=1e-14)


@pytest.mark.parametrize("seed", range(4))
def test_tangent_plane_against_brute_force(seed):
    rng = np.random.default_rng(seed)
    xy = rng.uniform(0, 10, (9, 2))
    P = np.column_stack([xy, -rng.uniform(0, 0.05, 9)])
    R, t = C.pose(seed + 10)
    f = datum_frame(Datum("A", "plane", C.place(P, R, t), normal=R @ [0, 0, 1]))
    a = f.datum("A")
    want = C.brute_tangent_width(P, np.array([0, 0, 1.0]))
    assert a.max_distance == pytest.approx(want, rel=1e-9, abs=1e-12)
    s = C.place(P, R, t) @ a.direction - a.direction @ a.point
    assert s.max() <= 1e-10 and s.max() >= -1e-10    # tangent: touches, nothing outside


@pytest.mark.parametrize("seed", range(4))
def test_secondary_plane_constrained_against_brute_force(seed):
    rng = np.random.default_rng(seed)
    A, B, Cc, _ = C.box_faces()
    Bn = np.column_stack([-rng.uniform(0, 0.05, 10), rng.uniform(0, 60, 10),
                          rng.uniform(0, 40, 10)])       # into the material (+x)
    f = datum_frame(Datum("A", "plane", A, normal=(0, 0, -1)),
                    Datum("B", "plane", Bn, normal=(-1, 0, 0)))
    b = f.datum("B")
    assert abs(b.direction @ f.datum("A").direction) < 1e-15
    want = C.brute_width_2d(Bn[:, :2])               # projected on the plane of A
    assert b.max_distance == pytest.approx(want, rel=1e-9, abs=1e-12)
    assert f.free == ("ty",)


@pytest.mark.parametrize("seed", range(3))
def test_plane_hole_plane(seed):
    R, t = C.pose(seed)
    u, v = C.grid(5, 5, 80.0, 80.0)
    A = np.column_stack([u, v, np.zeros_like(u)])    # top face, outward +z
    hole = C.cylinder(5.0, -20.0, -2.0, center=(30.0, 40.0))
    Cf = np.column_stack([np.linspace(5, 75, 6), np.zeros(6), np.linspace(-15, -3, 6)])
    Cf = np.vstack([Cf, [40.0, 0.2, -10.0]])
    f = datum_frame(Datum("A", "plane", C.place(A, R, t), normal=R @ [0, 0, 1]),
                    Datum("B", "cylinder", C.place(hole, R, t), feature="internal"),
                    Datum("C", "plane", C.place(Cf, R, t), normal=R @ [0, -1.0, 0]))
    assert np.abs(f.origin - C.place([[30.0, 40.0, 0.0]], R, t)[0]).max() < 1e-9 * 100
    assert np.abs(f.axes - np.array([[0, -1.0, 0], [1.0, 0, 0], [0, 0, 1.0]]) @ R.T
                  ).max() < 1e-12
    assert f.datum("B").size == pytest.approx(10.0, abs=1e-9)
    assert f.dof == {"A": ("tz", "rx", "ry"), "B": ("tx", "ty"), "C": ("rz",)}
    assert f.free == ()


def test_shaft_shoulder_and_clocking_hole():
    shaft = C.cylinder(8.0, 0.0, 30.0)
    shoulder = np.column_stack([12 * np.cos(np.arange(8)), 12 * np.sin(np.arange(8)),
                                np.zeros(8)])
    pin = C.cylinder(2.0, -10.0, -1.0, center=(0.0, 11.0))
    R, t = C.pose(3)
    f = datum_frame(Datum("A", "cylinder", C.place(shaft, R, t), feature="external",
                          axis=R @ [0, 0, 1.0]),
                    Datum("B", "plane", C.place(shoulder, R, t), normal=R @ [0, 0, -1.0]),
                    Datum("C", "cylinder", C.place(pin, R, t), feature="internal"))
    assert np.abs(f.origin - t).max() < 1e-9 * 30
    assert np.abs(f.axes[2] - R @ [0, 0, 1.0]).max() < 1e-12
    assert np.abs(f.axes[0] - R @ [0, 1.0, 0]).max() < 1e-9     # x toward the pin
    assert f.datum("A").size == pytest.approx(16.0, abs=1e-9)
    assert f.dof == {"A": ("tx", "ty", "rx", "ry"), "B": ("tz",), "C": ("rz",)}
    g = datum_frame(Datum("A", "cylinder", C.place(shaft, R, t), feature="external"))
    assert g.free == ("tz", "rz")


@settings(deadline=None, max_examples=25)
@given(seed=st.integers(0, 10_000), perm=st.integers(0, 10_000))
def test_frame_invariant_under_rigid_motion_and_order(seed, perm):
    f0, _ = box_frame(np.eye(3), np.zeros(3))
    R, t = C.pose(seed, offset=1e3)
    f1, _ = box_frame(R, t, perm=perm)
    # the same datum coordinates for the same physical points
    P = np.random.default_rng(seed).uniform(-50, 150, (5, 3))
    assert np.abs(f1.to_datum(C.place(P, R, t)) - f0.to_datum(P)).max() < 1e-9 * 100
    assert np.abs(align_to_cad(C.place(P, R, t), f1) - f0.to_datum(P)).max() < 1e-9 * 100


def test_align_to_cad_with_nominal_frame():
    f, axes = box_frame(*C.pose(1))
    nom = frame_from_axes((10.0, 20.0, 30.0), z=(0, 0, -1), x=(-1, 0, 0))
    A, _, _, _ = C.box_faces()
    R, t = C.pose(1)
    got = align_to_cad(C.place(A, R, t), f, nom)
    assert np.abs(got - (A + [10.0, 20.0, 30.0])).max() < 1e-9 * 100


def plate():
    u, v = C.grid(4, 4, 10.0, 10.0)
    return np.column_stack([u, v, np.zeros_like(u)])


@pytest.mark.parametrize("make, field, text", [
    (lambda: datum_frame(Datum("A", "plane", plate(), normal=(0, 0, 1)),
                         Datum("B", "plane", plate() + [0, 0, 5.0], normal=(0, 0, 1))),
     "datum B.normal", "perpendicular"),
    (lambda: datum_frame(Datum("A", "plane", plate(), normal=(0, 0, 1)), None,
                         Datum("C", "plane", plate(), normal=(1, 0, 0))),
     "tertiary", "needs a secondary"),
    (lambda: datum_frame(Datum("A", "plane", plate(), normal=(0, 0, 1)),
                         Datum("A", "plane", plate(), normal=(1, 0, 0))),
     "label", "must differ"),
    (lambda: datum_frame(Datum("A", "plane", plate())), "datum A.normal", "outward"),
    (lambda: datum_frame(Datum("A", "cone", plate())), "datum A.kind", "expected one"),
    (lambda: datum_frame(Datum("A", "cylinder", C.cylinder(1, 0, 1))), "feature",
     "internal"),
    (lambda: datum_frame(Datum("A", "plane", plate()[:2], normal=(0, 0, 1))),
     "datum A.points", "at least 3"),
    (lambda: datum_frame(Datum("A", "plane", np.vstack([plate(), [np.nan, 0, 0]]),
                               normal=(0, 0, 1))), "datum A.points", "non-finite"),
    (lambda: datum_frame(Datum("A", "sphere", C.octa_cube(5, 0)[0], method="lsq"),
                         Datum("B", "plane", plate(), normal=(0, 0, 1))),
     "secondary", "unsupported datum combination"),
    (lambda: datum_frame(Datum("A", "plane", plate(), normal=(0, 0, 1))).datum("D"),
     "datum", "not defined"),
    (lambda: datum_frame(Datum("A", "plane", plate(), normal=(0, 0, 0))),
     "datum A.normal", "non-zero"),
    (lambda: datum_frame(Datum("A", "plane", plate(), method="maxinscribed",
                               normal=(0, 0, 1))), "datum A.method", "expected one"),
])
def test_errors(make, field, text):
    with pytest.raises(InvalidInputError) as e:
        make()
    assert e.value.field == field and text in str(e.value)
    assert "\n" not in str(e.value)
