"""Collision and distance queries against coal, same run, same meshes and poses.

Meshes: tessellated shared cases (torus, sphere, freeform_1 at tolerances giving
~25–50k triangles) and trimesh primitives.  For each mesh pair and N random poses
(after JIT warm-up): median time per query of

* geomkit ``collide(..., all_pairs=False)`` one call per pose, interleaved pose by
  pose with coal ``collide`` (default request: first contact) with
  ``BVHModelOBBRSS`` and ``BVHModelOBB``, for OBB, 14-DOP, AABB trees;
* ``collide_many`` (all poses in one call, wall time / N; with the default threads
  and with one) against coal's Python loop over the same poses (total time / N:
  the same work, a mean per query, not a median of single calls);
* ``min_distance`` vs coal ``distance`` (OBBRSS);

with ratios geomkit / coal and bounding-volume tests per query.  Also the OBB fit
volume (root box and sum over all nodes) of the covariance centre vs Paper 3's
region-weighted centre on the shared cases' meshes.

Usage: ``python -m geomkit.bench.collision [--poses 200] [--repeats 5] [--bv obb,aabb]
[--quick]``
"""

from __future__ import annotations

import argparse
import time

import numpy as np

import geomkit
from geomkit.collision.collide import Body, collide, collide_many, min_distance


def _meshes(quick):
    import trimesh

    s = 4 if quick else 1
    out = {}
    m = geomkit.tessellate(geomkit.samples.load("torus"), 1e-2 * s)
    out["torus"] = (m.vertices, m.faces)
    m = geomkit.tessellate(geomkit.samples.load("sphere"), 5e-3 * s)
    out["sphere"] = (m.vertices, m.faces)
    m = geomkit.tessellate(geomkit.samples.load("freeform_1"), 1e-2 * s)
    out["freeform_1"] = (m.vertices * 0.5, m.faces)
    t = trimesh.creation.icosphere(5 if not quick else 4, 8.0)
    out["icosphere"] = (t.vertices, t.faces)
    t = trimesh.creation.capsule(height=30, radius=5, count=[160, 160] if not quick else [60, 60])
    out["capsule"] = (t.vertices, t.faces)
    return {k: (np.ascontiguousarray(V - V.mean(0), float), np.ascontiguousarray(F, np.int64))
            for k, (V, F) in out.items()}


PAIRS = [("torus", "sphere"), ("freeform_1", "torus"), ("icosphere", "capsule"),
         ("torus", "capsule")]


def _poses(n, spread, seed):
    from scipy.spatial.transform import Rotation

    rng = np.random.default_rng(seed)
    P = np.tile(np.eye(4), (n, 1, 1))
    P[:, :3, :3] = Rotation.random(n, random_state=seed).as_matrix()
    P[:, :3, 3] = rng.uniform(-spread, spread, (n, 3))
    return P


def _coal(coal, V, F, cls):
    m = cls()
    m.beginModel(len(F), len(V))
    m.addVertices(V)
    m.addTriangles(F)
    m.endModel()
    return m


def _median_time(fn, n):
    ts = np.empty(n)
    for k in range(n):
        t0 = time.perf_counter()
        fn(k)
        ts[k] = time.perf_counter() - t0
    return float(np.median(ts))


def _coal_pose(coal, P):
    return coal.Transform3s(np.ascontiguousarray(P[:3, :3]), np.ascontiguousarray(P[:3, 3]))


