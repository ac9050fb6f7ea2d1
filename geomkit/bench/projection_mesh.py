"""Exact projection against mesh-only point queries, same points, same run.

For each model (freeform_1, sphere, torus, plate_with_hole, and pyiges' impeller IGES
when pyiges is installed) and two point sets — ``scan`` (points on the surface moved
off it by up to ~1% of the model size, a CMM scan) and ``box`` (uniform in the
model's bounding box) — this times:

* geomkit ``Projector.project`` (exact feet; the candidate mesh build excluded),
  with its stage profile: candidate search (voxel best-first, alone), Newton (the
  batch kernel minus the search), trim feet, finishing (status, normals, signed
  distance: the certification of each answer) and the remaining Python overhead;
* libigl ``point_mesh_squared_distance`` on geomkit's own mesh of chord tolerance
  ``mesh_tol`` (default 1e-3 model units) — it builds its AABB
  tree on every call — and ``igl.AABB.squared_distance`` with the tree built once
  (the like-for-like comparison with a reused :class:`geomkit.Projector`); their
  achieved error is reported against geomkit's exact distance;
* ``trimesh.proximity.closest_point`` on a subset (it is ~100x slower).

Times are medians of ``repeat`` runs; ratios are from the same run.  The machine may
be shared: compare ratios, not absolute times.

Usage: ``python -m geomkit.bench.projection_mesh [--n 100000] [--repeat 3]``
"""

from __future__ import annotations

import argparse
import os
import time
import warnings

import numpy as np

import geomkit
from geomkit import samples

CASES = ("freeform_1", "sphere", "torus", "plate_with_hole", "impeller")
SCAN_OFFSET = 0.01
"""Scan points lie within this fraction of the model size from the surface."""


def load_case(name):
    """Surfaces of a sample case, or of pyiges' impeller (faces read by geomkit today;
    unreadable ones skipped)."""
    if name == "impeller":
        import pyiges

        path = os.path.join(os.path.dirname(pyiges.__file__), "examples", "impeller.igs")
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            return list(geomkit.read_iges(path, skip_invalid=True).surfaces)
    return samples.load(name)


def case_points(surfaces, n, rng):
    """``(scan, box)`` point sets of ``n`` points each (see the module docstring)."""
    lo = np.min([s.bounds[0] for s in surfaces], axis=0)
    hi = np.max([s.bounds[1] for s in surfaces], axis=0)
    size = float(np.linalg.norm(hi - lo))
    m = geomkit.tessellate(surfaces, 1e-2 * size)
    V, F = m.vertices, m.faces
    area = np.linalg.norm(np.cross(V[F[:, 1]] - V[F[:, 0]], V[F[:, 2]] - V[F[:, 0]]), axis=1)
    t = rng.choice(len(F), n, p=area / area.sum())
    r = rng.random((n, 2))
    r[r.sum(1) > 1] = 1 - r[r.sum(1) > 1]
    X = V[F[t, 0]] + r[:, :1] * (V[F[t, 1]] - V[F[t, 0]]) + r[:, 1:] * (V[F[t, 2]] - V[F[t, 0]])
    d = rng.normal(size=(n, 3))
    d *= (rng.uniform(0, SCAN_OFFSET * size, n) / np.linalg.norm(d, axis=1))[:, None]
    return X + d, rng.uniform(lo, hi, (n, 3))


def stage_profile(pr, P, repeat=3):
    """Median seconds of each stage of ``pr.project(P)`` (one chunk per 65,536
    points): ``total``, ``search`` (candidate search alone, same kernel, same
    threads), ``newton`` (batch kernel minus search), ``trim``, ``finish`` and
    ``python`` (the rest), plus the last :class:`~geomkit.query.results.Projection`."""
    from geomkit._kernels import project as pk

    g = pr.grid
    if repeat > 0:  # compile / load every kernel of the stages first (untimed)
        pr.project(P[:256])
        pk.candidates_batch(P[:256], g.vertices, g.faces, pr.fdev, pr.dmax, *g._args(),
                            np.inf, np.empty(min(256, len(P)), dtype=np.int64),
                            np.empty(min(256, len(P))))
    out = {k: [] for k in ("total", "search", "kernel", "trim", "finish")}
    res = None
    for _ in range(repeat):
        t0 = time.perf_counter()
        res = pr.project(P)
        out["total"].append(time.perf_counter() - t0)
        out["kernel"].append(res.stats["time_kernel"])
        out["trim"].append(res.stats["time_trim"])
        out["finish"].append(res.stats["time_finish"])
        k = np.empty(len(P), dtype=np.int64)
        lb = np.empty(len(P))
        t0 = time.perf_counter()
        pk.candidates_batch(P, g.vertices, g.faces, pr.fdev, pr.dmax, *g._args(), np.inf,
                            k, lb)
        out["search"].append(time.perf_counter() - t0)
    m = {k: float(np.median(v)) for k, v in out.items()}
    m["newton"] = max(0.0, m["kernel"] - m["search"])
    m["python"] = max(0.0, m["total"] - m["kernel"] - m["trim"] - m["finish"])
    return m, res


