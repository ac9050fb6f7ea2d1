"""Tessellation against Open CASCADE ``BRepMesh_IncrementalMesh``, same run.

For each case and absolute tolerance: geomkit (after JIT warm-up) and OCC at the same
deflection (angular deflection 0.5 rad, OCC's usual default); triangle counts, time,
and the deviation of *both* meshes measured by the same independent sampler
(:func:`sampled_deviation`).  Also the deviation geomkit itself reports.

Usage: ``python -m geomkit.bench.tessellate [--tols 1e-2,1e-3] [--cases a,b]``
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from geomkit import samples, tessellate
from geomkit.nurbs.evaluation import derivatives, evaluate

CASES = ["sphere", "torus", "cylinder_quarter", "freeform_1", "crease", "wave_seed003",
         "heavy_weights", "saddle", "plate_with_hole", "offset_planes"]


def sampled_deviation(surface, V, F, FUV, per_face=12, max_faces=40_000, seed=0,
                      distance=None):
    """Largest two-sided deviation of a mesh from its surface at random samples.

    For random barycentric points of (a subset of) the faces: the triangle point
    ``X`` and the surface point ``P = S(uv)`` at the interpolated UV.  The value is
    ``max(dist(P, triangle plane), dist(X, surface))`` where ``dist(X, surface)`` is
    taken from above by ``|X - S(uv*)|`` after 4 Gauss–Newton steps from ``uv``.
    ``FUV`` (m, 3, 2) are the UVs of each face's corners.  ``distance``, when given,
    maps (n, 3) points to their exact distances from the surface (an analytic
    truth) and replaces the Gauss–Newton estimate of ``dist(X, surface)``.
    """
    rng = np.random.default_rng(seed)
    m = len(F)
    idx = rng.choice(m, size=min(m, max_faces), replace=False) if m > max_faces else np.arange(m)
    tri_uv = FUV[idx]
    tri_x = V[F[idx]]
    (u0, u1), (v0, v1) = surface.domain
    b = rng.dirichlet([1.0, 1.0, 1.0], size=(len(tri_uv), per_face))
    uv = np.einsum("fsk,fkd->fsd", b, tri_uv).reshape(-1, 2)
    X = np.einsum("fsk,fkd->fsd", b, tri_x).reshape(-1, 3)
    P = evaluate(surface, uv)
    # dist(P, triangle): distance to the triangle's plane, bounded below by 0; for the
    # sample inside the triangle's own UV image the plane distance is the distance
    # when the foot lies inside, which holds for these small, flat triangles; take
    # the point-to-point gap as a safe upper bound otherwise
    Tx = np.repeat(tri_x, per_face, axis=0)
    n = np.cross(Tx[:, 1] - Tx[:, 0], Tx[:, 2] - Tx[:, 0])
    ln = np.linalg.norm(n, axis=1)
    good = ln > 0
    plane = np.where(good, np.abs(np.einsum("ij,ij->i", P - Tx[:, 0], n) / np.where(good, ln, 1)),
                     np.linalg.norm(P - X, axis=1))
    if distance is not None:
        best = np.asarray(distance(X), float)
        return float(np.max(np.maximum(plane, best))) if len(best) else 0.0
    # dist(X, surface) from above
    w = uv.copy()
    best = np.linalg.norm(X - P, axis=1)
    for _ in range(4):
        D = derivatives(surface, w, 1)
        r = X - D[:, 0, 0]
        J = np.stack([D[:, 1, 0], D[:, 0, 1]], axis=2)  # (n, 3, 2)
        A = np.einsum("nki,nkj->nij", J, J)
        g = np.einsum("nki,nk->ni", J, r)
        det = A[:, 0, 0] * A[:, 1, 1] - A[:, 0, 1] ** 2
        safe = det > 0
        det = np.where(safe, det, 1.0)
        du = np.where(safe, (A[:, 1, 1] * g[:, 0] - A[:, 0, 1] * g[:, 1]) / det, 0)
        dv = np.where(safe, (A[:, 0, 0] * g[:, 1] - A[:, 0, 1] * g[:, 0]) / det, 0)
        w[:, 0] = np.clip(w[:, 0] + du, u0, u1)
        w[:, 1] = np.clip(w[:, 1] + dv, v0, v1)
        best = np.minimum(best, np.linalg.norm(X - evaluate(surface, w), axis=1))
    return float(np.max(np.maximum(plane, best))) if len(best) else 0.0


def _geomkit(s, tol):
    t0 = time.perf_counter()
    m = tessellate(s, tol)
    dt = time.perf_counter() - t0
    return m.vertices, m.faces, m.face_uv, dt, m.max_deviation


def _occ(face, tol, occ):
    V, F, UV, dt = occ.mesh(face, tol, angle=0.5)
    return V, F, UV[F], dt


def _repeats(seconds: float, repeat: int) -> int:
    """Runs for a call that took ``seconds`` once: ``repeat``, three times as many for
    calls of milliseconds, fewer for slow calls (at least 3: a median of three)."""
    if seconds < 0.02:  # milliseconds: more runs against the noise of a shared machine
        return 3 * repeat
    return repeat if seconds < 0.2 else max(3, min(repeat, int(2.0 / max(seconds, 1e-9))))


def run(cases=CASES, tols=(1e-2, 1e-3), out=print, repeat=15):
    """Print one row per case and tolerance: medians of interleaved repeats (geomkit,
    then OCC, alternately, so load from other jobs hits both alike)."""
    try:
        from geomkit.bench.oracles import occ
        have_occ = occ.HAVE_OCP
    except Exception:  # pragma: no cover - optional
        have_occ = False
    # warm-up: compile every kernel once
    tessellate(samples.load("plate_with_hole"), 1e-1)
    tessellate(samples.load("sphere"), 1e-1)
    out(f"{'case':16s} {'tol':>7s} | {'gk faces':>9s} {'gk s':>7s} {'gk dev/tol':>10s} "
        f"{'(reported)':>10s} | {'occ faces':>9s} {'occ s':>7s} {'occ dev/tol':>11s} | "
        f"{'faces ratio':>11s} {'time ratio':>10s}")
    rows = []
    for name in cases:
        s = samples.load(name)[0]
        face = None
        if have_occ:
            face = occ.make_face(s.degree_u, s.degree_v, s.knots_u, s.knots_v,
                                 s.control_points, s.weights,
                                 trim=[[c.to_dict() for c in lp.pieces] for lp in s.trim] or None)
        for tol in tols:
            V, F, UV, dt, rep = _geomkit(s, tol)
            n = _repeats(dt, repeat)
            ts, ots = [dt], []
            for i in range(n):
                if have_occ:
                    oV, oF, oUV, odt = _occ(face, tol, occ)
                    ots.append(odt)
                if i + 1 < n:
                    ts.append(_geomkit(s, tol)[3])
            dt = float(np.median(ts))
            dev = sampled_deviation(s, V, F, UV)
            row = {"case": name, "tol": tol, "gk_faces": len(F), "gk_s": dt,
                   "gk_dev": dev, "gk_reported": rep, "repeats": n}
            occ_txt = f"{'-':>9s} {'-':>7s} {'-':>11s} | {'-':>11s} {'-':>10s}"
            if have_occ:
                odt = float(np.median(ots))
                odev = sampled_deviation(s, oV, oF, oUV)
                row.update(occ_faces=len(oF), occ_s=odt, occ_dev=odev)
                occ_txt = (f"{len(oF):9d} {odt:8.4f} {odev / tol:11.3f} | "
                           f"{len(F) / max(len(oF), 1):11.2f} {dt / max(odt, 1e-9):10.2f}")
            out(f"{name:16s} {tol:7.0e} | {len(F):9d} {dt:8.4f} {dev / tol:10.3f} "
                f"{rep / tol:10.3f} | {occ_txt}")
            rows.append(row)
    if have_occ:
        fr = [r["gk_faces"] / r["occ_faces"] for r in rows]
        tr = [r["gk_s"] / r["occ_s"] for r in rows]
        out(f"median faces ratio geomkit/OCC {np.median(fr):.2f}, median time ratio "
            f"{np.median(tr):.2f}; OCC meshes over tol: "
            f"{sum(r['occ_dev'] > r['tol'] for r in rows)}/{len(rows)}, geomkit: "
            f"{sum(r['gk_dev'] > r['tol'] for r in rows)}/{len(rows)}")
    return rows


SWEEP_CASES = ("sphere", "torus")


def _truth(name):
    """Exact point-to-surface distance of a case with an analytic truth, else None."""
    truth = samples.load_case(name).truth or {}
    if "analytic" not in truth:
        return None
    return lambda X: np.abs(samples.analytic_residual(truth["analytic"], X))


def sweep(cases=SWEEP_CASES, tols=(1e-1, 3e-2, 1e-2), repeat=3, angle=0.5, budget=0.5):
    """Rows of the common schema (:mod:`geomkit.bench._common`): for each case and
    absolute tolerance, the wall time of one tessellation (geomkit after warm-up;
    OCC ``BRepMesh_IncrementalMesh`` at the same deflection, angular ``angle``) and
    the achieved deviation of each mesh by the same sampler
    (:func:`sampled_deviation`), exact for cases with an analytic truth.  Timed
    ``repeat`` times, fewer once geomkit's runs exceed ``budget`` seconds (OCC gets
    as many runs as geomkit; its time is ``BRepMesh_IncrementalMesh`` alone, without
    reading the triangulation back into Python).  The two are timed alternately, run
    by run, so that a change in the machine's load hits both alike."""
    from geomkit.bench._common import MISSING_OCC, make_row, median_time, occ_face, occ_or_none

    occ = occ_or_none()
    tessellate(samples.load("sphere"), 1e-1)                  # JIT warm-up
    tessellate(samples.load("plate_with_hole"), 1e-1)
    rows = []
    for name in cases:
        s = samples.load(name)[0]
        exact = _truth(name)
        face = occ_face(occ, s) if occ is not None else None
        for tol in tols:
            tg, ts = [], []
            for _ in range(max(1, int(repeat))):       # alternately, as many runs each
                t_gk, m, _ = median_time(lambda: tessellate(s, tol), 1)
                tg.append(t_gk)
                if face is not None:
                    oV, oF, oUV, odt = occ.mesh(face, tol, angle=angle)
                    ts.append(odt)
                if budget is not None and sum(tg) > budget:
                    break
            t_gk, n_gk = float(np.median(tg)), len(tg)
            dev = sampled_deviation(s, m.vertices, m.faces, m.face_uv, distance=exact)
            note = f"{len(m.faces)} triangles"
            ref = {}
            if face is not None:
                odev = sampled_deviation(s, oV, oF, oUV[oF], distance=exact)
                ref = dict(reference_name="OCC BRepMesh_IncrementalMesh",
                           reference_seconds=float(np.median(ts)), reference_error=odev)
                note += f" vs OCC {len(oF)}"
            else:
                note += "; " + MISSING_OCC
            note += "; error " + ("exact (analytic) at samples" if exact else
                                  "by the shared Gauss-Newton sampler")
            rows.append(make_row("tessellate", name, "tol", tol, t_gk, dev, repeats=n_gk,
                                 note=note, **ref))
    return rows


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--tols", default="1e-2,1e-3")
    ap.add_argument("--cases", default=",".join(CASES))
    ap.add_argument("--repeat", type=int, default=15,
                    help="timed runs per row (fewer, at least 3, for calls over 0.2 s)")
    ap.add_argument("--markdown", action="store_true",
                    help="also print the rows as a markdown table (docs/benchmarks.md)")
    a = ap.parse_args(argv)
    rows = run(a.cases.split(","), [float(t) for t in a.tols.split(",")], repeat=a.repeat)
    if a.markdown:
        print(markdown(rows))


def _ms(t: float) -> str:
    return f"{t * 1e3:.3g} ms" if t < 1 else f"{t:.3g} s"


def markdown(rows) -> str:
    """The rows of :func:`run` as the table of docs/benchmarks.md."""
    out = ["| case | tol | geomkit faces | time | sampled dev/tol | reported | OCC faces "
           "| OCC time | OCC dev/tol | faces ratio | time ratio | runs |",
           "|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        occ = ("| - | - | - | - | -" if "occ_s" not in r else
               f"| {r['occ_faces']:,} | {_ms(r['occ_s'])} | {r['occ_dev'] / r['tol']:.2f} "
               f"| {r['gk_faces'] / max(r['occ_faces'], 1):.2f} "
               f"| {r['gk_s'] / r['occ_s']:.2f}")
        out.append(f"| {r['case']} | {r['tol']:.0e} | {r['gk_faces']:,} | {_ms(r['gk_s'])} "
                   f"| {r['gk_dev'] / r['tol']:.2f} | {r['gk_reported'] / r['tol']:.2f} {occ} "
                   f"| {r['repeats']} |")
    return "\n".join(out)


if __name__ == "__main__":
    main()
