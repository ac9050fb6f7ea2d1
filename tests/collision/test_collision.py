"""Collision core (Papers 3 and 5) against brute force, coal, and invariants.

* brute force: every triangle pair through the exact kernels (collide pairs equal,
  min_distance equal within 1e-12 relative) for the three tree kinds;
* coal (independent library, skipped when absent): identical sets of intersecting
  triangle pairs on >= 1,000 random poses over pairs of tessellated shared cases
  and trimesh primitives, and the same distances;
* hypothesis: symmetry, invariance under a common rigid motion, collide <=>
  min_distance == 0;
* input validation: poses, meshes, mixed tree kinds.
"""

from __future__ import annotations

import pickle

import numpy as np
import pytest
import trimesh
from hypothesis import given
from hypothesis import strategies as st
from scipy.spatial.transform import Rotation

import geomkit
from geomkit._kernels.numba_ext.policy import jit
from geomkit._kernels.bvh_query import PLANE_SLACK, _prism_gap, _unit_normal
from geomkit._kernels.triangles import triangle_triangle_distance, triangles_intersect
from geomkit.collision.collide import Body, collide, collide_many, min_distance
from geomkit.errors import InvalidInputError

BVS = ("obb", "aabb", "kdop14")


# ---------------------------------------------------------------- meshes
_MESHES = {}


def mesh(name):
    """Small meshes of comparable size (~20 units): tessellated shared cases and
    trimesh primitives, as (vertices, faces)."""
    if name not in _MESHES:
        if name == "torus":
            m = geomkit.tessellate(geomkit.samples.load("torus"), 0.3)
            V, F = m.vertices * 0.4, m.faces
        elif name == "sphere":
            m = geomkit.tessellate(geomkit.samples.load("sphere"), 0.3)
            V, F = m.vertices, m.faces
        elif name == "freeform":
            m = geomkit.tessellate(geomkit.samples.load("freeform_1"), 0.5)
            V, F = m.vertices * 0.2, m.faces
        elif name == "box":
            t = trimesh.creation.box((12, 8, 5))
            V, F = t.vertices, t.faces
        elif name == "capsule":
            t = trimesh.creation.capsule(height=14, radius=4, count=[16, 16])
            V, F = t.vertices, t.faces
        elif name == "icosphere":
            t = trimesh.creation.icosphere(2, 7.0)
            V, F = t.vertices, t.faces
        V = np.ascontiguousarray(V - V.mean(axis=0), float)
        _MESHES[name] = (V, np.ascontiguousarray(F, np.int64))
    return _MESHES[name]


_BODIES = {}


def body(name, bv):
    if (name, bv) not in _BODIES:
        _BODIES[name, bv] = Body(mesh(name), bv=bv)
    return _BODIES[name, bv]


def random_poses(n, seed, spread=12.0):
    rng = np.random.default_rng(seed)
    P = np.tile(np.eye(4), (n, 1, 1))
    P[:, :3, :3] = Rotation.random(n, random_state=rng.integers(1 << 31)).as_matrix()
    P[:, :3, 3] = rng.uniform(-spread, spread, (n, 3))
    return P


def moved(V, P):
    return V @ P[:3, :3].T + P[:3, 3]


# ---------------------------------------------------------------- brute force
@jit
def _brute(VA, FA, VB, FB, want_pairs, out):
    ta = np.empty((3, 3))
    tb = np.empty((3, 3))
    p = np.empty(3)
    q = np.empty(3)
    best = np.inf
    n = 0
    for i in range(FA.shape[0]):
        for v in range(3):
            ta[v] = VA[FA[i, v]]
        for j in range(FB.shape[0]):
            for v in range(3):
                tb[v] = VB[FB[j, v]]
            if want_pairs:
                if triangles_intersect(ta, tb):
                    out[n, 0] = i
                    out[n, 1] = j
                    n += 1
            else:
                best = min(best, triangle_triangle_distance(ta, tb, p, q))
    return n, best


def brute_pairs(VA, FA, VB, FB):
    out = np.empty((FA.shape[0] * FB.shape[0], 2), np.int64)
    n, _ = _brute(VA, FA, VB, FB, True, out)
    return {tuple(x) for x in out[:n].tolist()}


