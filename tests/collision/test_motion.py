"""First contact and probe paths (geomkit.collision.motion) against analytic truths, an
independent conservative-advancement oracle on min_distance, and python-fcl."""

import numpy as np
import pytest
import trimesh

from geomkit.collision.collide import Body, collide, min_distance
from geomkit.errors import InvalidInputError
from geomkit.collision.motion import first_contact, probe_path

from helpers.poses import pose

KINDS = ["obb", "aabb", "kdop14"]


def _rot(seed):
    from scipy.spatial.transform import Rotation
    return Rotation.random(random_state=seed).as_matrix()


def _box_toi(ca, ha, cb, hb, w, t_max):
    """Exact first contact of two axis-aligned boxes (centres, half sizes), B moving
    with w: the latest per-axis entry time if before the earliest exit."""
    t0, t1 = 0.0, t_max
    for k in range(3):
        D = cb[k] - ca[k]
        r = ha[k] + hb[k]
        if w[k] == 0:
            if abs(D) > r:
                return np.inf
            continue
        a, b = (-r - D) / w[k], (r - D) / w[k]
        t0, t1 = max(t0, min(a, b)), min(t1, max(a, b))
    return t0 if t0 <= t1 else np.inf


@pytest.mark.parametrize("bv", KINDS)
def test_boxes_axis_and_diagonal(bv):
    a = Body(trimesh.creation.box((1, 1, 1)), bv=bv)
    b = Body(trimesh.creation.box((2, 0.5, 1)), bv=bv)
    fc = first_contact(a, pose(), (0, 0, 0), b, pose((3, 0, 0)), (-0.5, 0, 0), 10.0)
    assert fc.hit and abs(fc.time - 3.0) <= 1e-12
    assert abs(fc.point[0] - 0.5) <= 1e-12
    rng = np.random.default_rng(1)
    for _ in range(25):
        cb = rng.uniform(-4, 4, 3)
        va, vb = rng.uniform(-1, 1, 3), rng.uniform(-1, 1, 3) - 0.3 * cb
        ca = rng.uniform(-0.5, 0.5, 3)
        exact = _box_toi(ca, [0.5] * 3, cb, [1, 0.25, 0.5], vb - va, 20.0)
        if exact == 0.0:
            continue
        fc = first_contact(a, pose(ca), va, b, pose(cb), vb, 20.0)
        if np.isinf(exact):
            assert not fc.hit
        else:
            assert fc.hit and abs(fc.time - exact) <= 1e-9, (ca, cb, va, vb, exact)
            assert fc.time_error == 0.0


def test_sphere_against_plane_vertex_hits():
    s = trimesh.creation.icosphere(2, 1.0)
    plane = Body(trimesh.creation.box((40, 40, 1)))       # top face at z = 0.5
    for seed in range(4):
        R = _rot(seed)
        body = Body(s, bv="obb")
        P = pose((0.3, -0.2, 3.0), R)
        v = np.array([0.2, -0.1, -0.7]) * (seed + 1)
        zmin = ((s.vertices @ R.T)[:, 2] + 3.0).min()
        exact = (zmin - 0.5) / -v[2]
        fc = first_contact(plane, pose(), (0, 0, 0), body, P, v, 100.0)
        assert fc.hit and abs(fc.time - exact) <= 1e-9
        assert abs(fc.point[2] - 0.5) <= 1e-9
        # the plane moving up instead gives the same time
        fc2 = first_contact(plane, pose(), -v, body, P, (0, 0, 0), 100.0)
        assert abs(fc2.time - exact) <= 1e-9


def _ca_oracle(a, Pa, va, b, Pb, vb):
    """Conservative advancement on min_distance (independent of the ray casts)."""
    w = np.linalg.norm(np.asarray(vb) - va)
    t = 0.0
    for _ in range(2000):
        Qa, Qb = Pa.copy(), Pb.copy()
        Qa[:3, 3] += t * np.asarray(va)
        Qb[:3, 3] += t * np.asarray(vb)
        d = min_distance(a, Qa, b, Qb).distance
        if d < 1e-13:
            return t
        t += d / w
    raise AssertionError("no convergence")


