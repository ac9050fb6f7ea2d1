"""Plane sections against Open CASCADE, same run: ``BRepAlgoAPI_Section`` and
``GeomAPI_IntSS``.

For each case and plane: median wall time of geomkit (after JIT warm-up), of
``BRepAlgoAPI_Section.Build`` and of ``GeomAPI_IntSS``; the number of curves / points
each finds; and for each the largest plane residual and the largest distance to the
surface (``GeomAPI_ProjectPointOnSurf`` via :func:`geomkit.bench.oracles.occ.project_point`
on up to 60 points per curve, the same projection for all three).  Then a tolerance
sweep of geomkit (time, points, achieved chord error).

Usage: ``python -m geomkit.bench.section [--repeat 5]``; ``--impeller``: pyiges'
impeller.igs (277 faces) at five planes, geomkit beside BRepAlgoAPI_Section
(:func:`impeller`).
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from geomkit import plane_section, samples

CASES = [
    ("sphere_plane_cut", 0, [0, 0, 1, -6.0]),
    ("sphere", 0, [0, 0, 1, -10.0]),
    ("sphere", 0, [0, 0, 1, -(10 - 1e-7)]),
    ("sphere", 0, [0.3, -0.5, 0.8, -2.0]),
    ("torus", 0, [1, 0, 0, 0.0]),
    ("saddle", 0, [0, 0, 1, 0.0]),
    ("wave_seed003", 0, [-0.5407575913134987, 0.0, 0.8411784753765534, -21.630303652539943]),
    ("freeform_1", 0, [0.3, 0.2, 1.0, -20.0]),
    ("heavy_weights", 0, [0, 0, 1, -0.5]),
    ("crease", 0, [1, 0, 0, -20.0]),
]


def _median_time(fn, repeat):
    ts, out = [], None
    for _ in range(repeat):
        t0 = time.perf_counter()
        out = fn()
        ts.append(time.perf_counter() - t0)
    return float(np.median(ts)), out


def _residuals(occ, gsurf, plane, polys):
    if not polys:
        return float("nan"), float("nan")
    n = np.asarray(plane[:3], float)
    d = float(plane[3]) / np.linalg.norm(n)
    n = n / np.linalg.norm(n)
    X = np.concatenate(polys)
    pr = float(np.abs(X @ n + d).max())
    sub = np.concatenate([P[:: max(1, len(P) // 60)] for P in polys])
    res = occ.project_point(gsurf, sub, include_boundary=False)
    dist = res[0]
    return pr, float(np.max(np.atleast_1d(dist)))


def run(repeat=5, tol=1e-6, out=print):
    from geomkit.bench.oracles import occ, occ_section

    have = occ.HAVE_OCP
    plane_section(samples.load("sphere"), [0, 0, 1, -3], 1e-3)   # JIT warm-up
    plane_section(samples.load("sphere"), [0, 0, 1, -10], 1e-3)
    out(f"tol {tol:g}; times are medians of {repeat}; residuals: plane | surface distance")
    out(f"{'case':18s} {'plane':>24s} | {'gk ms':>7s} {'n':>5s} {'plane':>8s} {'surf':>8s} | "
        f"{'BRep ms':>7s} {'n':>3s} {'plane':>8s} {'surf':>8s} | {'IntSS ms':>8s} {'n':>3s} "
        f"{'plane':>8s} {'surf':>8s} | {'gk/BRep':>7s} {'gk/IntSS':>8s}")
    rows = []
    for name, idx, plane in CASES:
        s = samples.load(name)[idx]
        tg, sec = _median_time(lambda: plane_section(s, plane, tol), repeat)
        gk_n = f"{len(sec.curves)}c{len(sec.points)}p"
        row = {"case": name, "plane": plane, "gk_s": tg, "gk_curves": len(sec.curves),
               "gk_points": len(sec.points)}
        txt = f"{name:18s} {str(np.round(plane, 3).tolist()):>24s} | {tg * 1e3:7.1f} {gk_n:>5s} "
        if have:
            gs = occ.make_surface(s.degree_u, s.degree_v, s.knots_u, s.knots_v,
                                  s.control_points, s.weights)
            gpr, gsr = _residuals(occ, gs, plane, sec.curves + ([sec.points] if len(sec.points)
                                                                 else []))
            txt += f"{gpr:8.1e} {gsr:8.1e} | "
            face = occ.make_face(s.degree_u, s.degree_v, s.knots_u, s.knots_v,
                                 s.control_points, s.weights)
            tb, (bp, _) = _median_time(lambda: occ.section(face, plane, deflection=tol), repeat)
            bpr, bsr = _residuals(occ, gs, plane, bp)
            ti, (ip, _) = _median_time(lambda: occ_section.intss(gs, plane, 1e-7, tol), repeat)
            ipr, isr = _residuals(occ, gs, plane, ip)
            txt += (f"{tb * 1e3:7.1f} {len(bp):3d} {bpr:8.1e} {bsr:8.1e} | {ti * 1e3:8.1f} "
                    f"{len(ip):3d} {ipr:8.1e} {isr:8.1e} | {tg / tb:7.2f} {tg / ti:8.2f}")
            row.update(brep_s=tb, brep_n=len(bp), intss_s=ti, intss_n=len(ip), gk_plane=gpr,
                       gk_surf=gsr, brep_plane=bpr, brep_surf=bsr, intss_plane=ipr,
                       intss_surf=isr)
        out(txt)
        rows.append(row)
    if have:
        out(f"median time ratio geomkit/BRepAlgoAPI_Section "
            f"{np.median([r['gk_s'] / r['brep_s'] for r in rows]):.2f}, geomkit/GeomAPI_IntSS "
            f"{np.median([r['gk_s'] / r['intss_s'] for r in rows]):.2f}")
    out("")
    out("tolerance sweep (wave_seed003, Paper 2 plane; sphere_plane_cut z=6)")
    out(f"{'case':18s} {'tol':>7s} {'ms':>8s} {'points':>7s} {'chord err':>9s} {'residual':>9s}")
    for name, idx, plane in (CASES[6], CASES[0]):
        s = samples.load(name)[idx]
        for t in (1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10):
            dt, sec = _median_time(lambda: plane_section(s, plane, t), max(1, repeat // 2))
            npts = sum(len(c) for c in sec.curves)
            out(f"{name:18s} {t:7.0e} {dt * 1e3:8.1f} {npts:7d} {sec.max_chord_error:9.2e} "
                f"{sec.max_residual:9.1e}")
    return rows


def _unit_plane(plane):
    n = np.asarray(plane[:3], float)
    return n / np.linalg.norm(n), float(plane[3]) / np.linalg.norm(n)


def exact_circles(name, plane):
    """The exact section of the sphere (radius 10 at the origin) with any plane, and of
    the torus (R 20, r 5 about z) with the plane x = 0: a list of (centre, radius)."""
    n, d = _unit_plane(plane)
    if name == "sphere":
        return [(-d * n, float(np.sqrt(100.0 - d * d)))]
    if name == "torus" and np.allclose(n, [1, 0, 0]) and d == 0:
        return [(np.array([0.0, 20.0, 0.0]), 5.0), (np.array([0.0, -20.0, 0.0]), 5.0)]
    raise ValueError(f"no exact section for {name} with plane {plane}")


def circle_error(polys, plane, circles):
    """Largest distance of a polyline set from the exact section circles (all in
    ``plane``), over the vertices and the segment midpoints (a chord's largest
    deviation from its arc is at its midpoint); inf when nothing was found."""
    if not polys:
        return float("inf")
    n, d = _unit_plane(plane)
    X = np.concatenate([np.concatenate([P, 0.5 * (P[1:] + P[:-1])]) for P in polys])
    h = X @ n + d
    best = np.full(len(X), np.inf)
    for c, r in circles:
        Y = X - c - np.outer(X @ n + d, n)
        best = np.minimum(best, np.hypot(h, np.linalg.norm(Y, axis=1) - r))
    return float(best.max())


SWEEP_CASES = (("sphere", [0.3, -0.5, 0.8, -2.0]), ("torus", [1.0, 0.0, 0.0, 0.0]))


def sweep(cases=SWEEP_CASES, tols=(1e-3, 1e-5, 1e-7), repeat=5):
    """Rows of the common schema (:mod:`geomkit.bench._common`): for each case with an
    exact section (circles) and each chord tolerance, the median time of
    ``plane_section`` (after warm-up) and of ``BRepAlgoAPI_Section`` with its edges
    discretised at the same deflection (:func:`geomkit.bench.oracles.occ.section`, whole
    call, so it includes reading the points back into Python); errors are the largest
    distances of the polylines from the exact circles (:func:`circle_error`)."""
    from geomkit.bench._common import MISSING_OCC, make_row, median_time, occ_face, occ_or_none

    occ = occ_or_none()
    plane_section(samples.load("sphere"), [0, 0, 1, -3], 1e-3)   # JIT warm-up
    rows = []
    for name, plane in cases:
        s = samples.load(name)[0]
        circles = exact_circles(name, plane)
        face = occ_face(occ, s) if occ is not None else None
        plane_section(s, plane, tols[0])                      # warm-up of this case
        if face is not None:
            occ.section(face, plane, deflection=tols[0])
        for tol in tols:
            t, sec, k = median_time(lambda: plane_section(s, plane, tol), repeat, 1.0)
            err = circle_error(sec.curves, plane, circles)
            note = f"{sum(len(c) for c in sec.curves)} points"
            ref = {}
            if face is not None:
                tb, (bp, _), _ = median_time(lambda: occ.section(face, plane, deflection=tol),
                                             k)
                ref = dict(reference_name="OCC BRepAlgoAPI_Section",
                           reference_seconds=tb, reference_error=circle_error(bp, plane, circles))
                note += f" vs OCC {sum(len(c) for c in bp)}"
            else:
                note += "; " + MISSING_OCC
            rows.append(make_row("section", f"{name} {np.round(plane, 2).tolist()}", "tol",
                                 tol, t, err, repeats=k, note=note, **ref))
    return rows


IMPELLER_PLANES = ((0, 5.9), (0, -33.3), (1, 15.15), (2, -9.3), (2, 1.2))


def impeller(planes=IMPELLER_PLANES, repeat=3, tol=1e-3, out=print):
    """pyiges' impeller.igs (277 trimmed faces) cut by planes ``x[axis] = c``: median
    time of ``plane_section(tol, gap=model_gap)`` beside OCC's ``BRepAlgoAPI_Section``
    on the same file (IGESControl_Reader), ``Build`` only, with approximation off and
    on; curves (geomkit) and edges (OCC) found."""
    from geomkit.cad.gaps import model_gap
    from geomkit.cad.iges.reader import read_iges
    from geomkit.bench.oracles import occ

    try:
        from pyiges import examples
    except ImportError:
        out("impeller: needs pyiges (pip install pyiges)")
        return []
    if not occ.HAVE_OCP:
        out("impeller: needs cadquery-ocp (OCC)")
        return []
    from OCP.BRepAlgoAPI import BRepAlgoAPI_Section
    from OCP.gp import gp_Dir, gp_Pln, gp_Pnt
    from OCP.IGESControl import IGESControl_Reader
    from OCP.TopAbs import TopAbs_EDGE
    from OCP.TopExp import TopExp_Explorer

    faces = read_iges(examples.impeller).surfaces
    gap = model_gap(faces)
    rd = IGESControl_Reader()
    rd.ReadFile(str(examples.impeller))
    rd.TransferRoots()
    shape = rd.OneShape()

    def occ_cut(axis, c, approx):
        n = np.zeros(3)
        n[axis] = 1
        sec = BRepAlgoAPI_Section(shape, gp_Pln(gp_Pnt(*(n * c)), gp_Dir(*n)), False)
        sec.Approximation(approx)
        sec.Build()
        ex, k = TopExp_Explorer(sec.Shape(), TopAbs_EDGE), 0
        while ex.More():
            k += 1
            ex.Next()
        return k

    plane_section(faces, [1, 0, 0, -5.9], tol, gap)   # JIT warm-up
    out(f"impeller.igs, {len(faces)} faces, tol {tol:g}, model gap {gap:.3g}; medians of "
        f"{repeat}")
    out(f"{'plane':>10s} | {'geomkit s':>9s} {'curves':>6s} | {'OCC s':>7s} {'edges':>5s} | "
        f"{'OCC+apx s':>9s} | {'gk/OCC':>6s}")
    rows = []
    for axis, c in planes:
        pl = np.zeros(4)
        pl[axis], pl[3] = 1.0, -c
        tg, sec = _median_time(lambda: plane_section(faces, pl, tol, gap), repeat)
        to, k = _median_time(lambda: occ_cut(axis, c, False), repeat)
        ta, _ = _median_time(lambda: occ_cut(axis, c, True), repeat)
        out(f"{'xyz'[axis] + ' = ' + str(c):>10s} | {tg:9.2f} {len(sec.curves):6d} | "
            f"{to:7.2f} {k:5d} | {ta:9.2f} | {tg / to:6.2f}")
        rows.append({"plane": (axis, c), "gk_s": tg, "occ_s": to, "occ_approx_s": ta})
    out(f"median ratio geomkit / BRepAlgoAPI_Section (approximation off) "
        f"{np.median([r['gk_s'] / r['occ_s'] for r in rows]):.2f}")
    return rows


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--tol", type=float, default=1e-6)
    ap.add_argument("--impeller", action="store_true",
                    help="only the impeller.igs rows (pyiges' example, against OCC)")
    a = ap.parse_args(argv)
    if a.impeller:
        impeller(repeat=a.repeat)
    else:
        run(a.repeat, a.tol)


if __name__ == "__main__":
    main()