def brute_distance(VA, FA, VB, FB):
    return _brute(VA, FA, VB, FB, False, np.empty((0, 2), np.int64))[1]


@pytest.mark.parametrize("bv", BVS)
def test_against_brute_force(bv):
    pairs = [("torus", "icosphere"), ("box", "capsule"), ("freeform", "sphere")]
    hits = 0
    for k, (na, nb) in enumerate(pairs):
        (VA, FA), (VB, FB) = mesh(na), mesh(nb)
        a, b = body(na, bv), body(nb, bv)
        Pa = random_poses(1, 100 + k, spread=2.0)[0]
        for Pb in random_poses(8, k, spread=15.0):
            WA, WB = moved(VA, Pa), moved(VB, Pb)
            ref = brute_pairs(WA, FA, WB, FB)
            c = collide(a, Pa, b, Pb)
            assert {tuple(x) for x in c.pairs.tolist()} == ref
            assert c.colliding == bool(ref)
            first = collide(a, Pa, b, Pb, all_pairs=False)
            assert first.colliding == bool(ref) and len(first.pairs) == int(bool(ref))
            assert {tuple(x) for x in first.pairs.tolist()} <= ref
            hits += bool(ref)
            d = min_distance(a, Pa, b, Pb)
            dref = brute_distance(WA, FA, WB, FB)
            assert abs(d.distance - dref) <= 1e-12 * max(dref, 1e-300) or d.distance == dref
            assert (d.distance == 0.0) == bool(ref)
            if d.distance > 0:
                assert abs(np.linalg.norm(d.point_a - d.point_b) - d.distance) <= 1e-9
                ta = WA[FA[d.triangle_a]]
                tb = WB[FB[d.triangle_b]]
                p, q = np.empty(3), np.empty(3)
                assert triangle_triangle_distance(ta, tb, p, q) == pytest.approx(d.distance,
                                                                                 rel=1e-9)
    assert 4 <= hits <= 20


# ---------------------------------------------------------------- coal
def _coal_model(coal, V, F):
    m = coal.BVHModelOBBRSS()
    m.beginModel(len(F), len(V))
    m.addVertices(np.asarray(V, float))
    m.addTriangles(np.asarray(F, np.int64))
    m.endModel()
    return m


def test_agrees_with_coal_on_1000_poses():
    coal = pytest.importorskip("coal")
    pairs = [("torus", "sphere"), ("freeform", "capsule"), ("box", "icosphere"),
             ("torus", "freeform")]
    n_per = 250
    total = mism_flag = 0
    hit = 0
    for k, (na, nb) in enumerate(pairs):
        (VA, FA), (VB, FB) = mesh(na), mesh(nb)
        ca, cb = _coal_model(coal, VA, FA), _coal_model(coal, VB, FB)
        Pas = random_poses(n_per, 500 + k, spread=1.0)
        Pbs = random_poses(n_per, 600 + k, spread=16.0)
        many = {bv: collide_many(body(na, bv), body(nb, bv), Pas, Pbs) for bv in BVS}
        req = coal.CollisionRequest()
        req.num_max_contacts = 10 ** 6
        for i in range(n_per):
            res = coal.CollisionResult()
            coal.collide(ca, coal.Transform3s(Pas[i, :3, :3], Pas[i, :3, 3]), cb,
                         coal.Transform3s(Pbs[i, :3, :3], Pbs[i, :3, 3]), req, res)
            ref = {(c.b1, c.b2) for c in res.getContacts()}
            c = collide(body(na, "obb"), Pas[i], body(nb, "obb"), Pbs[i])
            got = {tuple(x) for x in c.pairs.tolist()}
            assert got == ref, (na, nb, i, sorted(got ^ ref)[:5])
            for bv in BVS:
                mism_flag += bool(many[bv].colliding[i]) != bool(ref)
            total += 1
            hit += bool(ref)
    assert total >= 1000 and mism_flag == 0
    assert 150 < hit < 850