@pytest.mark.parametrize("bv", ["obb", "kdop14"])
def test_sphere_against_sphere(bv):
    s = trimesh.creation.icosphere(2, 1.0)
    a, b = Body(s, bv=bv), Body(s, bv=bv)
    for seed in range(3):
        Pa, Pb = pose((0, 0, 0), _rot(seed)), pose((6, 0.4 * seed, -0.3), _rot(seed + 10))
        va, vb = np.array([0.5, 0, 0]), np.array([-1.0, 0.05, 0.02])
        fc = first_contact(a, Pa, va, b, Pb, vb, 10.0)
        oracle = _ca_oracle(a, Pa, va, b, Pb, vb)
        assert fc.hit and abs(fc.time - oracle) <= 1e-9
        # exact spheres touch no later (the mesh is inside its sphere)
        w = vb - va
        c = Pb[:3, 3]
        qa, qb, qc = w @ w, 2 * c @ w, c @ c - 4.0
        t_sphere = (-qb - np.sqrt(qb * qb - 4 * qa * qc)) / (2 * qa)
        assert t_sphere - 1e-12 <= fc.time <= t_sphere + 0.2
        # contact: touching at time, apart just before
        Qa, Qb = Pa.copy(), Pb.copy()
        Qa[:3, 3] += fc.time * va
        Qb[:3, 3] += fc.time * vb
        assert min_distance(a, Qa, b, Qb).distance <= 1e-9
        Qa[:3, 3] -= 1e-6 * va
        Qb[:3, 3] -= 1e-6 * vb
        assert not collide(a, Qa, b, Qb).colliding


def test_python_fcl_naive_agrees_within_its_resolution():
    fcl = pytest.importorskip("fcl")
    s = trimesh.creation.icosphere(2, 1.0)
    a, b = Body(s), Body(s)

    def obj(t):
        m = fcl.BVHModel()
        m.beginModel(len(s.vertices), len(s.faces))
        m.addSubModel(s.vertices, s.faces)
        m.endModel()
        return fcl.CollisionObject(m, fcl.Transform(np.eye(3), np.array(t, float)))

    n = 2001
    for y in (0.0, 0.7, 1.5):
        req = fcl.ContinuousCollisionRequest(num_max_iterations=n, ccd_motion_type=0,
                                             ccd_solver_type=0)
        res = fcl.ContinuousCollisionResult()
        fcl.continuousCollide(obj([0, 0, 0]), fcl.Transform(), obj([5, y, 0]),
                              fcl.Transform(np.eye(3), np.array([-5.0, y, 0])), req, res)
        fc = first_contact(a, pose(), (0, 0, 0), b, pose((5, y, 0)), (-10.0, 0, 0), 1.0)
        assert res.is_collide and fc.hit
        # naive CCD reports the first colliding sample of n: within 1 / (n - 1) after
        assert 0.0 <= res.time_of_contact - fc.time <= 1.0 / (n - 1) + 1e-12


def test_backoff_within_step_and_no_hit_and_initial_contact():
    a = Body(trimesh.creation.box((1, 1, 1)))
    b = Body(trimesh.creation.icosphere(1, 0.5))
    fe = first_contact(a, pose(), (0, 0, 0), b, pose((3, 0.1, 0)), (-0.37, 0, 0), 20.0)
    fb = first_contact(a, pose(), (0, 0, 0), b, pose((3, 0.1, 0)), (-0.37, 0, 0), 20.0,
                       method="backoff", step=0.02)
    assert fb.method == "backoff" and fb.time_error == 0.02
    assert 0.0 <= fb.time - fe.time <= 0.02 + 1e-12
    away = first_contact(a, pose(), (0, 0, 0), b, pose((3, 0, 0)), (1, 0, 0), 20.0)
    assert not away.hit and np.isinf(away.time) and away.triangle_a == -1
    short = first_contact(a, pose(), (0, 0, 0), b, pose((3, 0, 0)), (-0.37, 0, 0), 1.0)
    assert not short.hit
    already = first_contact(a, pose(), (0, 0, 0), b, pose((0.8, 0, 0)), (1, 0, 0), 1.0)
    assert already.hit and already.time == 0.0


def test_first_contact_invalid_input():
    a = Body(trimesh.creation.box((1, 1, 1)))
    with pytest.raises(InvalidInputError, match="velocity_b"):
        first_contact(a, pose(), (0, 0, 0), a, pose((3, 0, 0)), (1, 0), 1.0)
    with pytest.raises(InvalidInputError, match="t_max"):
        first_contact(a, pose(), (0, 0, 0), a, pose((3, 0, 0)), (1, 0, 0), -1.0)
    with pytest.raises(InvalidInputError, match="method"):
        first_contact(a, pose(), (0, 0, 0), a, pose((3, 0, 0)), (1, 0, 0), 1.0, method="x")
    with pytest.raises(InvalidInputError, match="pose_b"):
        first_contact(a, pose(), (0, 0, 0), a, np.ones((4, 4)), (1, 0, 0), 1.0)