def bench_pair(coal, meshes, na, nb, n_poses, seed, bvs=("obb", "kdop14", "aabb"),
               repeats=5):
    """One mesh pair: per tree kind, single ``collide`` calls (first hit) timed pose by
    pose, interleaved with coal's call on the same pose (medians over poses and
    ``repeats``), ``collide_many`` over all poses (wall time / poses, median of
    ``repeats``; also with one thread) against coal's Python loop over the same
    poses (total / poses, median of ``repeats``), and ``min_distance``."""
    import numba

    (VA, FA), (VB, FB) = meshes[na], meshes[nb]
    spread = 0.45 * max(np.ptp(VA, 0).max(), np.ptp(VB, 0).max())
    PA = _poses(n_poses, 0.0, seed)
    PA[:, :3, :3] = np.eye(3)     # a static, b moves (the usual simulation case)
    PB = _poses(n_poses, spread, seed + 1)
    out = {"geomkit": {}}
    cmod = {}
    if coal is not None:
        for name, cls in (("OBBRSS", coal.BVHModelOBBRSS), ("OBB", coal.BVHModelOBB)):
            cmod[name] = (_coal(coal, VA, FA, cls), _coal(coal, VB, FB, cls))
        tfa = [_coal_pose(coal, P) for P in PA]
        tfb = [_coal_pose(coal, P) for P in PB]
        req = coal.CollisionRequest()
        cres = {name: np.empty(n_poses, bool) for name in cmod}

    def coal_one(name, k):
        ca, cb = cmod[name]
        r = coal.CollisionResult()
        t0 = time.perf_counter()
        coal.collide(ca, tfa[k], cb, tfb[k], req, r)
        t = time.perf_counter() - t0
        cres[name][k] = r.isCollision()
        return t

    def coal_loop(name):
        ca, cb = cmod[name]
        c0, t0 = time.process_time(), time.perf_counter()
        for k in range(n_poses):
            coal.collide(ca, tfa[k], cb, tfb[k], req, coal.CollisionResult())
        return ((time.perf_counter() - t0) / n_poses, (time.process_time() - c0) / n_poses)

    flags = None
    for bv in bvs:
        a, b = Body((VA, FA), bv=bv), Body((VB, FB), bv=bv)
        collide(a, PA[0], b, PB[0], all_pairs=False)          # warm-up
        collide_many(a, b, PA[:2], PB[:2])
        tests = np.empty(n_poses, np.int64)
        res = np.empty(n_poses, bool)
        t_gk, t_co = [], {name: [] for name in cmod}
        PAL, PBL = list(PA), list(PB)    # pose views made once, as coal's transforms are
        for _ in range(repeats if bv == "obb" else 1):
            for k in range(n_poses):
                Pa, Pb = PAL[k], PBL[k]
                t0 = time.perf_counter()
                c = collide(a, Pa, b, Pb, all_pairs=False)
                t_gk.append(time.perf_counter() - t0)
                tests[k] = c.bv_tests
                res[k] = c.colliding
                if bv == "obb":
                    for name in cmod:
                        t_co[name].append(coal_one(name, k))
        if bv == "obb":
            flags = res.copy()
            for name in cmod:
                out["coal_" + name] = float(np.median(t_co[name]))
                out["agree_" + name] = int((cres[name] == res).sum())
        t1 = float(np.median(t_gk))
        tm, tm1, tcl, cm1, ccl = [], [], [], [], []
        nt = numba.get_num_threads()
        for _ in range(repeats):
            t0 = time.perf_counter()
            many = collide_many(a, b, PA, PB)
            tm.append((time.perf_counter() - t0) / n_poses)
            assert np.array_equal(many.colliding, res)
            numba.set_num_threads(1)
            try:
                c0, t0 = time.process_time(), time.perf_counter()
                collide_many(a, b, PA, PB)
                tm1.append((time.perf_counter() - t0) / n_poses)
                cm1.append((time.process_time() - c0) / n_poses)
            finally:
                numba.set_num_threads(nt)
            if bv == "obb" and coal is not None:
                w, c = coal_loop("OBBRSS")
                tcl.append(w)
                ccl.append(c)
        if tcl:
            out["coal_loop"] = float(np.median(tcl))
            out["coal_loop_cpu"] = float(np.median(ccl))
        min_distance(a, PA[0], b, PB[0])
        dt = _median_time(lambda k: min_distance(a, PA[k], b, PB[k]), min(n_poses, 50))
        out["geomkit"][bv] = (t1, float(np.median(tm)), float(np.median(tm1)),
                              float(np.median(cm1)), float(np.mean(tests)),
                              float(np.median(tests)), dt)
    out["hits"] = int(flags.sum()) if flags is not None else -1
    if coal is not None:
        ca, cb = cmod["OBBRSS"]
        dreq = coal.DistanceRequest()
        out["coal_dist"] = _median_time(
            lambda k: coal.distance(ca, tfa[k], cb, tfb[k], dreq, coal.DistanceResult()),
            min(n_poses, 50))
    return out


def obb_volumes(meshes):
    rows = []
    for name in ("torus", "sphere", "freeform_1"):
        V, F = meshes[name]
        vols = {}
        for centre in ("covariance", "regions"):
            b = Body((V, F), bv="obb", obb_center=centre)
            node = 8.0 * np.prod(b.E, axis=1)
            vols[centre] = (float(node[0]), float(node.sum()))
        rows.append((name, len(F), vols))
    return rows