def test_distance_agrees_with_coal():
    coal = pytest.importorskip("coal")
    (VA, FA), (VB, FB) = mesh("torus"), mesh("capsule")
    ca, cb = _coal_model(coal, VA, FA), _coal_model(coal, VB, FB)
    for P in random_poses(20, 7, spread=25.0):
        res = coal.DistanceResult()
        ref = coal.distance(ca, coal.Transform3s(), cb, coal.Transform3s(P[:3, :3], P[:3, 3]),
                            coal.DistanceRequest(), res)
        for bv in BVS:
            d = min_distance(body("torus", bv), np.eye(4), body("capsule", bv), P)
            if ref > 0:
                assert d.distance == pytest.approx(ref, rel=1e-7, abs=1e-9)
            else:
                assert d.distance == 0.0


# ---------------------------------------------------------------- properties
names = st.sampled_from(["torus", "box", "capsule", "freeform"])
kinds = st.sampled_from(BVS)
seeds = st.integers(0, 2 ** 31 - 1)


@given(names, names, kinds, seeds)
def test_symmetry(na, nb, bv, seed):
    Pa, Pb = random_poses(2, seed, spread=8.0)
    a, b = body(na, bv), body(nb, bv)
    c1 = collide(a, Pa, b, Pb)
    c2 = collide(b, Pb, a, Pa)
    assert np.array_equal(c1.pairs, c2.pairs[np.lexsort((c2.pairs[:, 0], c2.pairs[:, 1]))][:, ::-1])
    d1 = min_distance(a, Pa, b, Pb)
    d2 = min_distance(b, Pb, a, Pa)
    assert d1.distance == pytest.approx(d2.distance, rel=1e-12, abs=1e-300)


@given(names, names, kinds, seeds)
def test_common_rigid_motion(na, nb, bv, seed):
    Pa, Pb, G = random_poses(3, seed, spread=8.0)
    a, b = body(na, bv), body(nb, bv)
    c1 = collide(a, Pa, b, Pb)
    d1 = min_distance(a, Pa, b, Pb)
    c2 = collide(a, G @ Pa, b, G @ Pb)
    d2 = min_distance(a, G @ Pa, b, G @ Pb)
    # the motion changes rounding only: pairs within rounding of touching may flip
    assert c1.colliding == c2.colliding or min(d1.distance, d2.distance) < 1e-9
    assert d1.distance == pytest.approx(d2.distance, rel=1e-9, abs=1e-9)
    if d1.distance > 0:
        assert np.allclose(G[:3, :3] @ d1.point_a + G[:3, 3], d2.point_a, atol=1e-7) or \
            d1.triangle_a != d2.triangle_a


@given(names, names, kinds, seeds)
def test_collide_iff_zero_distance(na, nb, bv, seed):
    Pa, Pb = random_poses(2, seed, spread=8.0)
    a, b = body(na, bv), body(nb, bv)
    c = collide(a, Pa, b, Pb, all_pairs=False)
    d = min_distance(a, Pa, b, Pb)
    assert c.colliding == (d.distance == 0.0)
    assert collide_many(a, b, Pa, Pb).colliding[0] == c.colliding


# ---------------------------------------------------------------- margin, batch
def test_margin_and_batch_forms():
    a, b = body("torus", "obb"), body("capsule", "obb")
    Ps = random_poses(40, 3, spread=20.0)
    many = collide_many(a, b, np.eye(4), Ps, all_pairs=True)
    for P, col, n in zip(Ps, many.colliding, many.n_pairs):
        c = collide(a, np.eye(4), b, P)
        assert col == c.colliding and n == len(c.pairs)
        d = min_distance(a, np.eye(4), b, P).distance
        for margin in (0.5, 2.0):
            m = min_distance(a, np.eye(4), b, P, margin=margin)
            assert m.within_margin == (d < margin)
            if m.within_margin:
                assert d <= m.distance < margin
            else:
                assert m.distance == np.inf and m.triangle_a == -1


def test_face_tags_and_input_mesh_types():
    m = geomkit.tessellate(geomkit.samples.load("sphere_pair"), 0.5)
    a = Body(m)
    assert np.array_equal(a.face_tags, m.face_surface)
    b = Body(m.to_trimesh(), bv="aabb", face_tags=np.arange(len(m.faces)))
    assert b.depth >= 1 and b.n_nodes == b.child.shape[0]
    c = collide(a, np.eye(4), Body(m), np.eye(4))
    assert c.colliding and np.array_equal(c.tags, m.face_surface[c.pairs])


