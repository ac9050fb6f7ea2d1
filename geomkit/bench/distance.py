"""Surface–surface distance against Open CASCADE, same run.

1. Per case: geomkit :func:`~geomkit.surface_distance` (tol 1e-9, after JIT warm-up,
   median of ``--repeat`` runs) against ``BRepExtrema_DistShapeShape`` on the same
   faces (``Perform`` only), the time ratio and the error of each against the truth
   (analytic where the case has one, else the dense-sampling + L-BFGS-B oracle of the
   tests, which every certified interval must contain).
2. Speed versus error over tol 1e-3 ... 1e-12 (time, error, interval width, pairs
   examined, sub-patches, memory).
3. Lazy refinement versus uniform tessellation: sub-patches / memory the branch and
   bound creates against the triangles / memory of :func:`geomkit.tessellate` at the
   same accuracy (the mesh route of Paper 1).

4. ``--continuum``: only the continuum-minimum cases (curves or surfaces of minima) against OCC.

Usage: ``python -m geomkit.bench.distance [--repeat 5] [--continuum]``
"""

from __future__ import annotations

import argparse
import math
import time

import numpy as np

from geomkit import samples
from geomkit.query.distance import surface_distance
from geomkit.mesh.tessellate import tessellate
from geomkit.nurbs.surface import Surface


def _moved(s, t):
    return Surface(s.degree_u, s.degree_v, s.knots_u, s.knots_v,
                   s.control_points + np.asarray(t, float), s.weights,
                   trim=list(s.trim) or None)


def _rand_surface(rng, shift=(0, 0, 0), R=None, n=5, p=3):
    g = np.linspace(0, 10, n)
    X, Y = np.meshgrid(g, g, indexing="ij")
    P = np.stack([X, Y, rng.uniform(-2, 2, (n, n))], -1) + rng.uniform(-0.5, 0.5, (n, n, 3))
    if R is not None:
        P = P @ R.T
    P = P + np.asarray(shift, float)
    kn = np.r_[[0.0] * (p + 1), np.linspace(0, 1, n - p + 1)[1:-1], [1.0] * (p + 1)]
    return Surface(p, p, kn, kn, P, rng.uniform(0.5, 2.0, (n, n)))


def rand_pair(seed):
    """The random rational bicubic pair of the tests (seed -> pair)."""
    rng = np.random.default_rng(seed)
    a = _rand_surface(rng)
    R = np.linalg.qr(rng.normal(size=(3, 3)))[0] if seed % 2 else None
    b = _rand_surface(rng, shift=np.r_[rng.uniform(-3, 3, 2), rng.uniform(1, 8)], R=R)
    return a, b


def dense_oracle(a, b, m=80, starts=10):
    """Brute force (the tests' oracle): m x m samples on each surface, the nearest
    sample pairs, then L-BFGS-B on the 4 parameters from the `starts` best pairs."""
    from scipy.optimize import minimize
    from scipy.spatial import cKDTree

    g = np.linspace(0, 1, m)
    UV = np.stack(np.meshgrid(g, g, indexing="ij"), -1).reshape(-1, 2)
    A, B = a.evaluate(UV), b.evaluate(UV)
    d, j = cKDTree(B).query(A)
    best = np.inf
    for i in np.argsort(d)[:starts]:
        def f(x):
            return float(np.sum((a.evaluate(x[None, :2])[0] - b.evaluate(x[None, 2:])[0]) ** 2))
        res = minimize(f, np.r_[UV[i], UV[j[i]]], method="L-BFGS-B", bounds=[(0, 1)] * 4,
                       options=dict(ftol=1e-300, gtol=1e-14, maxiter=500))
        best = min(best, math.sqrt(res.fun))
    return best


def cases():
    out = []
    for name in ("sphere_pair", "offset_planes", "sphere_plane_cut"):
        c = samples.load_case(name)
        out.append((name, c.surfaces[0], c.surfaces[1], c.truth["min_distance"]))
    for seed in range(4):
        a, b = rand_pair(seed)
        out.append((f"random_{seed}", a, b, None))
    plate = samples.load("plate_with_hole")[0]
    sph = samples.load("sphere")[0]
    out.append(("sphere_vs_plate_edge", _moved(sph, (-13, 50, 4)), plate,
                math.sqrt(185.0) - 10))
    return out + continuum_cases()


CONTINUUM_CASES = ("torus_sphere_axis", "coaxial_cylinders", "concentric_spheres",
                   "parallel_trimmed_planes")


def _scaled(s, sx, sy, sz, t=(0.0, 0.0, 0.0)):
    return Surface(s.degree_u, s.degree_v, s.knots_u, s.knots_v,
                   s.control_points * np.array([sx, sy, sz]) + np.asarray(t, float),
                   s.weights, trim=list(s.trim) or None)