def _sweep_poses(pair, n, seed):
    """Random poses of body b (body a, the sample sphere, stays at the origin) and the
    exact signed contact margin of the two *surfaces* at each pose: two radius-10
    spheres meet iff their centres are within 20, the radius-10 sphere and the torus
    (R 20, r 5) iff the sphere's centre is within 15 of the torus core circle.  The
    margin (centre distance minus 20, resp. core distance minus 15) is the surfaces'
    distance when positive, and its size is how far the centre must move to change
    the answer."""
    from scipy.spatial.transform import Rotation

    rng = np.random.default_rng(seed)
    P = np.tile(np.eye(4), (n, 1, 1))
    R = Rotation.random(n, random_state=seed).as_matrix()
    P[:, :3, :3] = R
    if pair == "sphere-sphere":
        u = rng.normal(size=(n, 3))
        t = u / np.linalg.norm(u, axis=1)[:, None] * rng.uniform(12, 28, (n, 1))
        P[:, :3, 3] = t
        return P, np.linalg.norm(t, axis=1) - 20.0
    t = rng.uniform(-35, 35, (n, 3))
    P[:, :3, 3] = t
    y = np.einsum("nji,nj->ni", R, -t)              # the sphere's centre in the torus frame
    core = np.hypot(np.hypot(y[:, 0], y[:, 1]) - 20.0, y[:, 2])
    return P, core - 15.0


SWEEP_PAIRS = ("sphere-sphere", "sphere-torus")


