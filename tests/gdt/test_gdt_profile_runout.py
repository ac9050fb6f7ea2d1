"""Profile against the exact NURBS samples (planted radial offsets on the sphere),
the rigid minimax fit, and runout against analytic values."""

from __future__ import annotations

import json
import math
import sys
from pathlib import Path

import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).resolve().parent))
import gdtcases as C  # noqa: E402

import geomkit  # noqa: E402
from geomkit.errors import DegenerateGeometryError, InvalidInputError  # noqa: E402
from geomkit.gdt import (Datum, circular_runout, datum_frame, profile_line,  # noqa: E402
                         profile_surface, total_runout)

SPHERE = geomkit.samples.load("sphere")          # radius 10 about the origin


def sphere_points(n, seed, h=0.02):
    rng = np.random.default_rng(seed)
    U = rng.normal(size=(n, 3))
    U /= np.linalg.norm(U, axis=1)[:, None]
    dev = rng.uniform(-h, h, n)
    dev[3], dev[7] = h * 1.3, -h * 0.9            # planted extremes
    return (10.0 + dev)[:, None] * U, dev


@pytest.fixture(scope="module")
def frame():
    u, v = C.grid(3, 3, 10.0, 10.0)
    return datum_frame(Datum("A", "plane", np.column_stack([u, v, np.zeros_like(u)]),
                             normal=(0, 0, -1)))


def test_profile_with_frame_exact_offsets(frame):
    P, dev = sphere_points(60, 0)
    ch = profile_surface(P, SPHERE, 0.06, frame=frame)
    assert np.abs(ch.details["deviation"] - dev).max() < 1e-9
    assert ch.measured == pytest.approx(2 * 0.026, abs=1e-9) and ch.passed
    assert ch.deciding.tolist() == [3] and ch.datums == ("A",)
    assert not profile_surface(P, SPHERE, 0.05, frame=frame).passed
    json.dumps(ch.to_dict())


@pytest.mark.parametrize("U, passed", [(0.03, True), (0.026 + 1e-9, True),
                                       (0.026 - 1e-9, False), (0.025, False),
                                       (0.045, False)])
def test_profile_unequal_zone(frame, U, passed):
    # zone [U - 0.06, U]; points in [-0.018, 0.026].  The planted extreme is bracketed
    # 1e-9 inside and outside the limit: exactly on it, the verdict is decided by the
    # projection's last bit (measured 0.06 + 9e-17 against 0.06 with one mesh, 0.06
    # with another)
    P, dev = sphere_points(60, 0)
    ch = profile_surface(P, SPHERE, 0.06, frame=frame, unequal=U)
    c = U - 0.03
    assert ch.measured == pytest.approx(2 * np.abs(dev - c).max(), abs=1e-9)
    assert ch.passed == passed
    assert ch.tolerance["limits"] == pytest.approx((U - 0.06, U))


def test_profile_best_fit_recovers_translation():
    h = 0.01
    P, _ = C.octa_cube(10.0, h)
    t = np.array([0.3, -0.2, 0.1])
    ch = profile_surface(P + t, SPHERE, 0.05)
    assert ch.details["best_fit"] is True
    assert ch.measured == pytest.approx(2 * h, abs=1e-9)
    moved = ch.details["points"]
    assert np.abs(moved.mean(axis=0) - P.mean(axis=0)).max() < 1e-7


@pytest.mark.parametrize("name", ["freeform_1", "torus"])
def test_profile_best_fit_undoes_rigid_motion(name):
    surfs = geomkit.samples.load(name)
    rng = np.random.default_rng(1)
    s = surfs[0]
    (u0, u1), (v0, v1) = s.domain
    uv = np.column_stack([rng.uniform(u0 + 0.1 * (u1 - u0), u1 - 0.1 * (u1 - u0), 80),
                          rng.uniform(v0 + 0.1 * (v1 - v0), v1 - 0.1 * (v1 - v0), 80)])
    X = s.evaluate(uv)
    N = s.normals(uv)
    dev = rng.uniform(-0.01, 0.01, 80)
    P = X + dev[:, None] * N
    base = profile_surface(P, surfs, 1.0, best_fit=False)
    assert np.abs(np.abs(base.details["deviation"]) - np.abs(dev)).max() < 1e-8
    R, _ = C.pose(2)
    ang = 2e-3
    from scipy.spatial.transform import Rotation
    Rm = Rotation.from_rotvec(ang * R[:, 0]).as_matrix()
    c = P.mean(axis=0)
    Pm = (P - c) @ Rm.T + c + [0.02, -0.01, 0.015]
    moved = profile_surface(Pm, surfs, 1.0, best_fit=False)
    fitted = profile_surface(Pm, surfs, 1.0)
    fit_base = profile_surface(P, surfs, 1.0)
    assert moved.measured > base.measured
    assert fitted.measured <= base.measured + 1e-9
    assert fitted.measured == pytest.approx(fit_base.measured, rel=1e-6, abs=1e-9)


