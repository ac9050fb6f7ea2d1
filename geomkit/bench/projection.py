"""Point projection against Open CASCADE, same run.

For each case: N random points in the surface's box grown by ``--margin`` (default 10:
points within +-10 of the box), and N near-surface points (surface samples moved along the normal by
a N(0, 0.05) offset, the CMM situation).  geomkit ``project_points`` (after JIT
warm-up; the candidate mesh build is timed separately) against, on a subset,
``GeomAPI_ProjectPointOnSurf`` (orthogonal feet only, OCC's point projector) and
``BRepExtrema_DistShapeShape`` on the (trimmed) face (boundary feet too).  Errors
against the analytic distance where the case has one, otherwise against the best of
all answers, each taken as the distance of a real surface point (OCC's by the
surface point at its returned parameters, since its reported foot can lie slightly
off the patch), so the smallest is the closest to the truth.  Then a
speed-versus-error sweep over geomkit's Newton tolerance.

Usage: ``python -m geomkit.bench.projection [--n 100000] [--occ-n 1000]``
"""

from __future__ import annotations

import argparse
import time

import numpy as np

import geomkit
from geomkit import samples

CASES = ["sphere", "torus", "cylinder_quarter", "plate_with_hole", "saddle", "freeform_1",
         "heavy_weights", "crease"]


def analytic_distance(name, P):
    """Exact distances where the case has a closed form (None otherwise)."""
    if name == "sphere":
        return np.abs(np.linalg.norm(P, axis=1) - 10.0)
    if name == "torus":
        return np.abs(np.hypot(np.hypot(P[:, 0], P[:, 1]) - 20.0, P[:, 2]) - 5.0)
    if name == "plate_with_hole":
        x, y, z = P.T
        dx = np.maximum(0, np.maximum(-x, x - 100))
        dy = np.maximum(0, np.maximum(-y, y - 100))
        rho = np.hypot(x - 50, y - 50)
        dxy = np.where(rho < 20, 20 - rho, np.hypot(dx, dy))
        return np.hypot(dxy, z)
    return None


def _points(s, n, margin, rng):
    lo, hi = s.bounds
    box = rng.uniform(lo - margin, hi + margin, (n, 3))
    (u0, u1), (v0, v1) = s.domain
    uv = np.c_[rng.uniform(u0, u1, n), rng.uniform(v0, v1, n)]
    if s.is_trimmed:
        uv = uv[geomkit.classify_uv(s, uv) == geomkit.INSIDE]
    X = geomkit.evaluate(s, uv)
    near = X + geomkit.normals(s, uv) * rng.normal(0, 0.05, (len(uv), 1))
    return box, near


def _occ_run(occ, s, P):
    """OCC distances, and the distances of the surface points at OCC's parameters
    (OCC's reported foot can lie off the patch: on `crease` GeomAPI_ProjectPointOnSurf
    returned y = 15.00000001 where the surface's maximum is 15)."""
    face = occ.make_face(s.degree_u, s.degree_v, s.knots_u, s.knots_v, s.control_points,
                         s.weights, trim=[[c.to_dict() for c in loop.pieces]
                                          for loop in s.trim] or None)
    surf = occ.make_surface(s.degree_u, s.degree_v, s.knots_u, s.knots_v, s.control_points,
                            s.weights)
    t0 = time.perf_counter()
    orth = [occ.project_point(surf, p, include_boundary=False) for p in P]
    t_orth = (time.perf_counter() - t0) / len(P)
    t0 = time.perf_counter()
    fc = [occ.project_point(face, p) for p in P]
    t_face = (time.perf_counter() - t0) / len(P)
    (u0, u1), (v0, v1) = s.domain

    def real(res):
        uv = np.array([r[2] for r in res], dtype=float)
        uv[:, 0] = np.clip(uv[:, 0], u0, u1)
        uv[:, 1] = np.clip(uv[:, 1], v0, v1)
        ok = np.isfinite(uv).all(axis=1)
        d = np.full(len(res), np.inf)
        d[ok] = np.linalg.norm(geomkit.evaluate(s, uv[ok]) - P[ok], axis=1)
        return np.array([r[0] for r in res]), d

    d_orth, real_orth = real(orth)
    d_face, real_face = real(fc)
    return d_orth, t_orth, d_face, t_face, np.minimum(real_orth, real_face)


