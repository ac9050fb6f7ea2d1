"""Evaluation throughput against geomdl (and Open CASCADE when installed), same run.

For each surface: N random parameter pairs, evaluated by geomkit (parallel numba
kernels, after warm-up), geomdl (``evaluate_list``) and OCC (``Geom_BSplineSurface.D0``
in a Python loop); reports time per point, the speed-up and the largest deviation
between the results (relative to model size).  JIT cost is reported separately:
a cold compile (fresh cache directory) and a warm start (cache load) are timed in
subprocesses.

Usage: ``python -m geomkit.bench.evaluation [--points 100000] [--geomdl-points N]``
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
import time

import numpy as np

import geomkit
from geomkit import samples

CASES = ["freeform_1", "sphere", "torus", "heavy_weights", "crease", "wave_seed003"]

_COLD = """
import time, numpy as np
t0 = time.perf_counter()
import geomkit
t1 = time.perf_counter()
s = geomkit.samples.load("sphere")[0]
uv = np.random.default_rng(0).random((10, 2))
t2 = time.perf_counter(); s.evaluate(uv); t3 = time.perf_counter()
s.derivatives(uv, 2); t4 = time.perf_counter(); s.normals(uv); t5 = time.perf_counter()
print(f"{t1-t0:.3f} {t3-t2:.3f} {t4-t3:.3f} {t5-t4:.3f}")
"""


def jit_cost(cache_dir: str | None) -> list[float]:
    env = dict(os.environ)
    if cache_dir:
        env["NUMBA_CACHE_DIR"] = cache_dir
    out = subprocess.run([sys.executable, "-c", _COLD], env=env, capture_output=True,
                         text=True, check=True)
    return [float(x) for x in out.stdout.split()]


def _median_time(fn, repeat=5):
    ts = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        ts.append(time.perf_counter() - t0)
    return float(np.median(ts))


def run(points=100_000, geomdl_points=None, occ_points=20_000, cases=CASES, out=print):
    rng = np.random.default_rng(1)
    geomdl_points = points if geomdl_points is None else geomdl_points
    try:
        from geomkit.bench.oracles import occ
        have_occ = occ.HAVE_OCP
    except Exception:  # pragma: no cover - optional
        have_occ = False
    out(f"evaluation of {points} random points per surface; geomdl on {geomdl_points}, "
        f"OCC on {occ_points if have_occ else 0} (per-point times; median of 5 for geomkit)")
    out(f"{'surface':14s} {'geomkit us/pt':>13s} {'geomdl us/pt':>12s} {'speed-up':>9s} "
        f"{'max|diff|/size':>14s} {'OCC us/pt':>10s} {'vs OCC':>7s} {'derivs2 us/pt':>13s} "
        f"{'normals us/pt':>13s}")
    rows = []
    for name in cases:
        s = samples.load(name)[0]
        (u0, u1), (v0, v1) = s.domain
        uv = np.column_stack([rng.uniform(u0, u1, points), rng.uniform(v0, v1, points)])
        s.evaluate(uv[:10]); s.derivatives(uv[:10], 2); s.normals(uv[:10])  # warm-up
        t_gk = _median_time(lambda: s.evaluate(uv)) / points
        t_d2 = _median_time(lambda: s.derivatives(uv, 2), 3) / points
        t_n = _median_time(lambda: s.normals(uv), 3) / points
        P = s.evaluate(uv)
        g = s.to_geomdl()
        sub = uv[:geomdl_points]
        t0 = time.perf_counter()
        G = np.asarray(g.evaluate_list(sub.tolist()))
        t_gd = (time.perf_counter() - t0) / geomdl_points
        err = float(np.max(np.abs(G - P[:geomdl_points]))) / s.size
        row = {"surface": name, "geomkit_us": 1e6 * t_gk, "geomdl_us": 1e6 * t_gd,
               "speedup_vs_geomdl": t_gd / t_gk, "max_rel_diff_geomdl": err,
               "derivs2_us": 1e6 * t_d2, "normals_us": 1e6 * t_n}
        occ_txt = f"{'-':>10s} {'-':>7s}"
        if have_occ:
            surf = occ.make_surface(s.degree_u, s.degree_v, s.knots_u, s.knots_v,
                                    s.control_points, s.weights)
            sub = uv[:occ_points]
            t0 = time.perf_counter()
            O = occ.evaluate(surf, sub)
            t_occ = (time.perf_counter() - t0) / occ_points
            row["occ_us"] = 1e6 * t_occ
            row["speedup_vs_occ"] = t_occ / t_gk
            row["max_rel_diff_occ"] = float(np.max(np.abs(O - P[:occ_points]))) / s.size
            occ_txt = f"{1e6 * t_occ:10.3f} {t_occ / t_gk:6.0f}x"
        out(f"{name:14s} {1e6 * t_gk:13.4f} {1e6 * t_gd:12.2f} {t_gd / t_gk:8.0f}x "
            f"{err:14.2e} {occ_txt} {1e6 * t_d2:13.4f} {1e6 * t_n:13.4f}")
        rows.append(row)
    sp = [r["speedup_vs_geomdl"] for r in rows]
    out(f"speed-up vs geomdl: median {np.median(sp):.0f}x, min {np.min(sp):.0f}x "
        f"(threads: {geomkit_threads()})")
    with tempfile.TemporaryDirectory() as tmp:
        cold = jit_cost(tmp)
        warm = jit_cost(tmp)
    out(f"JIT, fresh cache: import {cold[0]:.2f} s, first evaluate {cold[1]:.2f} s, "
        f"first derivatives {cold[2]:.2f} s, first normals {cold[3]:.2f} s")
    out(f"JIT, warm cache:  import {warm[0]:.2f} s, first evaluate {warm[1]:.2f} s, "
        f"first derivatives {warm[2]:.2f} s, first normals {warm[3]:.2f} s")
    return {"rows": rows, "jit_cold": cold, "jit_warm": warm}


SWEEP_CASES = ("sphere", "torus")


def sweep(sizes=(1_000, 10_000), cases=SWEEP_CASES, repeat=5, seed=1):
    """Rows of the common schema (:mod:`geomkit.bench._common`): for each case with an
    analytic truth and each batch size, the time of one ``evaluate`` call on that many
    random parameters (geomkit after warm-up; OCC ``Geom_BSplineSurface`` in a Python
    loop) and the error of the points: the largest |analytic residual| (distance of
    the returned point from the exact sphere / torus)."""
    from geomkit.bench._common import MISSING_OCC, make_row, median_time, occ_or_none, occ_surface

    occ = occ_or_none()
    rng = np.random.default_rng(seed)
    rows = []
    for name in cases:
        case = samples.load_case(name)
        s, analytic = case.surfaces[0], case.truth["analytic"]
        s.evaluate(np.full((4, 2), 0.5))                      # JIT warm-up
        surf = occ_surface(occ, s) if occ is not None else None
        (u0, u1), (v0, v1) = s.domain
        for n in sizes:
            uv = np.column_stack([rng.uniform(u0, u1, n), rng.uniform(v0, v1, n)])
            t_gk, P, _ = median_time(lambda: s.evaluate(uv), repeat)
            e_gk = np.max(np.abs(samples.analytic_residual(analytic, P)))
            ref = dict(note=MISSING_OCC)
            if surf is not None:
                t_occ, O, _ = median_time(lambda: occ.evaluate(surf, uv), repeat)
                ref = dict(reference_name="OCC Geom_Surface.Value (Python loop)",
                           reference_seconds=t_occ,
                           reference_error=np.max(np.abs(samples.analytic_residual(analytic, O))),
                           note="OCC time is mostly the per-point Python call")
            rows.append(make_row("evaluation", name, "points", int(n), t_gk, e_gk,
                                 repeats=repeat, **ref))
    return rows


def geomkit_threads() -> int:
    import numba
    return numba.get_num_threads()


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--points", type=int, default=100_000)
    ap.add_argument("--geomdl-points", type=int, default=None)
    ap.add_argument("--occ-points", type=int, default=20_000)
    args = ap.parse_args(argv)
    run(args.points, args.geomdl_points, args.occ_points)


if __name__ == "__main__":
    main()