def test_profile_line_section_of_sphere():
    rng = np.random.default_rng(3)
    th = np.linspace(0, 2 * np.pi, 40, endpoint=False)
    dev = rng.uniform(-0.01, 0.01, 40)
    dev[5] = 0.015
    z = 6.0
    r = 8.0                      # section circle radius at z = 6
    # points offset along the in-plane radial direction by dev_in
    P = np.column_stack([(r + dev) * np.cos(th), (r + dev) * np.sin(th), np.full(40, z)])
    ch = profile_line(P, SPHERE, ((0, 0, z), (0, 0, 1)), 0.04, best_fit=False)
    # 3-D distance over the in-plane share of the radial direction P/|P|
    rad = np.linalg.norm(P, axis=1)
    want = (rad - 10.0) * rad / np.hypot(P[:, 0], P[:, 1])
    assert np.abs(ch.details["deviation"] - want).max() < 1e-9
    # the in-plane distance to the section circle is dev (first order)
    assert np.abs(ch.details["deviation"] - dev).max() < 1e-5
    assert ch.details["inplane_share_min"] == pytest.approx(0.8, abs=1e-3)
    fitted = profile_line(P, SPHERE, ((0, 0, z), (0, 0, 1)), 0.04)
    assert fitted.measured <= ch.measured + 1e-12


def test_profile_errors(frame):
    P, _ = sphere_points(10, 1)
    with pytest.raises(InvalidInputError, match="tol"):
        profile_surface(P, SPHERE, 0.0)
    with pytest.raises(InvalidInputError, match=r"\[0, tol\]"):
        profile_surface(P, SPHERE, 0.1, unequal=0.2)
    with pytest.raises(InvalidInputError, match="DatumFrame"):
        profile_surface(P, SPHERE, 0.1, frame="A")
    ring = np.column_stack([np.cos(np.arange(8)), np.sin(np.arange(8)), np.full(8, 9.9999)])
    with pytest.raises(DegenerateGeometryError, match="tangent"):
        profile_line(ring * [0.1, 0.1, 1], SPHERE, ((0, 0, 9.9999), (0, 0, 1)), 0.1,
                     best_fit=False)
    with pytest.raises(InvalidInputError, match="point, normal"):
        profile_line(P, SPHERE, (0, 0, 1), 0.1)


def shaft_frame():
    return datum_frame(Datum("A", "cylinder", C.cylinder(8.0, 0.0, 40.0),
                             feature="external"))


def test_circular_runout_offset_cylinder():
    e = 0.02
    P = C.cylinder(5.0, 50.0, 80.0, n_theta=24, n_z=4, center=(e, 0.0))
    f = shaft_frame()
    ch = circular_runout(P, f, 0.05, width=5.0)
    assert ch.measured == pytest.approx(2 * e, abs=1e-12) and ch.passed
    assert len(ch.details["per_section"]) == 4
    tr = total_runout(P, f, 0.05)
    assert tr.measured == pytest.approx(2 * e, abs=1e-12)
    Q = P.copy()                                       # taper: last ring 0.01 larger
    Q[3::4, :2] = (Q[3::4, :2] - [e, 0]) * 5.01 / 5.0 + [e, 0]
    assert circular_runout(Q, f, 0.05, width=5.0).measured == pytest.approx(2 * e)
    assert total_runout(Q, f, 0.05).measured == pytest.approx(2 * e + 0.01)
    json.dumps(ch.to_dict())


