"""Warm speed of the ahead-of-time kernels against the JIT's, in one process.

``python tools/aot_bench.py [repeats]``: each job runs alternately with the
ahead-of-time code (:mod:`geomkit._kernels._aot`) and with the JIT dispatchers
(``use_aot(False)``, compiled and warmed first), ``repeats`` times; prints the
medians and their ratio.  The jobs are the demo's steps at the demo's sizes plus a
larger projection.
"""

from __future__ import annotations

import sys
import time

import numpy as np

sys.path.insert(0, str(__import__("pathlib").Path(__file__).resolve().parents[1]))


def _jobs():
    from geomkit import samples
    from geomkit.jobs.deviation import deviation
    from geomkit.cli.demo import PROBE_RADIUS, synthetic_scan
    from geomkit.query.distance import surface_distance
    from geomkit.query.projection import project_points
    from geomkit.section.plane import plane_section
    from geomkit.mesh.tessellate import tessellate

    surf = samples.load("freeform_1")[0]
    C, N, _ = synthetic_scan(surf, 40)
    lo, hi = surf.bounds
    P = lo + (hi - lo) * np.random.default_rng(1).random((20000, 3))
    planes = [np.array([1.0, 0.0, 0.0, -x]) for x in (10, 30, 50, 70, 90)]
    a, b = samples.load("sphere_pair")
    return {
        "tessellate freeform_1 1e-3": lambda: tessellate(surf, 1e-3),
        "deviation (demo scan, 1600 points)": lambda: deviation(surf, C, N,
                                                                probe_radius=PROBE_RADIUS),
        "project_points 20000 points in the box": lambda: project_points(surf, P),
        "plane_section x5 (demo)": lambda: [plane_section(surf, p, 1e-4) for p in planes],
        "surface_distance sphere_pair 1e-9": lambda: surface_distance(a, b, tol=1e-9),
    }


def run(repeats: int = 7) -> dict:
    from geomkit._kernels import _aot

    if not _aot.active():
        raise SystemExit(f"no ahead-of-time kernels: {_aot.status}")
    jobs = _jobs()
    for f in jobs.values():  # compile the JIT side, warm both
        with _aot.use_aot(False):
            f()
        f()
    res = {}
    for name, f in jobs.items():
        ta, tj = [], []
        for _ in range(repeats):
            t = time.perf_counter()
            f()
            ta.append(time.perf_counter() - t)
            with _aot.use_aot(False):
                t = time.perf_counter()
                f()
                tj.append(time.perf_counter() - t)
        res[name] = (float(np.median(ta)), float(np.median(tj)))
        print(f"{name:42s} aot {res[name][0] * 1e3:9.2f} ms  jit {res[name][1] * 1e3:9.2f} ms"
              f"  aot/jit {res[name][0] / res[name][1]:.3f}", flush=True)
    return res


if __name__ == "__main__":
    run(int(sys.argv[1]) if len(sys.argv) > 1 else 7)
