"""The main job on built-in data (grows with each engine).

Now: load every bundled sample, evaluate a parameter grid exactly, check the analytic
cases against their formulas, measure the trimmed area fraction of ``plate_with_hole``
by exact UV classification, time evaluation, and tessellate every sample to a chord
tolerance (triangle count, measured deviation, area against the analytic truth).
"""

from __future__ import annotations

import time

import numpy as np

from . import samples
from .evaluation import evaluate, normals
from .tessellate import tessellate
from .trimming import INSIDE, ON_BOUNDARY, classify_uv

__all__ = ["run_demo"]


def _grid(surface, n):
    (u0, u1), (v0, v1) = surface.domain
    u, v = np.meshgrid(np.linspace(u0, u1, n), np.linspace(v0, v1, n), indexing="ij")
    return np.stack([u.ravel(), v.ravel()], axis=1)


def run_demo(grid: int = 200, tol: float = 1e-2) -> dict:
    """Run the demo; returns a JSON-ready summary (one row per surface)."""
    rows = []
    t_all = time.perf_counter()
    for name in samples.names():
        case = samples.load_case(name)
        for k, s in enumerate(case.surfaces):
            uv = _grid(s, grid)
            t0 = time.perf_counter()
            P = evaluate(s, uv)
            dt = time.perf_counter() - t0
            N = normals(s, uv)
            row = {"case": name, "surface": s.name or f"{name}[{k}]",
                   "kind": "NURBS" if s.is_rational else "B-spline",
                   "degree": [s.degree_u, s.degree_v], "control_net": list(s.shape),
                   "trim_loops": len(s.trim), "points": int(uv.shape[0]),
                   "eval_us_per_point": 1e6 * dt / uv.shape[0],
                   "bbox": [P.min(axis=0).round(6).tolist(), P.max(axis=0).round(6).tolist()],
                   "normals_unit_err": float(np.max(np.abs(np.linalg.norm(N, axis=1) - 1)))}
            analytic = case.truth.get("analytic")
            if analytic and len(case.surfaces) == 1:
                row["analytic"] = analytic["type"]
                row["analytic_max_err"] = float(np.max(np.abs(
                    samples.analytic_residual(analytic, P))))
            if s.trim:
                # cell-centre sampling of the domain: inside fraction ~ trimmed area share
                (u0, u1), (v0, v1) = s.domain
                h = 1.0 / grid
                c = np.arange(grid) * h + 0.5 * h
                cu, cv = np.meshgrid(u0 + (u1 - u0) * c, v0 + (v1 - v0) * c, indexing="ij")
                cls = classify_uv(s, np.stack([cu.ravel(), cv.ravel()], axis=1))
                row["uv_inside_fraction"] = float(np.mean(cls == INSIDE)
                                                  + 0.5 * np.mean(cls == ON_BOUNDARY))
            rows.append(row)
        t0 = time.perf_counter()
        mesh = tessellate(case.surfaces, tol)
        rows[-1]["case_mesh"] = {
            "tol": tol, "faces": int(mesh.faces.shape[0]), "max_deviation": mesh.max_deviation,
            "area": mesh.area, "area_truth": case.truth.get("area"),
            "seconds": time.perf_counter() - t0}
    return {"surfaces": rows, "seconds": time.perf_counter() - t_all}