@pytest.mark.parametrize("pose, msg", [
    (np.eye(3), "shape"),
    (np.diag([1.0, 1.0, 2.0, 1.0]), "orthonormal"),
    (np.diag([1.0, 1.0, -1.0, 1.0]), "determinant"),
    (np.full((4, 4), np.nan), "non-finite"),
    (np.vstack([np.eye(4)[:3], [[0, 0, 1, 1]]]), "last row"),
])
def test_bad_poses(pose, msg):
    a = body("box", "obb")
    with pytest.raises(InvalidInputError, match=msg) as e:
        collide(a, np.eye(4), a, pose)
    assert e.value.field == "pose_b"


def test_bad_inputs():
    V, F = mesh("box")
    with pytest.raises(InvalidInputError, match="bv"):
        Body((V, F), bv="sphere")
    with pytest.raises(InvalidInputError, match="faces"):
        Body((V, F + 1000))
    with pytest.raises(InvalidInputError, match="faces"):
        Body((V, F[:0]))
    with pytest.raises(InvalidInputError, match="vertices"):
        Body((V[:, :2], F))
    with pytest.raises(InvalidInputError, match="face_tags"):
        Body((V, F), face_tags=[1, 2])
    with pytest.raises(InvalidInputError, match="leaf_size: must be <= 16"):
        Body((V, F), leaf_size=17)
    with pytest.raises(InvalidInputError, match="14-DOP"):
        collide(body("box", "obb"), np.eye(4), body("box", "kdop14"), np.eye(4))
    with pytest.raises(InvalidInputError, match="margin"):
        min_distance(body("box", "obb"), np.eye(4), body("box", "obb"), np.eye(4), margin=-1)
    with pytest.raises(InvalidInputError, match="Body"):
        collide((V, F), np.eye(4), body("box", "obb"), np.eye(4))


# ---------------------------------------------------------------- batch kernels (issue 15)
def _coherent_poses(n, seed):
    """A body sliding through another in small steps (consecutive poses close:
    the first-hit seed of collide_many is reused from pose to pose)."""
    rng = np.random.default_rng(seed)
    P = np.tile(np.eye(4), (n, 1, 1))
    P[:, :3, :3] = Rotation.from_rotvec(np.outer(np.linspace(0, 1.5, n),
                                                 rng.normal(size=3))).as_matrix()
    P[:, :3, 3] = np.outer(np.linspace(-25, 25, n), rng.normal(size=3) / 3 + [1, 0, 0])
    return P


@pytest.mark.parametrize("bv", BVS)
def test_collide_many_equals_single_calls_on_coherent_poses(bv):
    import numba
    a, b = body("torus", bv), body("capsule", bv)
    Ps = _coherent_poses(600, 4)    # > one task of collide_many: several threads
    Pa = random_poses(1, 9, spread=2.0)[0]
    many = collide_many(a, b, Pa, Ps)
    ref = [collide(a, Pa, b, P, all_pairs=False) for P in Ps]
    assert np.array_equal(many.colliding, [c.colliding for c in ref])
    assert 100 < many.colliding.sum() < 500
    assert np.array_equal(many.n_pairs, many.colliding.astype(np.int64))
    nt = numba.get_num_threads()
    numba.set_num_threads(1)   # one thread: the same rows (the cut does not matter)
    try:
        one = collide_many(a, b, Pa, Ps)
    finally:
        numba.set_num_threads(nt)
    assert np.array_equal(one.colliding, many.colliding)
    full = collide_many(a, b, np.repeat(Pa[None], len(Ps), 0), Ps, all_pairs=True)
    assert np.array_equal(full.n_pairs, [len(collide(a, Pa, b, P).pairs) for P in Ps])