def run(n=100_000, occ_n=1000, margin=10.0, cases=CASES, seed=0):
    try:
        from geomkit.bench.oracles import occ
        have_occ = occ.HAVE_OCP
    except ImportError:  # pragma: no cover
        have_occ = False
    rng = np.random.default_rng(seed)
    rows = []
    print(f"{'case':16s} {'points':7s} {'build s':>7s} {'gk us/pt':>8s} {'gk max err':>10s} "
          f"{'edge%':>5s} | {'ProjPt us':>9s} {'ratio':>6s} {'ProjPt err':>10s} | "
          f"{'DistSS us':>9s} {'ratio':>6s} {'DistSS err':>10s} {'gk>best':>8s}")
    for name in cases:
        s = samples.load(name)[0]
        t0 = time.perf_counter()
        pr = geomkit.Projector(s)
        build = time.perf_counter() - t0
        pr.project(np.zeros((8, 3)))  # JIT warm-up
        for label, P in zip(("box", "near"), _points(s, n, margin, rng)):
            t0 = time.perf_counter()
            res = pr.project(P)
            t_gk = (time.perf_counter() - t0) / len(P)
            exact = analytic_distance(name, P)
            row = dict(case=name, points=label, n=len(P), build_s=build, gk_us=t_gk * 1e6,
                       edge=float(np.mean(res.status != geomkit.query.results.INTERIOR)))
            sub = np.arange(min(occ_n, len(P)))
            ref = exact
            if have_occ:
                d_orth, t_orth, d_face, t_face, d_real = _occ_run(occ, s, P[sub])
                row.update(orth_us=t_orth * 1e6, face_us=t_face * 1e6)
                if ref is None:  # the best real surface point of all answers (subset)
                    ref = np.full(len(P), np.nan)
                    ref[sub] = np.minimum(res.distance[sub], d_real)
                row.update(orth_err=float(np.nanmax(np.abs(d_orth - ref[sub]))),
                           face_err=float(np.nanmax(np.abs(d_face - ref[sub]))))
                row["gk_above_best"] = float(np.nanmax(res.distance[sub] - ref[sub]))
            if ref is not None:
                row["gk_err"] = float(np.nanmax(np.abs(res.distance - ref)))
            rows.append(row)
            f = lambda k, fmt: (fmt % row[k]) if k in row else "-"
            print(f"{name:16s} {label:7s} {build:7.2f} {row['gk_us']:8.2f} "
                  f"{f('gk_err', '%10.1e'):>10s} {100 * row['edge']:5.1f} | "
                  f"{f('orth_us', '%9.0f'):>9s} "
                  f"{(row['orth_us'] / row['gk_us']) if 'orth_us' in row else 0:6.0f} "
                  f"{f('orth_err', '%10.1e'):>10s} | {f('face_us', '%9.0f'):>9s} "
                  f"{(row['face_us'] / row['gk_us']) if 'face_us' in row else 0:6.0f} "
                  f"{f('face_err', '%10.1e'):>10s} {f('gk_above_best', '%8.1e'):>8s}",
                  flush=True)
    # speed against error: geomkit's Newton tolerance
    print("\nspeed vs error (sphere and torus, box points, analytic truth)")
    print(f"{'tol':>8s} {'sphere us/pt':>12s} {'max err':>9s} {'torus us/pt':>12s} {'max err':>9s}")
    sweep = []
    prs = {c: geomkit.Projector(samples.load(c)[0]) for c in ("sphere", "torus")}
    pts = {c: _points(samples.load(c)[0], n // 2, margin, rng)[0] for c in prs}
    for tol in (1e-3, 1e-4, 1e-6, 1e-8, 1e-10, 1e-12):
        out = [tol]
        for c in ("sphere", "torus"):
            t0 = time.perf_counter()
            res = prs[c].project(pts[c], tol=tol)
            dt = (time.perf_counter() - t0) / len(pts[c]) * 1e6
            err = float(np.max(np.abs(res.distance - analytic_distance(c, pts[c]))))
            out += [dt, err]
        sweep.append(out)
        print(f"{tol:8.0e} {out[1]:12.2f} {out[2]:9.1e} {out[3]:12.2f} {out[4]:9.1e}",
              flush=True)
    return rows, sweep


def _occ_orth(surf, P, tol):
    """Distances by ``GeomAPI_ProjectPointOnSurf`` with Extrema tolerance ``tol``
    (orthogonal feet over the whole patch; one Python call per point)."""
    from OCP.GeomAPI import GeomAPI_ProjectPointOnSurf
    from OCP.gp import gp_Pnt

    u0, u1, v0, v1 = surf.Bounds()
    out = np.full(len(P), np.nan)
    for i, p in enumerate(P):
        pr = GeomAPI_ProjectPointOnSurf(gp_Pnt(*map(float, p)), surf, u0, u1, v0, v1,
                                        float(tol))
        if pr.IsDone() and pr.NbPoints() > 0:
            out[i] = pr.LowerDistance()
    return out


SWEEP_CASES = ("sphere", "torus")


def sweep(cases=SWEEP_CASES, tols=(1e-3, 1e-6, 1e-9, 1e-12), n=4_000, occ_n=100,
          margin=10.0, repeat=3, seed=0, mesh_cases=(), mesh_n=2_000, trimesh_n=200):
    """Rows of the common schema (:mod:`geomkit.bench._common`): for each case with a
    closed-form distance and each Newton tolerance, seconds per point of
    ``Projector.project`` (``n`` random points in the box grown by ``margin``, after
    warm-up; the candidate mesh build is not timed) and of ``GeomAPI_ProjectPointOnSurf``
    at the same Extrema tolerance on the first ``occ_n`` points; errors are the
    largest |distance - analytic distance| (geomkit over all ``n`` points, OCC over
    its subset).  ``mesh_cases``: also the mesh-query rows of :func:`mesh_sweep`
    (libigl per call and with a prebuilt tree, trimesh) on ``mesh_n`` points."""
    from geomkit.bench._common import MISSING_OCC, make_row, median_time, occ_or_none, occ_surface

    occ = occ_or_none()
    rng = np.random.default_rng(seed)
    rows = []
    for name in cases:
        s = samples.load(name)[0]
        pr = geomkit.Projector(s)
        pr.project(np.zeros((8, 3)))                          # JIT warm-up
        P = _points(s, n, margin, rng)[0]
        exact = analytic_distance(name, P)
        surf = occ_surface(occ, s) if occ is not None else None
        if surf is not None:
            _occ_orth(surf, P[:2], 1e-6)
        for tol in tols:
            t, res, _ = median_time(lambda: pr.project(P, tol=tol), repeat)
            err = np.max(np.abs(res.distance - exact))
            ref = dict(note=MISSING_OCC)
            if surf is not None:
                sub = P[:occ_n]
                t_occ, d, k = median_time(lambda: _occ_orth(surf, sub, tol), repeat, 2.0)
                ref = dict(reference_name="OCC GeomAPI_ProjectPointOnSurf",
                           reference_seconds=t_occ / len(sub),
                           reference_error=np.nanmax(np.abs(d - exact[:occ_n])),
                           note=f"OCC on {len(sub)} of the {len(P)} points (Python loop), "
                                f"{k} runs; {int(np.isnan(d).sum())} without answer")
            rows.append(make_row("projection", name, "tol", tol, t / len(P), err,
                                 per="point", repeats=repeat, **ref))
    if mesh_cases:
        rows += mesh_sweep(mesh_cases, mesh_n, repeat, seed, trimesh_n)
    return rows


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=100_000)
    ap.add_argument("--occ-n", type=int, default=1000)
    ap.add_argument("--margin", type=float, default=10.0)
    ap.add_argument("--cases", default=",".join(CASES))
    ap.add_argument("--mesh", action="store_true",
                    help="instead: geomkit vs libigl / trimesh mesh queries with the stage "
                         "profile (geomkit.bench.projection_mesh)")
    a = ap.parse_args(argv)
    if a.mesh:
        from geomkit.bench.projection_mesh import run as run_mesh
        run_mesh(a.n)
        return
    run(a.n, a.occ_n, a.margin, a.cases.split(","))


def mesh_sweep(cases=("freeform_1", "sphere", "torus", "plate_with_hole", "impeller"),
               n=10_000, repeat=3, seed=0, trimesh_n=200):
    """Rows of the common schema: geomkit's exact ``project`` beside the mesh-only
    queries on a 1e-3 mesh of the same faces (their error against geomkit's exact
    distance in ``reference_error``), scan and box points
    (:mod:`geomkit.bench.projection_mesh`; cases it cannot load are skipped): one row
    per reference — libigl ``point_mesh_squared_distance`` (tree built per call),
    libigl ``AABB.squared_distance`` (tree built once) and trimesh
    ``proximity.closest_point`` (on the first ``trimesh_n`` points; it needs rtree)."""
    from geomkit.bench._common import make_row
    from geomkit.bench.projection_mesh import run as run_mesh

    refs = (("igl_us", "libigl point_mesh_squared_distance (1e-3 mesh)", "igl_err"),
            ("aabb_us", "libigl AABB, tree prebuilt (1e-3 mesh)", "igl_err"),
            ("trimesh_us", f"trimesh closest_point (1e-3 mesh, {trimesh_n} points)", None))
    rows = []
    for r in run_mesh(n, repeat, cases, seed=seed, trimesh_n=trimesh_n):
        note = (f"stages search/newton/trim/finish us {r['search_us']:.2f}/"
                f"{r['newton_us']:.2f}/{r['trim_us']:.2f}/{r['finish_us']:.2f}")
        for key, ref_name, err_key in refs:
            if key not in r:
                continue
            rows.append(make_row("projection", f"{r['case']}/{r['points']}", "mesh_tol",
                                 1e-3, r["gk_us"] * 1e-6, None, per="point",
                                 repeats=repeat, note=note, reference_name=ref_name,
                                 reference_seconds=r[key] * 1e-6,
                                 reference_error=r.get(err_key) if err_key else None))
    return rows


if __name__ == "__main__":
    main()
