"""Scene broad phase (sweep and prune) against brute force; groups, static bodies,
narrow phase and declared fits (false interference, Paper 4)."""

import numpy as np
import pytest
import trimesh

from geomkit.collision.collide import Body, collide, min_distance
from geomkit.errors import InvalidInputError
from geomkit.collision.scene import Scene, SweepAndPrune, fit_exclusions

from helpers.poses import pose


def _brute(lo, hi, group, static, margin=0.0):
    ov = np.ones((lo.shape[0], lo.shape[0]), dtype=bool)
    for a in range(3):
        ov &= (lo[:, None, a] - margin <= hi[None, :, a] + margin)
        ov &= (lo[None, :, a] - margin <= hi[:, None, a] + margin)
    ov &= group[:, None] != group[None, :]
    ov &= ~(static[:, None] & static[None, :])
    i, j = np.nonzero(np.triu(ov, 1))
    return np.column_stack([i, j])


def test_sap_equals_brute_force_2000_boxes_100_frames():
    rng = np.random.default_rng(7)
    n = 2000
    c = rng.uniform(0, 100, (n, 3))
    h = rng.uniform(0.2, 2.0, (n, 3))
    group = rng.integers(0, 1500, n)
    static = rng.random(n) < 0.3
    vel = rng.normal(0, 0.3, (n, 3)) * ~static[:, None]
    sap = SweepAndPrune(c - h, c + h, group, static)
    total = 0
    for frame in range(100):
        c = c + vel
        # some boxes touch exactly (closed intervals)
        c[:5] = c[5:10] + np.array([1, 0, 0]) * (h[:5, 0] + h[5:10, 0])[:, None]
        lo, hi = c - h, c + h
        sap.update(lo, hi)
        got = sap.pairs()
        want = _brute(lo, hi, group, static)
        np.testing.assert_array_equal(got, want)
        total += got.shape[0]
        if frame % 25 == 0:
            np.testing.assert_array_equal(sap.pairs(0.7), _brute(lo, hi, group, static, 0.7))
    assert total > 1000
    for a in range(3):       # still sorted
        v = sap.ep_val[a]
        assert np.all(v[1:] >= v[:-1])


def test_sap_incremental_sort_is_cheap_for_small_motions():
    rng = np.random.default_rng(3)
    c = rng.uniform(0, 100, (500, 3))
    h = np.full((500, 3), 0.5)
    sap = SweepAndPrune(c - h, c + h)
    c2 = c + rng.normal(0, 1e-3, c.shape)
    assert sap.update(c2 - h, c2 + h) < 50
    sap2 = SweepAndPrune(c - h, c + h)
    c3 = rng.uniform(0, 100, (500, 3))
    assert sap2.update(c3 - h, c3 + h) > 50_000


def test_scene_groups_static_and_narrow_phase():
    box = Body(trimesh.creation.box((1, 1, 1)))
    ball = Body(trimesh.creation.icosphere(1, 0.6))
    s = Scene()
    a = s.add(box, pose((0, 0, 0)), group=1)
    b = s.add(box, pose((0.9, 0, 0)), group=1)           # same assembly: never tested
    c = s.add(ball, pose((0, 0.95, 0)))                  # touches a
    d = s.add(box, pose((5, 0, 0)), static=True)
    e = s.add(box, pose((5.5, 0, 0)), static=True)       # static vs static: skipped
    assert s.pairs().tolist() == [[a, c], [b, c]]
    col = s.collisions()
    want = [[i, j] for i, j in s.pairs()
            if collide(s.bodies[i], s.poses[i], s.bodies[j], s.poses[j]).colliding]
    assert col.pairs.tolist() == want and col.candidates == 2
    s.update({c: pose((5.25, 1.2, 0))})                   # move the ball near d and e
    assert s.pairs().tolist() == []
    dist = s.min_distances(0.5)
    assert dist.pairs.tolist() == [[c, d], [c, e]]
    for (i, j), dd in zip(dist.pairs, dist.distance):
        ref = min_distance(s.bodies[i], s.poses[i], s.bodies[j], s.poses[j]).distance
        assert dd == ref and dd < 0.5
    s.update(s.poses)
    assert len(s) == 5 and d != e


def test_scene_invalid_input():
    s = Scene()
    with pytest.raises(InvalidInputError, match="body"):
        s.add("box")
    b = Body(trimesh.creation.box((1, 1, 1)))
    s.add(b)
    with pytest.raises(InvalidInputError, match="poses"):
        s.update(np.tile(np.eye(4), (3, 1, 1)))
    with pytest.raises(InvalidInputError, match="margin"):
        s.min_distances(-1.0)
    with pytest.raises(InvalidInputError, match="hi"):
        SweepAndPrune(np.ones((2, 3)), np.zeros((2, 3)))