def sweep(pairs=SWEEP_PAIRS, tols=(1e-1, 3e-2, 1e-2), poses=100, bv="obb", seed=0, repeat=3):
    """Rows of the common schema (:mod:`geomkit.bench._common`): the sample sphere
    against a second sphere or the torus, both tessellated at each mesh tolerance
    (the size sweep), ``poses`` random poses.  Per pair and tolerance four rows,
    times per query, against coal (``BVHModelOBBRSS``, same meshes and poses):

    * ``collide`` (first hit, one Python call per pose) vs ``coal.collide``, the two
      timed pose by pose in one loop (``repeat`` passes; medians over poses and
      passes): error = largest |exact contact margin| (:func:`_sweep_poses`) at a
      pose the answer got wrong (0 when every pose is right), i.e. how far from the
      contact boundary a wrong answer can be;
    * ``collide mean``: the same timed calls, mean per call (a path's total time over
      its calls; the median falls on the poses whose root boxes are disjoint);
    * ``collide per pose``: the same timed calls, each pose's median over the
      passes, then the geometric mean over the poses for both libraries: their
      ratio is the geometric mean of the per-pose speed-ups, a comparison pose by
      pose (the pooled median compares one pose's call with another's when, as on
      sphere–torus, about half of the poses end at the root boxes and the median
      falls where those calls end and the traversing ones begin);
    * ``collide_many`` (first hit, all poses in one call) vs coal's Python loop over
      the same poses: total time / poses for both (the same work; medians of
      ``repeat``);
    * ``min_distance`` vs ``coal.distance`` (medians over poses): error = largest
      |mesh distance - exact distance of the surfaces| over the poses.
    """
    from geomkit.bench._common import MISSING_COAL, coal_or_none, make_row

    coal = coal_or_none()
    rows = []
    eye = np.eye(4)
    for pair in pairs:
        PB, margin = _sweep_poses(pair, poses, seed)
        touching = margin <= 0.0
        exact = np.maximum(0.0, margin)
        for tol in tols:
            ma = geomkit.tessellate(geomkit.samples.load("sphere"), tol)
            mb = geomkit.tessellate(geomkit.samples.load(pair.split("-")[1]), tol)
            meshes = [(np.ascontiguousarray(m.vertices), np.ascontiguousarray(m.faces, np.int64))
                      for m in (ma, mb)]
            a, b = Body(meshes[0], bv=bv), Body(meshes[1], bv=bv)
            collide(a, eye, b, PB[0], all_pairs=False)        # JIT warm-up
            min_distance(a, eye, b, PB[0])
            hit, dist = np.empty(poses, bool), np.empty(poses)
            if coal is not None:
                ca = _coal(coal, *meshes[0], coal.BVHModelOBBRSS)
                cb = _coal(coal, *meshes[1], coal.BVHModelOBBRSS)
                ta = coal.Transform3s(np.eye(3), np.zeros(3))
                tb = [coal.Transform3s(P[:3, :3].copy(), P[:3, 3].copy()) for P in PB]
                creq, dreq = coal.CollisionRequest(), coal.DistanceRequest()
                chit, cdist = np.empty(poses, bool), np.empty(poses)
            t_hit, c_hit = [], []
            PL = list(PB)                # pose views made once, as coal's transforms are
            for _ in range(repeat):      # collide and coal's, interleaved pose by pose
                for k in range(poses):
                    Pk = PL[k]
                    t0 = time.perf_counter()
                    c = collide(a, eye, b, Pk, all_pairs=False)
                    t_hit.append(time.perf_counter() - t0)
                    hit[k] = c.colliding          # read outside the timing, as coal's
                    if coal is not None:
                        r = coal.CollisionResult()
                        t0 = time.perf_counter()
                        coal.collide(ca, ta, cb, tb[k], creq, r)
                        c_hit.append(time.perf_counter() - t0)
                        chit[k] = r.isCollision()

            def gk_dist(k):
                dist[k] = min_distance(a, eye, b, PB[k]).distance
            t_dist = _median_time(gk_dist, poses)
            EYE = np.broadcast_to(eye, PB.shape)
            collide_many(a, b, EYE[:2], PB[:2])
            t_many, c_loop = [], []
            for _ in range(repeat):
                t0 = time.perf_counter()
                many = collide_many(a, b, EYE, PB).colliding
                t_many.append((time.perf_counter() - t0) / poses)
                if coal is not None:
                    t0 = time.perf_counter()
                    for k in range(poses):
                        coal.collide(ca, ta, cb, tb[k], creq, coal.CollisionResult())
                    c_loop.append((time.perf_counter() - t0) / poses)
            size = f"{len(meshes[0][1])} + {len(meshes[1][1])} triangles"
            out = {"collide": [float(np.median(t_hit)), _wrong(hit, touching, margin)],
                   "collide mean": [float(np.mean(t_hit)), _wrong(hit, touching, margin)],
                   "collide per pose": [_per_pose(t_hit, repeat, poses),
                                        _wrong(hit, touching, margin)],
                   "collide_many": [float(np.median(t_many)), _wrong(many, touching, margin)],
                   "min_distance": [t_dist, float(np.max(np.abs(dist - exact)))]}
            refs = {k: dict(note=f"{size}; {MISSING_COAL}") for k in out}
            if coal is not None:
                def c_dist(k):
                    r = coal.DistanceResult()
                    coal.distance(ca, ta, cb, tb[k], dreq, r)
                    cdist[k] = max(0.0, r.min_distance)
                c_dist(0)
                wrong = _wrong(chit, touching, margin)
                refs["collide"] = dict(reference_name="coal collide (OBBRSS)",
                                       reference_seconds=float(np.median(c_hit)),
                                       reference_error=wrong,
                                       note=f"{size}; {int(touching.sum())}/{poses} poses "
                                            f"touch; wrong: geomkit {int((hit != touching).sum())}"
                                            f", coal {int((chit != touching).sum())}; calls "
                                            "interleaved pose by pose, medians")
                refs["collide mean"] = dict(
                    reference_name="coal collide (OBBRSS)",
                    reference_seconds=float(np.mean(c_hit)), reference_error=wrong,
                    note=f"{size}; the same timed calls as the collide row, mean per call "
                         "(a path's total time / calls) instead of the median (which falls "
                         "on the poses whose root boxes are disjoint)")
                refs["collide per pose"] = dict(
                    reference_name="coal collide (OBBRSS)",
                    reference_seconds=_per_pose(c_hit, repeat, poses), reference_error=wrong,
                    note=f"{size}; the same timed calls as the collide row: each pose's "
                         "median, geometric mean over the poses (the ratio is the "
                         "geometric mean of the per-pose speed-ups)")
                refs["collide_many"] = dict(
                    reference_name="coal collide loop (OBBRSS)",
                    reference_seconds=float(np.median(c_loop)), reference_error=wrong,
                    note=f"{size}; all poses in one call vs coal's Python loop over the "
                         "same poses, total time / poses for both")
                refs["min_distance"] = dict(
                    reference_name="coal distance (OBBRSS)",
                    reference_seconds=_median_time(c_dist, poses),
                    reference_error=float(np.max(np.abs(cdist - exact))), note=size)
            for what, (t, err) in out.items():
                rows.append(make_row("collision", f"{pair} {what}", "mesh tol", tol, t, err,
                                     per="query", repeats=poses, **refs[what]))
    return rows