def _med(fn, repeat):
    ts, r = [], None
    for _ in range(repeat):
        t0 = time.perf_counter()
        r = fn()
        ts.append(time.perf_counter() - t0)
    return float(np.median(ts)), r


def run(n=100_000, repeat=3, cases=CASES, mesh_tol=1e-3, trimesh_n=2000, seed=0):
    """Print one table (and return its rows): µs per point and ratios, same run."""
    try:
        import igl
    except ImportError:  # pragma: no cover - optional reference
        igl = None
    try:
        import trimesh
    except ImportError:  # pragma: no cover
        trimesh = None
    rng = np.random.default_rng(seed)
    rows = []
    hdr = (f"{'case':15s} {'pts':4s} | {'gk us':>6s} {'search':>6s} {'newton':>6s} "
           f"{'trim':>5s} {'finish':>6s} {'py':>5s} | {'igl us':>6s} {'gk/igl':>6s} "
           f"{'AABB us':>7s} {'gk/AABB':>7s} {'igl err':>8s} | {'tm us':>6s} {'gk/tm':>6s}"
           f" | newton runs/pt")
    print(hdr, flush=True)
    for name in cases:
        try:
            S = load_case(name)
        except ImportError:
            print(f"{name}: skipped (pyiges not installed)")
            continue
        pr = geomkit.Projector(S)
        pr.project(np.zeros((4, 3)))  # JIT warm-up
        mesh = geomkit.tessellate(S, mesh_tol)
        V = np.ascontiguousarray(mesh.vertices)
        F = np.ascontiguousarray(mesh.faces, dtype=np.int64)
        tree = None
        if igl is not None:
            tree = igl.AABB()
            tree.init(V, F)
        tm = trimesh.Trimesh(V, F, process=False) if (trimesh is not None
                                                      and trimesh_n > 0) else None
        try:
            import rtree  # noqa: F401 - trimesh's closest_point needs it
        except ImportError:
            if tm is not None:
                print("trimesh rows skipped: trimesh.proximity needs rtree (not installed)")
            tm = None
        for label, P in zip(("scan", "box"), case_points(S, n, rng)):
            st, res = stage_profile(pr, P, repeat)
            us = 1e6 / len(P)
            row = dict(case=name, points=label, n=len(P), triangles_mesh=len(F),
                       gk_us=st["total"] * us,
                       **{f"{k}_us": st[k] * us for k in ("search", "newton", "trim",
                                                        "finish", "python")},
                       newton_runs=res.stats["newton_runs"] / len(P))
            if igl is not None:
                t, (d2, _, _) = _med(lambda: igl.point_mesh_squared_distance(P, V, F),
                                     repeat)
                ta, _ = _med(lambda: tree.squared_distance(V, F, P), repeat)
                row.update(igl_us=t * us, aabb_us=ta * us,
                           igl_err=float(np.max(np.abs(np.sqrt(d2) - res.distance))))
            if tm is not None:
                sub = P[:trimesh_n]
                t, _ = _med(lambda: trimesh.proximity.closest_point(tm, sub), 1)
                row["trimesh_us"] = t * 1e6 / len(sub)
            rows.append(row)
            g = row.get
            print(f"{name:15s} {label:4s} | {row['gk_us']:6.2f} {row['search_us']:6.2f} "
                  f"{row['newton_us']:6.2f} {row['trim_us']:5.2f} {row['finish_us']:6.2f} "
                  f"{row['python_us']:5.2f} | {g('igl_us', np.nan):6.2f} "
                  f"{row['gk_us'] / g('igl_us', np.nan):6.2f} {g('aabb_us', np.nan):7.2f} "
                  f"{row['gk_us'] / g('aabb_us', np.nan):7.2f} {g('igl_err', np.nan):8.1e} | "
                  f"{g('trimesh_us', np.nan):6.1f} {row['gk_us'] / g('trimesh_us', np.nan):6.3f}"
                  f" | {row['newton_runs']:.2f}", flush=True)
    return rows


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=100_000)
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--cases", default=",".join(CASES))
    ap.add_argument("--mesh-tol", type=float, default=1e-3)
    ap.add_argument("--trimesh-n", type=int, default=2000)
    a = ap.parse_args(argv)
    run(a.n, a.repeat, a.cases.split(","), a.mesh_tol, a.trimesh_n)


if __name__ == "__main__":
    main()