def test_probe_path_clearance_and_first_contact():
    probe = Body(trimesh.creation.icosphere(2, 0.5))
    part = Body(trimesh.creation.box((2, 2, 2)))            # faces at +-1
    pts = np.array([[-3, 0, 2.0], [3, 0, 2.0], [3, 0, 1.7], [0, 0, 1.7], [0, 0, 0.0]])
    r = probe_path(probe, pts, part, margin=0.25, tol=1e-6)
    vz = (probe.vertices[:, 2]).min()                       # lowest vertex, -0.5
    assert r.clearance.shape == (4,)
    assert abs(r.clearance[0] - (2.0 + vz - 1.0)) <= 1e-12
    assert abs(r.clearance[2] - (1.7 + vz - 1.0)) <= 1e-12
    assert r.clearance[3] == 0.0 and not r.passed[3] and r.passed[0]
    assert not r.passed[2]     # 0.2 < margin 0.25
    # first contact on segment 3: the lowest vertex reaches z = 1
    assert abs(r.first_contact[3] - (1.7 + vz - 1.0) / 1.7) <= 1e-9
    assert np.isnan(r.first_contact[0]) and not r.ok
    # segment 1 descends: its minimum is at the end
    assert abs(r.parameter[1] - 1.0) <= 1e-9
    np.testing.assert_array_equal(r.lower_bound, r.clearance)   # exact on translations
    # against dense sampling (an upper bound of the minimum)
    for k in range(3):
        ds = [min_distance(probe, pose(pts[k] + s * (pts[k + 1] - pts[k])), part,
                           np.eye(4)).distance for s in np.linspace(0, 1, 41)]
        assert r.clearance[k] <= min(ds) + 1e-12


def test_probe_path_with_rotation_is_certified():
    probe = Body(trimesh.creation.box((2.0, 0.2, 0.2)))
    part = Body(trimesh.creation.box((1, 1, 1)))
    from scipy.spatial.transform import Rotation
    P = np.tile(np.eye(4), (2, 1, 1))
    P[:, :3, 3] = [[0, 0, 2.0], [0.5, 0, 1.9]]
    P[1, :3, :3] = Rotation.from_rotvec([0, 1.2, 0]).as_matrix()
    tol = 1e-4
    r = probe_path(probe, P, part, tol=tol)
    # dense sampling of the same interpolation is never below clearance - tol
    from scipy.spatial.transform import Rotation
    rv = Rotation.from_matrix(P[0, :3, :3].T @ P[1, :3, :3]).as_rotvec()
    ds = []
    for s in np.linspace(0, 1, 801):
        Q = np.eye(4)
        Q[:3, :3] = Rotation.from_rotvec(s * rv).as_matrix()
        Q[:3, 3] = P[0, :3, 3] + s * (P[1, :3, 3] - P[0, :3, 3])
        ds.append(min_distance(probe, Q, part, np.eye(4)).distance)
    assert r.clearance[0] - r.lower_bound[0] <= tol
    assert min(ds) >= r.lower_bound[0] - 1e-12
    assert r.clearance[0] <= min(ds) + tol


def test_probe_path_invalid_input():
    b = Body(trimesh.creation.box((1, 1, 1)))
    with pytest.raises(InvalidInputError, match="poses"):
        probe_path(b, np.zeros((1, 3)), b)
    with pytest.raises(InvalidInputError, match="margin"):
        probe_path(b, np.zeros((2, 3)) + [[0, 0, 5], [1, 0, 5]], b, margin=-1)


from hypothesis import given, settings, strategies as st  # noqa: E402

_BALL = trimesh.creation.icosphere(1, 0.7)
_BOX = trimesh.creation.box((1.0, 0.6, 0.8))


@settings(max_examples=25, deadline=None)
@given(st.lists(st.floats(-3, 3), min_size=9, max_size=9), st.integers(0, 1000))
def test_first_contact_symmetry_and_rigid_invariance(v, seed):
    a, b = Body(_BOX), Body(_BALL)
    Pa, Pb = pose(v[0:3], _rot(seed)), pose(np.array(v[3:6]) + [4, 0, 0], _rot(seed + 1))
    va, vb = np.zeros(3), np.array(v[6:9]) - [2, 0, 0]
    f = first_contact(a, Pa, va, b, Pb, vb, 5.0)
    g = first_contact(b, Pb, vb, a, Pa, va, 5.0)        # swapped bodies
    assert f.hit == g.hit
    if f.hit:
        assert abs(f.time - g.time) <= 1e-9
    # a common rigid motion of the world and a common velocity change nothing
    M = pose((1.5, -2.0, 0.3), _rot(seed + 2))
    u = np.array([0.3, -0.1, 0.2])
    h = first_contact(a, M @ Pa, M[:3, :3] @ va + u, b, M @ Pb, M[:3, :3] @ vb + u, 5.0)
    assert h.hit == f.hit
    if f.hit:
        assert abs(h.time - f.time) <= 1e-9