def test_collide_pose_layouts_agree():
    """The one-kernel path (float64 C-contiguous poses) and the validated path
    (lists, ints, Fortran order, views) give the same contacts."""
    a, b = body("freeform", "obb"), body("icosphere", "obb")
    for Pa, Pb in random_poses(30, 21, spread=6.0).reshape(15, 2, 4, 4):
        c = collide(a, Pa, b, Pb)
        for other in (Pb.tolist(), np.asfortranarray(Pb), np.tile(Pb, (1, 2))[:, :4]):
            d = collide(a, Pa, b, other)
            assert np.array_equal(c.pairs, d.pairs) and np.array_equal(c.tags, d.tags)
    c = collide(a, np.eye(4, dtype=int), b, np.eye(4))
    assert c.colliding and c.pairs.flags.c_contiguous and c.tags.flags.c_contiguous
    with pytest.raises(InvalidInputError, match="pose_b"):
        collide(a, np.eye(4), b, np.diag([1.0, 1.0, -1.0, 1.0]))
    # float64 C-contiguous 2-D arrays of another shape reach the kernel, which
    # checks the shape; read-only poses take the validated path
    for bad, msg in ((np.eye(5), "shape"), (np.eye(4)[:3].copy(), "shape"),
                     (np.zeros((4, 4)), "last row")):
        with pytest.raises(InvalidInputError, match="pose_a: .*" + msg):
            collide(a, bad, b, np.eye(4))
    Pa, Pb = random_poses(2, 5, spread=4.0)
    ro = Pb.copy()
    ro.flags.writeable = False
    c, d = collide(a, Pa, b, Pb), collide(a, Pa, b, ro)
    assert c.colliding and np.array_equal(c.pairs, d.pairs) and c.bv_tests == d.bv_tests


def test_single_call_kernel_equals_batch_rows():
    """The single-call kernel (packed buffers, root pre-test, results in the
    per-thread scratch, a retry when more pairs than the scratch holds) and the
    batch worker run the same traversal: same flags, pairs and node-test counts;
    all pairs equal brute force (more than the 64 the scratch holds at first)."""
    a, b = body("icosphere", "obb"), body("capsule", "obb")
    Pa = np.eye(4)
    for Pb in random_poses(40, 17, spread=10.0):
        c = collide(a, Pa, b, Pb, all_pairs=False)
        m = collide_many(a, b, Pa, Pb)    # one pose: no seed from an earlier pose
        assert (c.colliding, c.bv_tests) == (bool(m.colliding[0]), int(m.bv_tests[0]))
    (VA, FA), (VB, FB) = mesh("icosphere"), mesh("capsule")
    Pb = np.eye(4)
    Pb[0, 3] = 3.0
    c = collide(a, Pa, b, Pb)
    ref = brute_pairs(VA, FA, moved(VB, Pb), FB)
    assert len(ref) > 64 and {tuple(x) for x in c.pairs.tolist()} == ref
    assert c.pairs.tolist() == sorted(list(x) for x in ref)
    again = collide(a, Pa, b, Pb)        # the scratch is reused: results are copies
    assert np.array_equal(again.pairs, c.pairs) and np.array_equal(again.tags, c.tags)


def test_collide_many_broadcast_poses():
    """A stride-0 stack of one pose (np.broadcast_to) is checked and passed once:
    same rows as the materialised stack, its length counts, a bad pose is named."""
    a, b = body("torus", "obb"), body("capsule", "obb")
    Ps = random_poses(30, 5, spread=20.0)
    E = np.broadcast_to(np.eye(4), Ps.shape)
    for pa, pb in ((E, Ps), (Ps, E)):
        m = collide_many(a, b, pa, pb)
        ref = collide_many(a, b, np.ascontiguousarray(pa), np.ascontiguousarray(pb))
        assert np.array_equal(m.colliding, ref.colliding)
        assert np.array_equal(m.bv_tests, ref.bv_tests)
    assert collide_many(a, b, E, E).colliding.shape == (30,)
    with pytest.raises(InvalidInputError, match="3 poses for a but 30"):
        collide_many(a, b, np.broadcast_to(np.eye(4), (3, 4, 4)), Ps)
    bad = np.eye(4)
    bad[3, 3] = 2.0
    with pytest.raises(InvalidInputError, match=r"poses_a\[0\].*last row"):
        collide_many(a, b, np.broadcast_to(bad, (30, 4, 4)), Ps)