def _per_pose(times, passes, poses):
    """Geometric mean over the poses of each pose's median time (``times`` in pass
    order, ``poses`` per pass)."""
    t = np.median(np.asarray(times).reshape(passes, poses), axis=0)
    return float(np.exp(np.mean(np.log(t))))


def _wrong(answer, truth, margin):
    """Largest |contact margin| among the poses answered wrongly (0 if none): how far
    from the exact contact boundary a wrong answer was given."""
    bad = answer != truth
    return float(np.abs(margin[bad]).max()) if bad.any() else 0.0


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--poses", type=int, default=200)
    ap.add_argument("--quick", action="store_true", help="coarser meshes (smoke run)")
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--bv", default="obb,kdop14,aabb", help="tree kinds (comma separated)")
    args = ap.parse_args(argv)
    try:
        import coal
    except ImportError:  # pragma: no cover
        coal = None
    meshes = _meshes(args.quick)
    print("| mesh | triangles |\n|---|---|")
    for k, (V, F) in meshes.items():
        print(f"| {k} | {len(F)} |")
    print("\n## OBB fit volume: covariance centre vs Paper 3 region-weighted centre\n")
    print("| mesh | triangles | root vol (cov) | root vol (regions) | "
          "sum node vol (cov) | sum node vol (regions) |\n|---|---|---|---|---|---|")
    for name, m, v in obb_volumes(meshes):
        c, r = v["covariance"], v["regions"]
        print(f"| {name} | {m} | {c[0]:.6g} | {r[0]:.6g} | {c[1]:.6g} | {r[1]:.6g} |")
    print(f"\n## collide (first hit), {args.poses} random poses per pair\n")
    print("Single calls: geomkit and coal timed pose by pose in one loop, medians over "
          f"poses x {args.repeats} (OBB; other trees 1 pass).  collide_many: all poses in "
          "one call, wall time / poses (2 threads, and 1 thread), against coal's Python "
          "loop over the same poses (total / poses, OBBRSS); medians of "
          f"{args.repeats} repeats.  CPU: process time of the one-thread batch and of "
          "coal's loop (insensitive to other processes taking the cores).\n")
    print("| pair | hits | bv | geomkit 1 call µs | coal OBBRSS 1 call µs | coal OBB 1 call µs "
          "| ratio 1 call / OBBRSS | collide_many µs/query | many, 1 thread | coal loop "
          "µs/query | ratio many / coal loop | ratio many 1 thread / coal loop | "
          "CPU ratio many 1 thread / coal loop | "
          "BV tests mean | BV tests median |\n|---|---|---|---|---|---|---|---|---|---|---|"
          "---|---|---|---|")
    dist_rows = []
    bvs = tuple(args.bv.split(","))
    for k, (na, nb) in enumerate(PAIRS):
        r = bench_pair(coal, meshes, na, nb, args.poses, 10 * k, bvs, args.repeats)
        cr = r.get("coal_OBBRSS", np.nan)
        co = r.get("coal_OBB", np.nan)
        cl = r.get("coal_loop", np.nan)
        ccl = r.get("coal_loop_cpu", np.nan)
        for bv, (t1, tm, tm1, cm1, tmean, tmed, dt) in r["geomkit"].items():
            print(f"| {na}–{nb} | {r['hits']} | {bv} | {t1 * 1e6:.1f} | {cr * 1e6:.1f} | "
                  f"{co * 1e6:.1f} | {t1 / cr:.2f} | {tm * 1e6:.1f} | {tm1 * 1e6:.1f} | "
                  f"{cl * 1e6:.1f} | {tm / cl:.2f} | {tm1 / cl:.2f} | {cm1 / ccl:.2f} | "
                  f"{tmean:.0f} | "
                  f"{tmed:.0f} |")
            dist_rows.append((na, nb, bv, dt, r.get("coal_dist", np.nan)))
        if coal is not None and "agree_OBBRSS" in r:   # coal is timed with the obb rows
            print(f"|  | coal agrees on {r['agree_OBBRSS']}/{args.poses} (OBBRSS), "
                  f"{r['agree_OBB']}/{args.poses} (OBB) |||||||||||||| ")
    print("\n## min_distance (exact), 50 poses per pair, medians\n")
    print("| pair | bv | geomkit µs | coal OBBRSS distance µs | ratio |\n|---|---|---|---|---|")
    for na, nb, bv, dt, cd in dist_rows:
        print(f"| {na}–{nb} | {bv} | {dt * 1e6:.0f} | {cd * 1e6:.0f} | {dt / cd:.2f} |")


if __name__ == "__main__":
    main()