def continuum_cases():
    """Pairs whose minimum is attained on a continuum (analytic truths): the sphere
    (r 10) centred on the torus's axis in its hole (R 20, r 5: every point of the
    circle of radius 15 is a minimum, 5); coaxial quarter cylinders r 10 and 15 (5);
    concentric spheres r 10 and 20 (10); the plate with a hole and its copy 3 above
    (parallel trimmed planes, 3); the sphere on the torus's axis 3 above its plane
    (a circle of minima, sqrt(409) - 15, where no sphere / axis separator is exact)."""
    sph = samples.load("sphere")[0]
    tor = samples.load("torus")[0]
    cyl = samples.load("cylinder_quarter")[0]
    plate = samples.load("plate_with_hole")[0]
    return [("torus_sphere_axis", sph, tor, 5.0),
            ("coaxial_cylinders", cyl, _scaled(cyl, 1.5, 1.5, 1.0), 5.0),
            ("concentric_spheres", sph, _scaled(sph, 2.0, 2.0, 2.0), 10.0),
            ("parallel_trimmed_planes", plate, _moved(plate, (0.0, 0.0, 3.0)), 3.0),
            ("torus_sphere_axis_offset", _moved(sph, (0.0, 0.0, 3.0)), tor,
             math.sqrt(409.0) - 15.0)]


cases_ = cases


def _time(fn, repeat):
    ts = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        r = fn()
        ts.append(time.perf_counter() - t0)
    return r, float(np.median(ts))


def _face(occ, s):
    trim = [[c.to_dict() for c in loop.pieces] for loop in s.trim] or None
    return occ.make_face(s.degree_u, s.degree_v, s.knots_u, s.knots_v, s.control_points,
                         s.weights, trim=trim)


SWEEP_CASES = ("sphere_pair", "random_0")


def sweep(cases=SWEEP_CASES, tols=(1e-3, 1e-6, 1e-9, 1e-12), repeat=3):
    """Rows of the common schema (:mod:`geomkit.bench._common`): for each case and
    tolerance, the median time of ``surface_distance`` (after warm-up) and of
    ``BRepExtrema_DistShapeShape.Perform`` with ``SetDeflection(tol)``; errors are
    |distance - truth| against the case's analytic truth, or the dense-sampling +
    L-BFGS-B oracle (:func:`dense_oracle`) for the random pairs."""
    from geomkit.bench._common import MISSING_OCC, make_row, median_time, occ_or_none

    occ = occ_or_none()
    a, b = samples.load("sphere_pair")
    surface_distance(a, b)                                    # JIT warm-up
    by_name = {c[0]: c for c in cases_()}
    rows = []
    for name in cases:
        _, sa, sb, truth = by_name[name]
        oracle = "analytic truth"
        if truth is None:
            truth, oracle = dense_oracle(sa, sb), "dense oracle"
        surface_distance(sa, sb, tol=tols[0])                 # warm-up of this case
        fa = fb = None
        if occ is not None:
            fa, fb = _face(occ, sa), _face(occ, sb)
        for tol in tols:
            t, r, k = median_time(lambda: surface_distance(sa, sb, tol=tol), repeat, 1.0)
            ref = dict(note=MISSING_OCC)
            if fa is not None:
                ts = []
                for _ in range(k):
                    d_occ, _, _, sec = occ.distance_shapes(fa, fb, deflection=tol)
                    ts.append(sec)
                ref = dict(reference_name="OCC BRepExtrema_DistShapeShape",
                           reference_seconds=float(np.median(ts)),
                           reference_error=abs(d_occ - truth),
                           note=f"error vs {oracle}")
            cert = "certified" if r.certified else "NOT certified"
            ref["note"] = (ref.get("note", "") + f"; {cert}, interval "
                           f"{r.upper - r.lower:.2g}").lstrip("; ")
            rows.append(make_row("distance", name, "tol", tol, t, abs(r.distance - truth),
                                 repeats=k, **ref))
    return rows