# ----------------------------------------------------------- false interference
def tube(r_in, r_out, h, n, tags=(10, 11, 12, 13)):
    """A faceted tube (a hole in a collar): inner, outer, top, bottom faces tagged."""
    ang = 2 * np.pi * np.arange(n) / n
    ring = np.column_stack([np.cos(ang), np.sin(ang), np.zeros(n)])
    V = np.vstack([ring * r_in + [0, 0, -h / 2], ring * r_in + [0, 0, h / 2],
                   ring * r_out + [0, 0, -h / 2], ring * r_out + [0, 0, h / 2]])
    F, T = [], []
    for k in range(n):
        k1 = (k + 1) % n
        ib, it, ob, ot = k, n + k, 2 * n + k, 3 * n + k
        ib1, it1, ob1, ot1 = k1, n + k1, 2 * n + k1, 3 * n + k1
        F += [(ib, it1, it), (ib, ib1, it1)]
        T += [tags[0]] * 2
        F += [(ob, ot, ot1), (ob, ot1, ob1)]
        T += [tags[1]] * 2
        F += [(it, it1, ot1), (it, ot1, ot)]
        T += [tags[2]] * 2
        F += [(ib, ob1, ib1), (ib, ob, ob1)]
        T += [tags[3]] * 2
    return V, np.array(F), np.array(T)


def shaft_with_key(r, length, n, key=True):
    """A faceted shaft (side 1, caps 2, 3) rotated half a facet against the hole,
    plus a key block (tag 4) that really intrudes into the collar's top face."""
    m = trimesh.creation.cylinder(radius=r, height=length, sections=n)
    m.apply_transform(trimesh.transformations.rotation_matrix(np.pi / n, [0, 0, 1]))
    nz = m.face_normals[:, 2]
    tags = np.where(nz > 0.5, 2, np.where(nz < -0.5, 3, 1))
    V, F = m.vertices, m.faces
    if key:
        k = trimesh.creation.box((0.4, 0.4, 0.4))
        k.apply_translation([r + 0.3, 0, 0.55])     # collar top face at z = 0.5
        F = np.vstack([F, k.faces + len(V)])
        V = np.vstack([V, k.vertices])
        tags = np.concatenate([tags, np.full(len(k.faces), 4)])
    return V, F, tags


def test_false_interference_fit_excluded_real_interference_found():
    n = 24
    Vh, Fh, Th = tube(1.0, 2.0, 1.0, n)
    Vs, Fs, Ts = shaft_with_key(1.0, 3.0, n)
    s = Scene()
    i = s.add(Body((Vs, Fs), face_tags=Ts))
    j = s.add(Body((Vh, Fh), face_tags=Th))
    raw = s.collisions(all_pairs=True)
    tags = np.unique(raw.contacts[0].tags, axis=0).tolist()
    assert [1, 10] in tags          # faceting: shaft side vs hole (false interference)
    assert [4, 12] in tags          # the key in the collar's top face (real)
    s.declare_fit(i, j, shaft_faces=1, hole_faces=10, hole_adjacent=(12, 13))
    col = s.collisions()
    assert col.pairs.tolist() == [[0, 1]] and col.excluded > 0
    assert np.unique(col.contacts[0].tags, axis=0).tolist() == [[4, 12]]
    # without the key the fit is reported clean
    Vs2, Fs2, Ts2 = shaft_with_key(1.0, 3.0, n, key=False)
    s2 = Scene()
    i2 = s2.add(Body((Vs2, Fs2), face_tags=Ts2))
    j2 = s2.add(Body((Vh, Fh), face_tags=Th))
    assert s2.collisions().pairs.shape[0] == 1
    s2.declare_fit(i2, j2, 1, 10, hole_adjacent=(12, 13))
    assert s2.collisions().pairs.shape[0] == 0


def test_fit_exclusions_table():
    ex = fit_exclusions(1, 10, shaft_adjacent=(2,), hole_adjacent=(12,))
    assert ex.tolist() == [[1, 10], [1, 12], [2, 10]]


@pytest.mark.parametrize("bv", ["aabb", "obb", "kdop14"])
def test_coherent_pair_equals_collide_over_a_motion(bv):
    from geomkit.collision.scene import CoherentPair
    from scipy.spatial.transform import Rotation
    a = Body(trimesh.creation.icosphere(3, 1.0), bv=bv)
    b = Body(trimesh.creation.capsule(height=2.0, radius=0.5, count=[24, 24]), bv=bv)
    cp = CoherentPair(a, b)
    rng = np.random.default_rng(0)
    Pb = pose((1.6, 0, 0))
    sizes = []
    for k in range(60):
        Pb = Pb.copy()
        Pb[:3, 3] += [-0.01, 0.003, 0.002] if k < 40 else [0.02, 0, 0]
        Pb[:3, :3] = Rotation.from_rotvec(rng.normal(0, 0.01, 3)).as_matrix() @ Pb[:3, :3]
        got = cp.collide(np.eye(4), Pb)
        want = collide(a, np.eye(4), b, Pb)
        np.testing.assert_array_equal(got.pairs, want.pairs)
        assert got.colliding == want.colliding
        sizes.append(cp.front_size)
    assert max(sizes) > 1


def test_coherent_scene_matches_plain_scene():
    ball = Body(trimesh.creation.icosphere(2, 0.6))
    box = Body(trimesh.creation.box((1, 1, 1)))
    plain, coh = Scene(), Scene(coherent=True)
    for s in (plain, coh):
        s.add(box, pose((0, 0, 0)), static=True)
        s.add(ball, pose((1.2, 0, 0)))
        s.add(box, pose((3, 0, 0)), static=True)
    for k in range(30):
        P = {1: pose((1.2 + 0.03 * k, 0.01 * k, 0))}
        plain.update(P)
        coh.update(P)
        a, b = plain.collisions(all_pairs=True), coh.collisions()
        assert a.pairs.tolist() == b.pairs.tolist()
        for ca, cb in zip(a.contacts, b.contacts):
            np.testing.assert_array_equal(ca.pairs, cb.pairs)
