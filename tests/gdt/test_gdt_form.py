"""Form characteristics on constructed data with known minimum zones."""

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
from geomkit.gdt import (circularity, cylindricity, flatness, sphericity,  # noqa: E402
                         straightness)

H = 0.01


def flat_plate(h=H):
    """Grid z = 0, corners +h, centre -h: minimum-zone flatness 2h (3-1 contacts)."""
    u, v = C.grid(5, 5, 20.0, 20.0)
    P = np.column_stack([u, v, np.zeros_like(u)])
    P[[0, 4, 20, 24], 2] = h
    P[12, 2] = -h
    return P


@pytest.mark.parametrize("seed", range(3))
def test_flatness_planted(seed):
    R, t = C.pose(seed, 1e3)
    P = C.place(flat_plate(), R, t)
    ch = flatness(P, 0.03)
    assert ch.measured == pytest.approx(2 * H, abs=1e-12)
    assert ch.passed and set(ch.deciding.tolist()) == {0, 4, 20, 24, 12}
    assert not flatness(P, 0.019).passed
    assert flatness(P, 1.0, method="lsq").measured >= ch.measured - 1e-12
    assert ch.tolerance == {"zone": 0.03, "method": "minzone"}
    json.dumps(ch.to_dict())


def test_straightness_3d_diametral_pairs():
    z = np.linspace(0, 50, 11)
    P = np.column_stack([np.zeros_like(z), np.zeros_like(z), z])
    P = np.vstack([P, [[H, 0, 0], [-H, 0, 0], [0, H, 50], [0, -H, 50]]])
    R, t = C.pose(4, 1e3)
    ch = straightness(C.place(P, R, t), 0.05)
    assert ch.measured == pytest.approx(2 * H, abs=1e-11)
    assert ch.details["zone_shape"] == "cylinder"


@pytest.mark.parametrize("seed", range(4))
def test_straightness_line_elements_vs_brute_force(seed):
    rng = np.random.default_rng(seed)
    x = rng.uniform(0, 40, 12)
    Q = np.column_stack([x, 0.01 * rng.normal(size=12)])
    R, t = C.pose(seed, 1e3)
    P = C.place(np.column_stack([Q, np.zeros(12)]), R, t)
    ch = straightness(P, 0.1, normal=R @ [0, 0, 1.0])
    assert ch.measured == pytest.approx(C.brute_width_2d(Q), rel=1e-9, abs=1e-12)
    lsq = straightness(P, 0.1, normal=R @ [0, 0, 1.0], method="lsq")
    assert lsq.measured >= ch.measured - 1e-12


@pytest.mark.parametrize("with_normal", [False, True])
def test_circularity_alternating(with_normal):
    P = C.cylinder(7.0, 0.0, 0.0, n_theta=16, n_z=1, dev=C.alternating(H, 8))
    R, t = C.pose(2, 1e3)
    ch = circularity(C.place(P, R, t), 0.05, normal=R @ [0, 0, 1.0] if with_normal
                     else None)
    assert ch.measured == pytest.approx(2 * H, abs=1e-12)


def test_circularity_section_normal_projects():
    P = C.cylinder(7.0, 0.0, 0.0, n_theta=16, n_z=1, dev=C.alternating(H, 8))
    P[::3, 2] += 0.5                     # out-of-plane scatter is projected away
    ch = circularity(P, 0.05, normal=(0, 0, 1))
    assert ch.measured == pytest.approx(2 * H, abs=1e-12)
    assert ch.details["out_of_plane"] == pytest.approx(0.5)


def test_cylindricity_alternating_rings():
    P = C.cylinder(6.0, 0.0, 30.0, n_theta=8, n_z=3, dev=C.alternating(H, 4))
    R, t = C.pose(5, 1e3)
    ch = cylindricity(C.place(P, R, t), 0.021)
    assert ch.measured == pytest.approx(2 * H, abs=1e-11) and ch.passed


def test_sphericity_octa_cube():
    P, _ = C.octa_cube(9.0, H)
    R, t = C.pose(6, 1e3)
    ch = sphericity(C.place(P, R, t), 0.019)
    assert ch.measured == pytest.approx(2 * H, abs=1e-11) and not ch.passed


@settings(deadline=None, max_examples=25)
@given(seed=st.integers(0, 10_000))
def test_flatness_invariant_rigid_motion_and_order(seed):
    rng = np.random.default_rng(seed)
    P = np.column_stack([rng.uniform(0, 20, (30, 2)), 0.01 * rng.normal(size=30)])
    a = flatness(P, 1.0)
    R, t = C.pose(seed, 1e3)
    perm = rng.permutation(30)
    b = flatness(C.place(P[perm], R, t), 1.0)
    assert b.measured == pytest.approx(a.measured, rel=1e-8, abs=1e-12)
    assert set(perm[b.deciding].tolist()) == set(a.deciding.tolist())


@pytest.mark.parametrize("call, field, text", [
    (lambda: flatness(flat_plate(), 0.0), "tol", "> 0"),
    (lambda: flatness(flat_plate(), float("nan")), "tol", "finite"),
    (lambda: flatness(flat_plate()[:2], 0.1), "points", "at least 3"),
    (lambda: flatness(np.vstack([flat_plate(), [0, np.inf, 0]]), 0.1), "points",
     "non-finite"),
    (lambda: flatness(flat_plate(), 0.1, method="maxinscribed"), "method", "expected"),
    (lambda: sphericity(np.zeros((3, 3)), 0.1), "points", "at least 4"),
    (lambda: straightness(flat_plate(), 0.1, normal=(0, 0, 0)), "normal", "non-zero"),
])
def test_errors(call, field, text):
    with pytest.raises(InvalidInputError) as e:
        call()
    assert e.value.field == field and text in str(e.value)
