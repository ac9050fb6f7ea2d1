"""The main jobs on built-in data: ``geomkit demo``.

1. **Deviation**: a synthetic CMM scan of the bundled ``freeform_1`` surface (100 x 100
   bicubic): ``grid x grid`` probe ball centres (radius 1) placed along the surface
   normal at the surface plus a known Gaussian bump (height 0.05, at u = 0.62,
   v = 0.38) plus seeded noise (sigma 0.001); tolerance band +-0.02.  The report finds
   the bump: its maximum and location are compared with the known ones.
2. **Alignment check**: the same scan without bump or noise, moved by a known rigid
   transform; the best fit recovers it (error of the 4x4 matrix reported).
3. **Section**: five parallel planes x = 10, 30, ..., 90 through the surface.
4. **Probe safety**: a stylus (tip r 1, shaft r 0.5 x 20, extension r 2 x 30) travels
   8 above the surface through four waypoints (margin 2), then plunges along the
   normal through the surface; the clearance check certifies each travel move (one
   straight move between safe waypoints dips over a ridge) and finds the plunge's
   first contact, cross-checked with ``project_points`` (the tip centre
   at first contact is one tip radius from the surface).

Reports go to ``out_dir`` (default ``./geomkit-demo``): ``scan.csv`` (the synthetic
measurement, to try the CLI on), ``deviation.csv``, ``deviation_map.png``,
``deviation_hist.png``, ``section_000..004.csv/.dxf/.json``, ``sections.png``,
``probe_path.csv`` (the stylus path), ``clearance.csv``, ``clearance.png``,
``deviation_report.html``, ``section_report.html``, ``clearance_report.html`` (one
interactive report per job) and ``summary.json`` (written last).  The demo replaces its own report files there.
"""

from __future__ import annotations

import time
from pathlib import Path

import numpy as np
from scipy.spatial.transform import Rotation

from geomkit import samples
from geomkit.jobs.warmup import needed as warmup_needed
from geomkit.jobs.warmup import start_background
from geomkit.jobs.clearance import Stylus, probe_clearance
from geomkit.jobs.deviation import align_rigid, deviation
from geomkit.outputs import atomic_write
from geomkit.query.projection_part import project_points
from geomkit.report.files import (plot_clearance, plot_deviation_map, plot_histogram, plot_section,
                                  prepare_outputs, write_clearance_csv, write_deviation_csv,
                                  write_json, write_section)
from geomkit.section.plane import plane_section

__all__ = ["run_demo", "synthetic_scan"]

BUMP_HEIGHT = 0.05
BUMP_UV = (0.62, 0.38)
BUMP_SIGMA = 0.06
NOISE = 0.001
PROBE_RADIUS = 1.0
TOLERANCE = (-0.02, 0.02)
STYLUS = Stylus(tip_radius=PROBE_RADIUS, shaft_radius=0.5, shaft_length=20.0,
                extension_radius=2.0, extension_length=30.0)
TRAVEL_HEIGHT = 8.0
PLUNGE_DEPTH = 2.0
SAFETY_MARGIN = 2.0
WAYPOINTS_UV = [(0.15, 0.2), (0.4, 0.75), (0.8, 0.6), (0.62, 0.38)]


def synthetic_scan(surface, grid: int = 40, seed: int = 3, bump: float = BUMP_HEIGHT,
                   noise: float = NOISE, probe_radius: float = PROBE_RADIUS):
    """Probe ball centres over ``surface``: a ``grid x grid`` UV grid (margin 2 %),
    offset along the normal by ``probe_radius`` + a Gaussian bump + noise.

    Returns ``(centres (n, 3), normals (n, 3), true_deviation (n,))``.
    """
    (u0, u1), (v0, v1) = surface.domain
    g = np.linspace(0.02, 0.98, grid)
    uu, vv = np.meshgrid(g, g, indexing="ij")
    bumpv = bump * np.exp(-((uu - BUMP_UV[0]) ** 2 + (vv - BUMP_UV[1]) ** 2)
                          / (2 * BUMP_SIGMA ** 2))
    uv = np.column_stack([u0 + (u1 - u0) * uu.ravel(), v0 + (v1 - v0) * vv.ravel()])
    S = surface.evaluate(uv)
    N = surface.normals(uv)
    rng = np.random.default_rng(seed)
    true = bumpv.ravel() + noise * rng.standard_normal(uv.shape[0])
    return S + (true + probe_radius)[:, None] * N, N, true