def test_runout_tilted_cylinder_total_exceeds_circular():
    # axis through (0, 0, 50) tilted by a about y: centre offset z' tan(a) at height z'
    a, L = 1e-3, 30.0
    P = C.cylinder(5.0, 0.0, L, n_theta=24, n_z=4)
    c, s = math.cos(a), math.sin(a)
    P = P @ np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]]).T + [0, 0, 50.0]
    ids = np.repeat(np.arange(24)[:, None], 4, axis=1).T.ravel() * 0
    ids = np.tile(np.arange(4), 24)
    ch = circular_runout(P, ((0, 0, 0), (0, 0, 1)), 0.1, sections=ids)
    # the last ring: centre offset L sin(a); radial spread about the z axis
    V = P[ids == 3]
    r = np.hypot(V[:, 0], V[:, 1])
    assert ch.measured == pytest.approx(np.ptp(r), abs=1e-12)
    assert ch.measured == pytest.approx(2 * L * s, rel=1e-3)
    tr = total_runout(P, ((0, 0, 0), (0, 0, 1)), 0.1)
    r_all = np.hypot(P[:, 0], P[:, 1])
    assert tr.measured == pytest.approx(np.ptp(r_all), abs=1e-12)
    assert tr.measured >= ch.measured


def test_axial_runout_of_tilted_face():
    a = 2e-3
    rings = [np.column_stack([r * np.cos(t), r * np.sin(t), r * np.cos(t) * math.tan(a)])
             for r in (10.0, 20.0) for t in [np.linspace(0, 2 * np.pi, 16, endpoint=False)]]
    P = np.vstack(rings)
    ch = circular_runout(P, ((0, 0, 0), (0, 0, 1)), 0.1, width=5.0, direction="axial")
    assert ch.measured == pytest.approx(2 * 20.0 * math.tan(a), rel=1e-12)
    tr = total_runout(P, ((0, 0, 0), (0, 0, 1)), 0.1, direction="axial")
    assert tr.measured == pytest.approx(2 * 20.0 * math.tan(a), rel=1e-12)


def test_runout_errors():
    P = C.cylinder(5.0, 0.0, 10.0, n_theta=8, n_z=2)
    with pytest.raises(InvalidInputError, match="sections= .* or width="):
        circular_runout(P, ((0, 0, 0), (0, 0, 1)), 0.1)
    with pytest.raises(InvalidInputError, match="section 1 has 1 point"):
        ids = np.zeros(len(P), int)
        ids[0] = 1
        circular_runout(P, ((0, 0, 0), (0, 0, 1)), 0.1, sections=ids)
    with pytest.raises(InvalidInputError, match="direction"):
        total_runout(P, ((0, 0, 0), (0, 0, 1)), 0.1, direction="tangential")
    with pytest.raises(InvalidInputError, match="non-zero"):
        total_runout(P, ((0, 0, 0), (0, 0, 0)), 0.1)


def test_profile_free_dofs_float_only_those(frame):
    # a sphere profile to a plane datum A: the zone may slide in x and y (A leaves
    # them free), not along z
    P, _ = sphere_points(80, 3, h=0.0)
    t = np.array([0.4, -0.25, 0.0])
    ch = profile_surface(P + t, SPHERE, 0.06, frame=frame, free=frame.free)
    assert ch.details["free"] == frame.free
    assert ch.measured < 1e-9
    R, tr = ch.details["rotation"], ch.details["translation"]
    assert abs(tr[2]) < 1e-12 and abs(R[2, 2] - 1.0) < 1e-12   # only tx, ty, rz moved
    lifted = profile_surface(P + [0.0, 0.0, 0.01], SPHERE, 0.06, frame=frame,
                             free=frame.free)
    assert lifted.measured > ch.measured + 0.005      # tz is held by datum A
    with pytest.raises(InvalidInputError, match="degree of freedom"):
        profile_surface(P, SPHERE, 0.06, frame=frame, free=("tq",))


def test_profile_surface_of_keeps_each_point_on_its_face():
    # two parallel faces: points given their face are measured to it, not to the
    # nearest face
    a, b = geomkit.samples.load("offset_planes")
    uv = np.array([[0.5, 0.5]])
    pa, pb = a.evaluate(uv), b.evaluate(uv)
    P = np.vstack([pa, pb])
    ch = profile_surface(P, [a, b], 0.01, best_fit=False, surface_of=[0, 1])
    assert ch.measured < 1e-9
    # given the wrong faces the distances are those to the other face
    wrong = profile_surface(P, [a, b], 0.01, best_fit=False, surface_of=[1, 0])
    assert wrong.measured > 1e-6
    with pytest.raises(InvalidInputError, match="surface"):
        profile_surface(P, [a, b], 0.01, best_fit=False, surface_of=[0, 2])
    with pytest.raises(InvalidInputError):
        profile_surface(P, [a, b], 0.01, best_fit=False, surface_of=[0.5, 1.0])
