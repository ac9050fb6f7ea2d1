"""CMM deviation: measured points against the nominal surfaces.

Method:

1. (optional) best-fit rigid alignment of the points to the surfaces: iterated
   point-to-plane least squares (Chen & Medioni): project the points
   (:func:`geomkit.project_points`), linearise the signed distance along the foot
   normal in a small rotation ω and translation t, solve the 6x6 least-squares
   system (minimum-norm, so directions the surface cannot fix, e.g. the spin of a
   surface of revolution, are left unchanged), apply the exact rotation (Rodrigues)
   and repeat until the step is below ``1e-12`` of the model size.  Only interior
   feet take part (edge feet have no normal residual).
2. Projection of the (aligned) points on the exact trimmed surfaces.
3. Probe compensation: a ball-centre point lies ``probe_radius`` off the surface, on
   the side the probe touched from.  That side is given by the measured normals
   (i, j, k) when present (the side of the nominal normal they point to), otherwise
   the probe is taken to touch from the side the nominal normal points to.
   ``deviation = signed_distance - side * probe_radius``.

Sign convention: the deviation is measured along the nominal surface normal
``S_u x S_v`` at the foot: positive when the measured surface lies on the side the
normal points to (excess material when the normals point out of the material),
negative on the other side.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field

import numpy as np
from scipy.spatial.transform import Rotation

from geomkit.tolerances import ALIGN_RCOND, ALIGN_STEP_TOL
from geomkit.nurbs.surface import as_surfaces
from geomkit.query import results as R
from geomkit.errors import InvalidInputError
from geomkit.exchange.points import as_measured_points
from geomkit.query.projection_part import project_points

__all__ = ["deviation", "DeviationReport", "align_rigid", "deviation_chunk", "ALIGN_MAX_ITER",
           "COLUMNS"]

ALIGN_MAX_ITER = 60
"""Alignment iterations at most."""


@dataclass(eq=False)
class DeviationReport:
    """Result of :func:`deviation`.

    Attributes
    ----------
    points : (n, 3) float, the measured points as given.
    aligned : (n, 3) float, the points after the alignment transform (= points when
        not aligned).
    foot : (n, 3) float, nearest point of the nominal surfaces (NaN when none).
    uv : (n, 2) float; surface : (n,) int32 (-1 when none).
    normal : (n, 3) float, unit nominal normal at the foot.
    signed_distance : (n,) float, signed distance of the aligned point to the surface.
    deviation : (n,) float, ``signed_distance - side * probe_radius`` (NaN for points
        beyond ``max_distance`` or failed).
    status : (n,) int8, the :mod:`geomkit.query.results` codes (INTERIOR, DOMAIN_EDGE,
        TRIM_EDGE, BEYOND, FAILED).
    edge : (n,) bool, the foot is on a domain or trim edge (deviation along the
        normal is not meaningful there).
    transform : (4, 4) float, the rigid alignment applied to the points
        (``aligned = R @ p + t``); identity when not aligned.
    tolerance : (lower, upper) or None.
    probe_radius : float.
    stats : dict, the statistics (see :meth:`summary`).
    """

    points: np.ndarray
    aligned: np.ndarray
    foot: np.ndarray
    uv: np.ndarray
    surface: np.ndarray
    normal: np.ndarray
    signed_distance: np.ndarray
    deviation: np.ndarray
    status: np.ndarray
    edge: np.ndarray
    transform: np.ndarray
    tolerance: tuple | None
    probe_radius: float
    stats: dict = field(default_factory=dict)

    def __len__(self) -> int:
        return int(self.deviation.shape[0])

    @property
    def valid(self) -> np.ndarray:
        """(n,) bool, rows with a deviation (not beyond ``max_distance``, not failed)."""
        return np.isfinite(self.deviation)

    def summary(self) -> dict:
        """JSON-ready statistics, transform and settings."""
        return dict(self.stats)

    def __repr__(self) -> str:
        s = self.stats
        return (f"<DeviationReport {s['points']} points, {s['valid']} valid: "
                f"min {s['min']:.4g} max {s['max']:.4g} rms {s['rms']:.4g}>")


def _as_tolerance(tolerance):
    if tolerance is None:
        return None
    try:
        lo, hi = (float(x) for x in tolerance)
    except (TypeError, ValueError):
        raise InvalidInputError("expected (lower, upper), two numbers", "tolerance") from None
    if not (math.isfinite(lo) and math.isfinite(hi) and lo <= hi):
        raise InvalidInputError(f"expected finite lower <= upper, got ({lo}, {hi})",
                                "tolerance")
    return (lo, hi)


def _apply(T: np.ndarray, P: np.ndarray) -> np.ndarray:
    return P @ T[:3, :3].T + T[:3, 3]


def _side(normals, pr_normal):
    if normals is None:
        return np.ones(pr_normal.shape[0])
    d = np.einsum("ij,ij->i", normals, pr_normal)
    return np.where(d < 0, -1.0, 1.0)


def _step(c, x) -> np.ndarray:
    """4x4 rigid step: rotation ``x[:3]`` (Rodrigues vector) about ``c``, then
    translation ``x[3:]``."""
    Rk = Rotation.from_rotvec(x[:3]).as_matrix()
    step = np.eye(4)
    step[:3, :3] = Rk
    step[:3, 3] = c - Rk @ c + x[3:]
    return step


def align_rigid(surfaces, points, normals=None, probe_radius: float = 0.0,
                max_distance: float | None = None, max_iter: int = ALIGN_MAX_ITER,
                progress=None):
    """Best-fit rigid transform of points onto surfaces (point-to-plane least squares).

    Parameters
    ----------
    surfaces : Surface or list of Surface
    points : (n, 3) float, n >= 6 for a determined fit.
    normals : (n, 3) float, optional measured normals (probe side, see module doc).
    probe_radius : float >= 0, ball-centre offset the fit targets.
    max_distance : float, optional; points farther take no part.

    Returns
    -------
    dict
        ``transform`` (4, 4), ``rms_before``, ``rms_after`` (over the interior points
        of the last iteration), ``iterations``, ``rank`` (of the last system; < 6 when
        the surface leaves motions free) and ``converged``.
    """
    P0, N = as_measured_points(points, normals)
    surfs = as_surfaces(surfaces)
    size = max(s.size for s in surfs)
    T = np.eye(4)
    rms_before = None
    rank = 0
    converged = False
    it = 0
    best = None  # (T, rms, c, x) of the last accepted iterate and its step
    halvings = 0
    for it in range(1, max_iter + 1):
        P = _apply(T, P0)
        Nt = None if N is None else N @ T[:3, :3].T
        pr = project_points(surfs, P, max_distance)
        ok = pr.status == R.INTERIOR
        if ok.sum() < 1:
            raise InvalidInputError("no point has an interior foot on the surfaces; "
                                    "cannot align", "points")
        side = _side(Nt, pr.normal)
        r = pr.signed_distance[ok] - side[ok] * probe_radius
        rms = float(np.sqrt(np.mean(r * r)))
        if rms_before is None:
            rms_before = rms
        if best is not None and rms > best[1] * (1 + 1e-9) + 1e-15 * size:
            # the linearised step made the fit worse: halve it (never end worse than
            # the best iterate; a step halved 40 times is below rounding)
            halvings += 1
            if halvings > 40:
                T = best[0]
                converged = True
                break
            T_best, _, c, x = best
            x = x * 0.5
            best = (T_best, best[1], c, x)
            T = _step(c, x) @ T_best
            continue
        halvings = 0
        n = pr.normal[ok]
        c = P[ok].mean(axis=0)
        # rotation columns in length units (x size), so the rank threshold compares
        # like with like; a motion the surface leaves free (a sphere's rotations about
        # its centre, a cylinder's slide along its axis) has a singular value at the
        # rounding level and is not moved
        J = np.hstack([np.cross(P[ok] - c, n) / size, n])
        x, _, rank, _ = np.linalg.lstsq(J, -r, rcond=ALIGN_RCOND)
        x[:3] /= size
        best = (T, rms, c, x)
        step = _step(c, x)
        T = step @ T
        moved = float(np.max(np.linalg.norm(_apply(step, P[ok]) - P[ok], axis=1)))
        if progress is not None:
            progress(it, max_iter)
        if moved <= ALIGN_STEP_TOL * size:
            converged = True
            break
    P = _apply(T, P0)
    Nt = None if N is None else N @ T[:3, :3].T
    pr = project_points(surfs, P, max_distance)
    ok = pr.status == R.INTERIOR
    r = pr.signed_distance[ok] - _side(Nt, pr.normal)[ok] * probe_radius
    rms_after = float(np.sqrt(np.mean(r * r))) if ok.any() else float("nan")
    return {"transform": T, "rms_before": float(rms_before), "rms_after": rms_after,
            "iterations": it, "rank": int(rank), "converged": converged}


def deviation(surfaces, points, normals=None, probe_radius: float = 0.0,
              align: bool = False, max_distance: float | None = None,
              tolerance=None, progress=None) -> DeviationReport:
    """Signed deviation of measured points from nominal surfaces (CMM inspection).

    Parameters
    ----------
    surfaces : Surface or list of Surface
        The nominal (trimmed) surfaces.
    points : (n, 3) float
        Measured points: surface points, or probe ball centres when
        ``probe_radius > 0``.
    normals : (n, 3) float, optional
        Measured normals (i, j, k); they choose the probe side (see the module doc).
    probe_radius : float >= 0
        Probe ball radius for ball-centre data.
    align : bool
        Best-fit the points to the surfaces first (:func:`align_rigid`); the
        transform and RMS before / after are reported.
    max_distance : float, optional
        Points whose |deviation| would exceed this (their ball centre is farther than
        ``max_distance + probe_radius``) are not matched: status BEYOND, NaN deviation.
    tolerance : (lower, upper), optional
        Tolerance band; the statistics count the points in, over and under it.
    progress : callable(done, total), optional

    Returns
    -------
    DeviationReport
        Deviations within the projection's accuracy (~1e-12 of the model size; tested
        against analytic torus offsets to 1e-9).

    Examples
    --------
    >>> import geomkit
    >>> from geomkit.jobs.deviation import deviation
    >>> sphere = geomkit.samples.load("sphere")[0]
    >>> rep = deviation(sphere, [[0, 0, 10.5], [0, 0, -9.0]], tolerance=(-0.1, 0.1))
    >>> [round(float(d), 9) for d in rep.deviation]
    [0.5, -1.0]
    >>> rep.stats["over"], rep.stats["under"]
    (1, 1)
    """
    t0 = time.perf_counter()
    P0, N = as_measured_points(points, normals)
    probe_radius, max_distance = _check_settings(probe_radius, max_distance)
    tol = _as_tolerance(tolerance)
    md = None if max_distance is None else max_distance + probe_radius
    align_info = None
    T = np.eye(4)
    if align:
        align_info = align_rigid(surfaces, P0, N, probe_radius, md)
        T = align_info["transform"]
    P = _apply(T, P0) if align else P0
    Nt = None if N is None else N @ T[:3, :3].T
    pr = project_points(surfaces, P, md, progress=progress)
    dev, status, edge = _compensate(pr, Nt, probe_radius, max_distance)
    rep = DeviationReport(points=P0, aligned=P, foot=pr.point, uv=pr.uv, surface=pr.surface,
                          normal=pr.normal, signed_distance=pr.signed_distance, deviation=dev,
                          status=status, edge=edge, transform=T, tolerance=tol,
                          probe_radius=probe_radius)
    rep.stats = _statistics(rep, align_info, max_distance, time.perf_counter() - t0)
    rep.stats["faces_failed"] = {int(k): v for k, v in
                                 pr.stats.get("faces_failed", {}).items()}
    return rep


def _compensate(pr, Nt, probe_radius, max_distance):
    """Probe compensation and the max-distance cut of a projection: ``(deviation,
    status, edge)``; shared by :func:`deviation` and the streamed job
    (:mod:`geomkit.jobs.stream`), so both give the same values bit for bit."""
    side = _side(Nt, np.nan_to_num(pr.normal))
    dev = pr.signed_distance - side * probe_radius
    status = pr.status.copy()
    if max_distance is not None:
        far = np.isfinite(dev) & (np.abs(dev) > max_distance)
        status[far] = R.BEYOND
        dev[far] = np.nan
    dev[(status == R.BEYOND) | (status == R.FAILED)] = np.nan
    edge = (status == R.DOMAIN_EDGE) | (status == R.TRIM_EDGE)
    return dev, status, edge


def _check_settings(probe_radius, max_distance):
    try:
        probe_radius = float(probe_radius)
    except (TypeError, ValueError):
        raise InvalidInputError("must be a number", "probe_radius") from None
    if not (math.isfinite(probe_radius) and probe_radius >= 0):
        raise InvalidInputError(f"must be a finite number >= 0, got {probe_radius!r}",
                                "probe_radius")
    if max_distance is not None:
        max_distance = float(max_distance)
        if not (max_distance >= 0):
            raise InvalidInputError(f"must be >= 0, got {max_distance!r}", "max_distance")
    return probe_radius, max_distance


def _statistics(rep: DeviationReport, align_info, max_distance, seconds) -> dict:
    from geomkit.jobs.stats import DeviationStats

    acc = DeviationStats(rep.tolerance)
    acc.update(rep.deviation, rep.status, rep.edge)
    st = acc.result()
    st.update(probe_radius=rep.probe_radius, max_distance=max_distance,
              tolerance=list(rep.tolerance) if rep.tolerance else None)
    return _alignment_info(st, align_info, seconds)


def _alignment_info(st, align_info, seconds) -> dict:
    st["alignment"] = None
    if align_info is not None:
        st["alignment"] = {"transform": np.asarray(align_info["transform"]).tolist(),
                           "rms_before": align_info["rms_before"],
                           "rms_after": align_info["rms_after"],
                           "iterations": align_info["iterations"],
                           "rank": align_info["rank"],
                           "converged": align_info["converged"]}
    st["seconds"] = seconds
    return st


# ------------------------------------------------------------ chunks
COLUMNS = ("index", "x", "y", "z", "ax", "ay", "az", "foot_x", "foot_y", "foot_z", "u",
           "v", "surface", "nx", "ny", "nz", "signed_distance", "deviation", "status",
           "edge")
"""Per-point columns, those of :func:`geomkit.report.files.write_deviation_csv`."""


def deviation_chunk(projector, P0, N, T, probe_radius, max_distance, offset):
    """Deviation columns of one chunk of points (row ``offset`` onwards).

    Returns
    -------
    dict
        ``{column: (m,) array}`` for :data:`COLUMNS` (status as int8 codes), the
        values of :func:`geomkit.jobs.deviation.deviation` for these points.
    """
    aligned = T is not None
    P = _apply(T, P0) if aligned else P0
    Nt = None if N is None else (N @ T[:3, :3].T if aligned else N)
    md = None if max_distance is None else max_distance + probe_radius
    [pr] = projector.iter_project(P, md, chunk_size=max(1, P.shape[0]))
    dev, status, edge = _compensate(pr, Nt, probe_radius, max_distance)
    m = P0.shape[0]
    out = {"index": np.arange(offset, offset + m, dtype=np.int64)}
    for k, name in enumerate("xyz"):
        out[name] = P0[:, k]
        out["a" + name] = P[:, k]
        out["foot_" + name] = pr.point[:, k]
        out["n" + name] = pr.normal[:, k]
    out.update(u=pr.uv[:, 0], v=pr.uv[:, 1], surface=pr.surface.astype(np.int64),
               signed_distance=pr.signed_distance, deviation=dev, status=status,
               edge=edge.astype(np.int8))
    return {c: np.ascontiguousarray(out[c]) for c in COLUMNS}