STEPS = ("deviation", "alignment", "section", "clearance", "reports")
"""The demo's steps, in order (the names ``progress`` is called with)."""


def run_demo(out_dir="geomkit-demo", grid: int = 40, tol: float = 1e-4,
             warm_up: bool = True, progress=None) -> dict:
    """Run the demo jobs; returns a JSON-ready summary (also written to summary.json).

    ``warm_up``: on a fresh install the kernels of the later steps (surface distance,
    sections) are compiled by a second process while this one compiles and runs the
    deviation step (:mod:`geomkit.jobs.warmup`); a no-op cost (~1 s) once compiled.

    ``progress(step, summary, seconds)``, if given, is called as each step of
    :data:`STEPS` starts (``summary`` and ``seconds`` None) and when it is done (the
    summary so far, holding the step's results, and the step's seconds)."""
    t_all = time.perf_counter()
    summary = {"output": str(Path(out_dir)), "surface": "freeform_1"}
    marks, started = {}, {}

    def step(name, done=False):
        now = time.perf_counter()
        if not done:
            started[name] = now
        else:
            marks[name] = now
        if progress is not None:
            progress(name, summary if done else None,
                     now - started[name] if done else None)
    helper = (start_background(["distance", "section"])
              if warm_up and warmup_needed() else None)
    case = samples.load_case("freeform_1")
    surf = case.surfaces[0]
    units = case.units  # None: the bundled samples do not state one ("model units")
    planes = [np.array([1.0, 0.0, 0.0, -x]) for x in (10, 30, 50, 70, 90)]
    sec_names = [f"section_{k:03d}.{e}" for k in range(len(planes))
                 for e in ("csv", "dxf", "json")]
    names = ["scan.csv", "deviation.csv", "deviation_map.png", "deviation_hist.png",
             "sections.png", "probe_path.csv", "clearance.csv", "clearance.png",
             "summary.json"] + sec_names
    names += [f"{j}_report.html" for j in ("deviation", "section", "clearance")]
    targets = prepare_outputs(out_dir, names, overwrite=True)

    # 1. deviation of the synthetic scan
    step("deviation")
    C, N, true = synthetic_scan(surf, grid)
    text = "x,y,z,i,j,k\n" + "".join(
        f"{a!r},{b!r},{c!r},{i!r},{j!r},{k!r}\n"
        for (a, b, c), (i, j, k) in zip(C.tolist(), N.tolist()))
    atomic_write(targets["scan.csv"], lambda fh: fh.write(text.encode("utf-8")))
    rep = deviation(surf, C, N, probe_radius=PROBE_RADIUS, tolerance=TOLERANCE)
    write_deviation_csv(rep, targets["deviation.csv"], overwrite=True, units=units)
    plot_deviation_map(rep, surf, targets["deviation_map.png"], overwrite=True,
                       units=units)
    plot_histogram(rep, targets["deviation_hist.png"], overwrite=True, units=units)
    err = float(np.nanmax(np.abs(rep.deviation - true)))
    (u0, u1), (v0, v1) = surf.domain
    centre = surf.evaluate([[u0 + (u1 - u0) * BUMP_UV[0], v0 + (v1 - v0) * BUMP_UV[1]]])[0]
    i = int(np.nanargmax(rep.deviation))
    bump = {"height": BUMP_HEIGHT, "center_xyz": np.round(centre, 3).tolist(),
            "found_max": float(rep.deviation[i]),
            "found_xyz": np.round(rep.foot[i], 3).tolist(),
            "found_distance": float(np.linalg.norm(rep.foot[i] - centre)),
            "max_error_vs_truth": err}
    st = rep.summary()
    summary["deviation"] = {k: st[k] for k in ("points", "valid", "edge", "min", "max",
                                                "mean", "rms", "std", "pct_within",
                                                "pct_over", "pct_under", "tolerance",
                                                "probe_radius")}
    summary["bump"] = bump
    step("deviation", done=True)
    # 2. alignment check: a known rigid motion of an exact scan is recovered
    step("alignment")
    C0, N0, _ = synthetic_scan(surf, max(6, grid // 2), bump=0.0, noise=0.0,
                               probe_radius=0.0)
    T = np.eye(4)
    T[:3, :3] = Rotation.from_rotvec([0.01, -0.02, 0.015]).as_matrix()
    T[:3, 3] = (0.5, -0.3, 0.8)
    Ti = np.linalg.inv(T)
    moved = C0 @ Ti[:3, :3].T + Ti[:3, 3]
    al = align_rigid(surf, moved)
    align = {"transform_error": float(np.abs(al["transform"] - T).max()),
             "iterations": al["iterations"], "rms_before": al["rms_before"],
             "rms_after": al["rms_after"], "known_transform": T.tolist()}
    summary["alignment_check"] = align
    step("alignment", done=True)
    # 3. sections
    step("section")
    sections = []
    for k, pl in enumerate(planes):
        sec = plane_section(surf, pl, tol)
        sec.units = units  # the CSV and DXF writers state it
        sections.append(sec)
        write_section(sec, {e: targets[f"section_{k:03d}.{e}"] for e in ("csv", "dxf", "json")},
                      overwrite=True, units=units)
    plot_section(sections, targets["sections.png"], overwrite=True, units=units)
    section = {"planes": len(planes), "description": "x = 10, 30, 50, 70, 90",
               "curves": sum(len(s.curves) for s in sections),
               "max_residual": max(s.max_residual for s in sections),
               "tol": tol}
    summary["section"] = section
    step("section", done=True)
    # 4. probe safety: travel above the surface, then plunge along the normal
    step("clearance")
    uvw = np.array(WAYPOINTS_UV)
    uvw = np.column_stack([u0 + (u1 - u0) * uvw[:, 0], v0 + (v1 - v0) * uvw[:, 1]])
    Sw, Nw = surf.evaluate(uvw), surf.normals(uvw)
    path = np.vstack([Sw + TRAVEL_HEIGHT * Nw, Sw[-1:] - PLUNGE_DEPTH * Nw[-1:]])
    axis = Nw.mean(axis=0)
    text = "x,y,z\n" + "".join(f"{a!r},{b!r},{c!r}\n" for a, b, c in path.tolist())
    atomic_write(targets["probe_path.csv"], lambda fh: fh.write(text.encode("utf-8")))
    if helper is not None:  # let it finish what it compiles rather than compile it twice
        helper.wait()
    marks["waited for the compile helper"] = time.perf_counter()
    cl = probe_clearance(surf, STYLUS, path, axis=axis, margin=SAFETY_MARGIN)
    write_clearance_csv(cl, path, targets["clearance.csv"], overwrite=True, units=units)
    plot_clearance(cl, targets["clearance.png"], overwrite=True, units=units,
                   probing=[len(cl) - 1])
    k = len(cl) - 1
    fc = float(cl.first_contact[k])
    tip = path[k] + fc * (path[k + 1] - path[k]) if np.isfinite(fc) else path[k]
    check = float(project_points(surf, tip[None]).distance[0])
    travel = slice(0, k)
    clearance = {"segments": len(cl), "margin": SAFETY_MARGIN, "stylus": STYLUS.to_dict(),
                 "travel_moves": k, "travel_moves_passed": int(np.sum(cl.passed[travel])),
                 "travel_worst_move": int(np.argmin(cl.lower_bound[travel])),
                 "travel_min_clearance": float(cl.clearance[travel].min()),
                 "travel_min_lower_bound": float(cl.lower_bound[travel].min()),
                 "plunge_first_contact": fc,
                 "plunge_contact_component": cl.component_names[cl.component[k]],
                 "tip_distance_at_contact": check,
                 "certified": bool(np.all(cl.certified)),
                 "seconds": cl.stats["seconds"]}
    summary["clearance"] = clearance
    summary["files"] = sorted(names)
    step("clearance", done=True)
    # 5. one self-contained interactive HTML report per job
    step("reports")
    from geomkit.report.jobs import write_reports

    write_reports("deviation", ["html"], targets, True, rep=rep, surfaces=surf,
                  part="freeform_1", units=units)
    write_reports("section", ["html"], targets, True, sections=sections, surfaces=surf,
                  scan=C, probe_radius=PROBE_RADIUS, tolerance=TOLERANCE, part="freeform_1",
                  units=units)
    write_reports("clearance", ["html"], targets, True, res=cl, surfaces=surf,
                  path_points=path, stylus=STYLUS, axis=axis, probing=[k], part="freeform_1",
                  units=units)
    step("reports", done=True)
    prev, steps = t_all, {}
    for k, t in marks.items():
        steps[k] = t - prev
        prev = t
    summary["step_seconds"] = steps
    summary["seconds"] = time.perf_counter() - t_all
    write_json(summary, targets["summary.json"], overwrite=True, units=units)
    return summary