def continuum_table(repeat=5, tol=1e-9):
    """Continuum-minimum cases only: median time of ``surface_distance``
    (after warm-up) and of OCC ``DistShapeShape`` on the same faces in this run, the
    interval width and whether it certified; prints a markdown table."""
    from geomkit.bench._common import occ_or_none

    occ = occ_or_none()
    a, b = samples.load("sphere_pair")
    surface_distance(a, b)                                    # JIT warm-up
    print(f"| case | truth | geomkit ms | width | certified | pairs | OCC ms | OCC error "
          f"| OCC / geomkit |   (tol {tol:g}, median of {repeat})")
    print("|---|---|---|---|---|---|---|---|---|")
    for name, sa, sb, truth in continuum_cases():
        surface_distance(sa, sb, tol=tol)
        r, t = _time(lambda: surface_distance(sa, sb, tol=tol), repeat)
        assert r.lower <= truth <= r.upper, (name, r.lower, r.upper, truth)
        tocc = eocc = ratio = "n/a"
        if occ is not None:
            fa, fb = _face(occ, sa), _face(occ, sb)
            ts = []
            for _ in range(repeat):
                d_occ, _, _, sec = occ.distance_shapes(fa, fb, deflection=tol)
                ts.append(sec)
            t_occ = float(np.median(ts))
            tocc, eocc, ratio = (f"{1e3 * t_occ:.3g}", f"{abs(d_occ - truth):.1g}",
                                 f"{t_occ / t:.3g}")
        print(f"| {name} | {truth:.6g} | {1e3 * t:.3g} | {r.upper - r.lower:.2g} | "
              f"{r.certified} | {r.stats['pairs_examined']} | {tocc} | {eocc} | {ratio} |",
              flush=True)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--continuum", action="store_true",
                    help="only the continuum-minimum cases against OCC")
    args = ap.parse_args(argv)
    if args.continuum:
        continuum_table(args.repeat)
        return
    try:
        from geomkit.bench.oracles import occ
        occ._require_ocp("bench")
    except Exception:  # noqa: BLE001 - the benchmark runs without OCC too
        occ = None
    a, b = samples.load("sphere_pair")
    surface_distance(a, b)  # JIT warm-up
    print("## geomkit surface_distance (tol 1e-9) vs BRepExtrema_DistShapeShape\n")
    print("| case | truth | geomkit error | interval width | certified | OCC error | "
          "geomkit ms | OCC ms | OCC / geomkit |")
    print("|---|---|---|---|---|---|---|---|---|")
    rows = []
    for name, sa, sb, truth in cases():
        r, t = _time(lambda: surface_distance(sa, sb, tol=1e-9), args.repeat)
        if truth is None:
            truth = dense_oracle(sa, sb)
        if occ is not None:
            fa, fb = _face(occ, sa), _face(occ, sb)
            ts = []
            for _ in range(args.repeat):
                d_occ, _, _, sec = occ.distance_shapes(fa, fb)
                ts.append(sec)
            t_occ = float(np.median(ts))
            e_occ = f"{d_occ - truth:+.1e}"
            ratio = f"{t_occ / t:.1f}x"
            tocc = f"{1e3 * t_occ:.2f}"
        else:
            e_occ = tocc = ratio = "n/a"
        rows.append(t)
        print(f"| {name} | {truth:.12g} | {r.distance - truth:+.1e} | {r.width:.1e} | "
              f"{r.certified} | {e_occ} | {1e3 * t:.2f} | {tocc} | {ratio} |")
    print("\n## speed versus error (tol sweep)\n")
    print("| case | tol | ms | error | width | pairs examined | sub-patches | memory KiB |")
    print("|---|---|---|---|---|---|---|---|")
    for name, sa, sb, truth in [cases()[3], cases()[0]]:
        if truth is None:
            truth = dense_oracle(sa, sb)
        for tol in (1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10, 1e-11, 1e-12):
            r, t = _time(lambda: surface_distance(sa, sb, tol=tol), args.repeat)
            print(f"| {name} | {tol:.0e} | {1e3 * t:.2f} | {r.distance - truth:+.1e} | "
                  f"{r.width:.1e} | {r.stats['pairs_examined']} | {r.stats['nodes']} | "
                  f"{r.stats['memory_bytes'] / 1024:.1f} |")
    print("\n## lazy refinement vs uniform tessellation (random_0)\n")
    print("| tol | lazy sub-patches | lazy memory KiB | uniform triangles | "
          "uniform memory KiB | tessellate ms |")
    print("|---|---|---|---|---|---|")
    sa, sb = rand_pair(0)
    for tol in (1e-2, 1e-3, 1e-4, 1e-5, 1e-9):
        r = surface_distance(sa, sb, tol=tol)
        if tol >= 1e-5:
            t0 = time.perf_counter()
            m = tessellate([sa, sb], tol)
            tt = 1e3 * (time.perf_counter() - t0)
            mem = (m.vertices.nbytes + m.faces.nbytes + m.uv.nbytes + m.face_uv.nbytes
                   + m.face_deviation.nbytes) / 1024
            tri, mem, tt = str(m.faces.shape[0]), f"{mem:.0f}", f"{tt:.0f}"
        else:
            tri = mem = tt = "not built (too fine)"
        print(f"| {tol:.0e} | {r.stats['nodes']} | {r.stats['memory_bytes'] / 1024:.1f} | "
              f"{tri} | {mem} | {tt} |")


if __name__ == "__main__":
    main()