def test_single_collide_releases_the_gil_during_the_traversal():
    """The single-call entry keeps the GIL for the pose checks and the root test
    and releases it for the traversal: a Python thread keeps running during a long
    call (all pairs of two coincident spheres, ~0.2 s).  With the GIL held its
    longest pause would be one traversal's, about half of the call."""
    import threading
    import time

    a = Body(trimesh.creation.icosphere(5, 1.0))
    collide(a, np.eye(4), a, np.eye(4), all_pairs=True)
    stop, gaps = [], []

    def spin():
        last = time.perf_counter()
        while not stop:
            now = time.perf_counter()
            gaps.append(now - last)
            last = now
            time.sleep(0)

    th = threading.Thread(target=spin)
    th.start()
    time.sleep(0.02)
    t0 = time.perf_counter()
    c = collide(a, np.eye(4), a, np.eye(4), all_pairs=True)
    took = time.perf_counter() - t0
    stop.append(1)
    th.join()
    assert c.colliding and len(c.pairs) > 100_000
    assert max(gaps) < 0.25 * took, (max(gaps), took)   # two traversals (pairs > scratch)


def test_packed_node_links():
    """Each box node's record carries its first child or its leaf's triangle range
    (children are numbered c, c + 1 by the builder)."""
    from geomkit._kernels.bvh_boxes import LEAF_CODE
    for name in ("torus", "capsule"):
        b = body(name, "obb")
        link = b.N[:, 15]
        inner = b.child[:, 0] >= 0
        assert np.array_equal(b.child[inner, 1], b.child[inner, 0] + 1)
        assert np.array_equal(link[inner], b.child[inner, 0])
        k = (-link[~inner]).astype(np.int64) - 1
        assert np.array_equal(k % LEAF_CODE, b.rng[~inner, 0])
        assert np.array_equal(k // LEAF_CODE, b.rng[~inner, 1])
        assert np.array_equal(b.N[:, :3], b.C) and np.array_equal(b.N[:, 12:15], b.E)


def test_batch_kernels_are_serial():
    """Project policy: no numba parallel=True kernels in the collision group (batch
    work runs on threads by _numba.prun)."""
    from geomkit._kernels import bvh, bvh_boxes, bvh_query, triangles
    for mod in (bvh, bvh_boxes, bvh_query, triangles):
        for name in dir(mod):
            f = getattr(mod, name)
            if hasattr(f, "targetoptions"):
                assert not f.targetoptions.get("parallel"), (mod.__name__, name)


@pytest.mark.filterwarnings("ignore::PendingDeprecationWarning")   # np.matrix
def test_collide_other_pose_types_and_copied_bodies():
    """float64 2-D poses of any layout go to the single-call kernel as they are;
    other dtypes, byte orders and ndarray subclasses are converted; a copied body
    (pickle, deepcopy) holds its own buffer, and the kernel's handle follows it."""
    import copy
    a, b = body("freeform", "obb"), body("icosphere", "obb")
    poses = random_poses(20, 23, spread=6.0).reshape(10, 2, 4, 4)
    for Pa, Pb in poses:
        c = collide(a, Pa, b, Pb)
        for other in (Pb.astype(">f8"), np.asmatrix(Pb), np.asfortranarray(Pb),
                      Pb.astype(np.longdouble), Pb.repeat(2, 0).repeat(2, 1)[::2, ::2]):
            d = collide(a, Pa, b, other)
            assert np.array_equal(c.pairs, d.pairs) and c.bv_tests == d.bv_tests
    for other in (copy.deepcopy(b), pickle.loads(pickle.dumps(b))):
        assert other._addr == other._pf.ctypes.data != b._addr
        for Pa, Pb in poses:
            c, d = collide(a, Pa, b, Pb), collide(a, Pa, other, Pb)
            assert np.array_equal(c.pairs, d.pairs) and c.bv_tests == d.bv_tests
    with pytest.raises(InvalidInputError, match="pose_b: expected numbers"):
        collide(a, np.eye(4), b, "pose")


def test_distance_near_continuum_of_minima_vs_brute_force():
    """A ball centred on the torus's axis, in its hole: every point of a circle is
    (up to the tessellation) a closest point, so thousands of triangle pairs are
    within a hair of the minimum: the node bounds (bounding box in the other's
    axes, cut at the best distance) and the triangle prism bounds must prune none
    of the closest pair's ancestors.  Distances equal brute force's."""
    (VA, FA) = mesh("torus")
    t = trimesh.creation.icosphere(2, 3.0)
    VB, FB = np.ascontiguousarray(t.vertices, float), np.ascontiguousarray(t.faces, np.int64)
    for bv in ("obb", "aabb"):
        a, b = body("torus", bv), Body((VB, FB), bv=bv)
        for k, z in enumerate((0.0, 0.7, 2.5)):
            Pb = np.eye(4)
            Pb[:3, :3] = Rotation.random(random_state=k).as_matrix()
            Pb[:3, 3] = (0.0, 0.0, z)
            d = min_distance(a, np.eye(4), b, Pb)
            dref = brute_distance(VA, FA, moved(VB, Pb), FB)
            assert dref > 0.5 and abs(d.distance - dref) <= 1e-12 * dref


@jit
def _prism_vs_exact(T1, T2, out):
    n1 = np.empty((4, 3))
    n2 = np.empty((4, 3))
    p = np.empty(3)
    q = np.empty(3)
    for k in range(T1.shape[0]):
        _unit_normal(T1[k], n1)
        _unit_normal(T2[k], n2)
        out[k, 0] = max(_prism_gap(n1, T1[k], T2[k]), _prism_gap(n2, T2[k], T1[k]))
        out[k, 1] = triangle_triangle_distance(T1[k], T2[k], p, q)


def test_triangle_prism_bound_is_a_lower_bound():
    """The leaf pairs' prism bound (height over the other triangle's plane and
    distance beyond one of its edges) minus its rounding slack never exceeds the
    exact triangle distance: random, nearly parallel, nearly touching and sliver
    triangles; and it is tight for facing parallel triangles."""
    rng = np.random.default_rng(7)
    n = 4000
    T1 = rng.normal(size=(n, 3, 3))
    T2 = rng.normal(size=(n, 3, 3)) + rng.normal(size=(n, 1, 3)) * 2.0
    T2[:1000] = T1[:1000] + rng.normal(size=(1000, 1, 3)) * 0.5 + \
        rng.normal(size=(1000, 3, 3)) * 1e-3           # nearly parallel copies
    T1[1000:1500, 2] = T1[1000:1500, 0] + 1e-7 * rng.normal(size=(500, 3))  # slivers
    T2[1500:2000] = T1[1500:2000] * 1e6 + 1e3           # large coordinates
    T1[1500:2000] *= 1e6
    out = np.empty((n, 2))
    _prism_vs_exact(T1, T2, out)
    lever = np.linalg.norm(T1.mean(1) - T2.mean(1), axis=1) + \
        np.abs(T1 - T1.mean(1, keepdims=True)).max((1, 2)) * 3 + \
        np.abs(T2 - T2.mean(1, keepdims=True)).max((1, 2)) * 3
    assert np.all(out[:, 0] - PLANE_SLACK * lever <= out[:, 1])
    assert np.mean(out[:, 0] > 0.5 * out[:, 1]) > 0.5      # not a vacuous bound
    flat = np.array([[[0, 0, 0], [1, 0, 0], [0, 1, 0]]], float)
    _prism_vs_exact(flat, flat + [0.1, 0.1, 0.25], out[:1])
    assert abs(out[0, 0] - 0.25) < 1e-12 and abs(out[0, 1] - 0.25) < 1e-12


def test_object_refs_read_exact_float64_arrays_only():
    """The single-call kernel takes its arguments as the Python objects
    (geomkit._kernels.numba_ext.pyobj): it reads an array only if it is exactly an ndarray of
    the expected dtype and ndim; any other object gives 0 and is not read."""
    import ctypes

    import numba
    from geomkit._kernels.numba_ext.pyobj import address, array_data, array_fields_ok, object_ref
    assert array_fields_ok()        # CPython + NumPy here: the fast path is the one tested

    @numba.njit
    def probe(x, nd, f8):
        return array_data(address(x), nd, f8, 12, 2)

    entry = probe.compile((object_ref, numba.int64, numba.int64))
    refs = id(np.ndarray), id(np.dtype(np.float64))
    x = np.arange(16.0).reshape(4, 4)[::-1, ::2]
    data, dims, strides = entry(x, *refs)

    def i64(addr, k):
        return ctypes.c_int64.from_address(addr + 8 * k).value
    assert data == x.__array_interface__["data"][0]
    assert [i64(dims, 0), i64(dims, 1)] == list(x.shape)
    assert [i64(strides, 0), i64(strides, 1)] == list(x.strides)
    with pytest.warns(PendingDeprecationWarning):
        m = np.asmatrix(np.eye(4))
    for other in (np.eye(4, dtype=np.float32), np.eye(4).astype(">f8"), np.ones((1, 4, 4)),
                  np.ones(16), m, [[1.0] * 4] * 4, None, 3.0, "pose",
                  np.zeros((4, 4), dtype=[("x", "f8")]), np.eye(4).astype(object)):
        assert entry(other, *refs) == (0, 0, 0), type(other)
    # float64 with another descriptor object (unpickled arrays have their own): read
    for same in (pickle.loads(pickle.dumps(x)),
                 x.astype(np.dtype(np.float64, metadata={"k": 1}))):
        assert same.dtype is not np.dtype(np.float64)
        assert entry(same, *refs)[0] == same.__array_interface__["data"][0]


def test_unpickled_and_damaged_bodies():
    """An unpickled body keeps the single-call kernel (its buffer's dtype is another
    descriptor object); the packed buffer and its views are read-only; a buffer whose
    length does not match its header is refused by the kernel (the generic path
    answers)."""
    a, b = body("icosphere", "obb"), body("capsule", "obb")
    W = geomkit.collision.collide._single_scratch()
    P = np.eye(4)
    Q = random_poses(1, 3, spread=2.0)[0]
    ref = collide(a, P, b, Q)
    a2 = pickle.loads(pickle.dumps(a))
    assert a2._pf.dtype is not np.dtype(np.float64)
    assert geomkit.collision.collide._posed(a2._pf, b._pf, P, Q, False, W) >= 0
    for arr in (a.N, a.T, a.order, a.face_tags, a2.N, a2._pf):
        with pytest.raises(ValueError, match="read-only"):
            arr[0] = 0
    a2._pf = a2._pf[:-1]                 # damaged: the kernel refuses it
    assert geomkit.collision.collide._posed(a2._pf, b._pf, P, Q, False, W) == -4
    a2._pf = np.repeat(a._pf, 2)[::2]    # strided: refused
    assert geomkit.collision.collide._posed(a2._pf, b._pf, P, Q, False, W) == -4
    c = collide(a2, P, b, Q)             # the generic path (the body's own arrays)
    assert np.array_equal(c.pairs, ref.pairs) and c.bv_tests == ref.bv_tests


@pytest.mark.filterwarnings("ignore::PendingDeprecationWarning")   # np.matrix
def test_validate_pose_converts_subclasses():
    P = geomkit.collision.collide.validate_pose(np.asmatrix(np.eye(4)))
    assert type(P) is np.ndarray and P.shape == (4, 4)


def test_single_collide_from_threads():
    """Each thread has its own scratch for the single-call kernel: concurrent calls
    (long ones release the GIL mid-traversal) give the serial answers."""
    from concurrent.futures import ThreadPoolExecutor
    a, b = body("torus", "obb"), body("capsule", "obb")
    Ps = random_poses(200, 8, spread=12.0)
    ref = [collide(a, np.eye(4), b, P) for P in Ps]
    assert 20 < sum(c.colliding for c in ref) < 180

    def run(k0):
        return [collide(a, np.eye(4), b, Ps[k]) for k in range(k0, 200, 4)]
    with ThreadPoolExecutor(4) as ex:
        out = list(ex.map(run, range(4)))
    for k0, cs in enumerate(out):
        for c, k in zip(cs, range(k0, 200, 4)):
            assert c.colliding == ref[k].colliding and c.bv_tests == ref[k].bv_tests
            assert np.array_equal(c.pairs, ref[k].pairs) and np.array_equal(c.tags, ref[k].tags)
