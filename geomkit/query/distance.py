"""Exact minimum distance between NURBS surfaces with a certified interval.

Method (Paper 1's question — the minimum distance of two free-form surfaces — with a
certificate Paper 1 does not give):

1. every surface of both scenes is split into rational Bézier patches (knot
   insertion, :func:`geomkit.bezier_patches`); patches of a trimmed face that lie
   entirely outside it are dropped, patches crossed by a trim curve are kept
   (conservative);
2. best-first branch and bound over pairs (patch of A, patch of B): the lower bound
   of a pair is the separation of the two control nets (axis-box gap, and the slab
   gap along the box-centre and representative-point directions) — a proven bound,
   since with positive weights each patch lies in the convex hull of its control
   points — and the gap of curved 1-Lipschitz separators (distance to a sphere centre
   or an axis found at the first Newton feet, bounded over each patch by Bernstein
   coefficient ratios; exact on spheres / cylinders about them, which certifies
   continua of minima such as concentric spheres at the root,
   :mod:`geomkit._kernels.distance_sep`); the upper bound is the distance of real face points (patch centres by de
   Casteljau, inside the trimmed face);
3. whenever a pair's centres improve the upper bound, a 4-unknown Newton on
   |S_a(u, v) - S_b(s, t)|^2 (exact Hessian, Levenberg damping, active set on the
   domain boxes: surface–surface, edge–surface, edge–edge and corner minima) from
   those centres finishes it on the exact surfaces;
4. pairs whose lower bound is >= upper - tol are discarded; the pair with the smallest
   lower bound is subdivided (de Casteljau at 1/2 of the larger patch along its longer
   parameter direction) — only the regions that can still hold the minimum are ever
   refined ("model only what a scene needs");
5. stop when the smallest open lower bound is >= upper - tol: ``[lower, upper]``
   contains the exact distance and is at most ``tol`` wide.

Degenerate answers: touching or intersecting surfaces give hull overlaps all the way
down (lower 0) and Newton converges to a point of the intersection (upper <= tol);
continua of minima (parallel planes) are settled at the root when the nets are flat,
and otherwise the search is capped at ``max_pairs`` examined pairs with an honest
(wider) interval and ``certified=False``.

Trimmed faces: upper bounds only from points classified INSIDE the face (exact
winding test); lower bounds from every patch that meets the face.  A minimum lying on
a trim curve is approached by inside points of ever smaller patches (not by a
trim-curve Newton), so it converges linearly in the patch size — see the docs.
"""

from __future__ import annotations

import math
import time

import numpy as np

from geomkit.tolerances import HULL_ROUNDING
from geomkit._kernels import distance as _dk
from geomkit._kernels.bezier import de_casteljau_split
from geomkit.errors import InvalidInputError
from geomkit.query.projection import _pack
from geomkit.query.results import SurfaceDistance
from geomkit.nurbs.surface import as_surfaces
from geomkit.nurbs.trims import concat_segments

__all__ = ["surface_distance", "MAX_PAIRS", "MAX_NEWTON", "HULL_ROUNDING"]

MAX_PAIRS = 200_000
"""Default cap on examined sub-patch pairs (bounds the time and memory of a curved
continuum of minima, e.g. concentric spheres)."""
TRIM_PIECES = 32
"""Each trim segment's UV box is taken over this many sub-arcs (a sub-patch is
"crossed by the trim" only when one of these small boxes meets it)."""
MAX_NEWTON = 256
"""Newton runs at most (one per upper-bound improvement)."""


def _approx_error(scene) -> float:
    """Largest ``approx_error`` (distance bound from the true face) of a scene's faces;
    0 for exact faces (and for Surface objects without the attribute)."""
    e = 0.0
    for s in scene:
        v = float(getattr(s, "approx_error", 0.0) or 0.0)
        if not (math.isfinite(v) and v >= 0.0):
            raise InvalidInputError(f"approx_error must be a finite number >= 0, got {v!r}",
                                    "approx_error")
        e = max(e, v)
    return e


_UNTRIMMED_KERNELS = True
"""Scenes without a trimmed face run the kernels' untrimmed specialisation
(``seg_all`` None: numba prunes the trim branches, ~40 % less to compile on a first
run).  False: every scene runs the general one (the tests compare the two)."""


def _pack_trims(surfaces):
    """All surfaces' trim segments (:func:`geomkit.nurbs.trims.concat_segments`), the UV
    boxes of their sub-arcs (kept on each surface) and ``meta[s] = (offset, count,
    loops, first box, boxes)``."""
    seg_all, seg_deg, seg_loop, off = concat_segments(surfaces, min_rows=1)
    meta = np.zeros((len(surfaces), 5), dtype=np.int64)
    boxes = []
    for i, s in enumerate(surfaces):
        if not s.is_trimmed:
            continue
        pb = s._cache.get("distance_trim_boxes")
        if pb is None:
            seg, deg, _, _ = s.trim_segments()
            pb = s._cache["distance_trim_boxes"] = _trim_boxes(seg, deg)
        meta[i] = (off[i, 0], off[i, 1], off[i, 2], len(boxes), len(pb))
        boxes += pb
    seg_box = np.array(boxes) if boxes else np.zeros((1, 4))
    return seg_all, seg_deg, seg_loop, seg_box, meta


def _trim_boxes(seg, deg):
    """UV boxes of TRIM_PIECES sub-arcs of every trim segment (tight boxes)."""
    pb = []
    for k in range(seg.shape[0]):
        d = deg[k]
        rest = np.ascontiguousarray(seg[k, : d + 1])
        for j in range(TRIM_PIECES):  # boxes of TRIM_PIECES sub-arcs (tight)
            if j < TRIM_PIECES - 1:
                left = np.empty_like(rest)
                right = np.empty_like(rest)
                de_casteljau_split(rest, 1.0 / (TRIM_PIECES - j), left, right)
                piece, rest = left, right
            else:
                piece = rest
            xy = piece[:, :2] / piece[:, 2:3]
            pb.append((xy[:, 0].min(), xy[:, 0].max(), xy[:, 1].min(), xy[:, 1].max()))
    return pb


def _root_nodes(surfaces, nA):
    nets, rows = [], []
    off = 0
    for si, s in enumerate(surfaces):
        bp = s.bezier_patches()
        H = bp.homogeneous
        nsu, nsv, p1, q1, _ = H.shape
        for i in range(nsu):
            for j in range(nsv):
                nets.append(H[i, j].reshape(-1))
                rows.append((off, p1 - 1, q1 - 1, si, int(si >= nA),
                             bp.u_breaks[i], bp.u_breaks[i + 1], bp.v_breaks[j],
                             bp.v_breaks[j + 1]))
                off += p1 * q1 * 4
    n = len(rows)
    ctrl = np.concatenate(nets)
    ni = np.zeros((n, _dk.NI), dtype=np.int64)
    nf = np.zeros((n, _dk.NF))
    for k, r in enumerate(rows):
        ni[k, _dk.I_OFF], ni[k, _dk.I_P], ni[k, _dk.I_Q], ni[k, _dk.I_SURF] = r[:4]
        ni[k, _dk.I_SIDE] = r[4]
        nf[k, :4] = r[5:]
    return ctrl, ni, nf


def surface_distance(a, b, tol: float = 1e-9, max_pairs: int = MAX_PAIRS) -> SurfaceDistance:
    """Minimum distance between two surfaces (or two scenes of surfaces), certified.

    Parameters
    ----------
    a, b : Surface or non-empty list of Surface
        The two scenes (e.g. a probe against a part); trimmed faces are honoured.
    tol : float > 0
        Width of the certified interval: on return ``upper - lower <= tol`` (unless the
        work cap was hit; see ``certified``), in model units.  Faces that carry an
        ``approx_error`` (their distance bound from the true geometry, e.g. approximated
        offset faces) widen ``lower`` / ``upper`` by the largest such error of each
        scene, so the interval bounds the distance of the *true* faces; ``distance``
        and the points stay those of the faces given, and ``certified`` is then False
        when the widened interval is wider than ``tol``.  Both ends carry a rounding
        allowance of ``HULL_ROUNDING`` times the scene's size: a ``tol`` below twice that
        (``stats["rounding_floor"]``) cannot be certified, and the search then stops
        at an interval of about 1.5 times the floor instead of spending ``max_pairs``.
    max_pairs : int >= 1
        Cap on examined sub-patch pairs.

    Returns
    -------
    SurfaceDistance
        ``distance`` (= ``upper``, the distance of the returned real point pair),
        ``lower <= exact <= upper``, the points, parameters and surface indices that
        realise it, ``regions_refined`` and work statistics.

    Raises
    ------
    InvalidInputError
        Naming the field (``a``, ``b[2]``, ``tol``, ``max_pairs``).

    Examples
    --------
    >>> import geomkit
    >>> s1, s2 = geomkit.samples.load("sphere_pair")
    >>> r = surface_distance(s1, s2, tol=1e-9)
    >>> abs(r.distance - 5.0) < 1e-9 and r.lower <= 5.0 <= r.upper
    True
    """
    t0 = time.perf_counter()
    A = as_surfaces(a, "a")
    B = as_surfaces(b, "b")
    try:
        tol = float(tol)
    except (TypeError, ValueError):
        raise InvalidInputError(f"must be a finite number > 0, got {tol!r}", "tol") from None
    if not (math.isfinite(tol) and tol > 0):
        raise InvalidInputError(f"must be a finite number > 0, got {tol!r}", "tol")
    if isinstance(max_pairs, bool) or not isinstance(max_pairs, (int, np.integer)) \
            or max_pairs < 1:
        raise InvalidInputError(f"must be an integer >= 1, got {max_pairs!r}", "max_pairs")
    surfaces = A + B
    nA = len(A)
    lo = np.min([s.bounds[0] for s in surfaces], axis=0)
    hi = np.max([s.bounds[1] for s in surfaces], axis=0)
    size = float(np.linalg.norm(hi - lo))
    scale = max(size, float(np.abs(np.concatenate([lo, hi])).max()), 1e-300)
    rounding = HULL_ROUNDING * scale
    # both ends carry the allowance: the hull bound below, the evaluated points above,
    # so no interval narrower than 2 * rounding can be stated.  Below that floor the
    # search aims at rounding (the answer is not certified whatever it costs: a finer
    # target only spent the whole max_pairs budget, 0.2-0.5 s on the continuum cases,
    # to narrow a 3e-12 interval to 2e-12)
    if tol > 4 * rounding:
        tol_eff = tol - 2 * rounding
    else:
        tol_eff = max(0.5 * tol, rounding)
    Pw_all, U_all, V_all, meta, dom = _pack(surfaces)
    seg_all, seg_deg, seg_loop, seg_box, tmeta = _pack_trims(surfaces)
    if _UNTRIMMED_KERNELS and not tmeta[:, 1].any():
        # no trimmed face: the kernels' untrimmed specialisation, which does not compile
        # the trim classification and trim-edge search (a first run compiles less)
        seg_all = None
    side = max(float(np.max(dom[:, 1] - dom[:, 0])), float(np.max(dom[:, 3] - dom[:, 2])))
    uv_tol = 1e-12 * side
    ctrl, ni, nf = _root_nodes(surfaces, nA)
    n = ni.shape[0]
    _dk.init_nodes(ctrl, ni, nf, n, seg_all, seg_deg, seg_loop, seg_box, tmeta, uv_tol)
    keep = ni[:, _dk.I_STATE] != _dk.ST_OUTSIDE
    nodes_a = np.nonzero(keep & (ni[:, _dk.I_SIDE] == 0))[0].astype(np.int64)
    nodes_b = np.nonzero(keep & (ni[:, _dk.I_SIDE] == 1))[0].astype(np.int64)
    if nodes_a.size == 0 or nodes_b.size == 0:
        raise InvalidInputError("no patch of the scene meets its trimmed faces",
                                "a" if nodes_a.size == 0 else "b")
    out_f = np.zeros(12)
    out_i = np.zeros(10, dtype=np.int64)
    min_size = max(1e-3 * tol, 1e-13 * scale)
    step_tol = max(1e-3 * tol, 1e-15 * scale)
    ctrl, ni, nf = _dk.branch_and_bound(
        ctrl, ni, nf, n, nodes_a, nodes_b, Pw_all, U_all, V_all, meta, dom, seg_all, seg_deg,
        seg_loop, seg_box, tmeta, uv_tol, tol_eff, min_size, int(max_pairs), MAX_NEWTON,
        step_tol, out_f, out_i)
    measured = float(out_f[0])
    upper = measured + rounding  # the points are evaluated with rounding too
    lower = max(0.0, float(out_f[1]) - rounding)
    if measured <= tol:  # touching / intersecting: 0 is in the interval
        lower = 0.0
    # faces that only approximate the true geometry (e.g. approximated offsets) are
    # within their ``approx_error`` of it: the true distance lies within the sum of the
    # two scenes' largest approximation errors of the computed one
    widen = _approx_error(A) + _approx_error(B)
    if widen > 0.0:
        lower = max(0.0, lower - widen)
        upper = upper + widen
    nodes = int(out_i[5])
    node_bytes = nodes * (_dk.NI * 8 + _dk.NF * 8)
    ctrl_bytes = int(ni[:nodes, _dk.I_OFF].max() + 1) * 8 if nodes else 0
    ctrl_bytes = int(sum((ni[k, _dk.I_P] + 1) * (ni[k, _dk.I_Q] + 1) * 32
                         for k in range(nodes))) if nodes < 20000 else ctrl_bytes
    heap_bytes = int(out_i[8]) * 24
    stats = {"pairs_examined": int(out_i[2]), "pairs_pushed": int(out_i[4]),
             "pairs_pruned": int(out_i[9]), "nodes": nodes, "root_patches": n,
             "newton_runs": int(out_i[6]), "peak_heap": int(out_i[8]),
             "stop": {0: "certified", 1: "max_pairs", 2: "exhausted"}[int(out_i[7])],
             "memory_bytes": node_bytes + ctrl_bytes + heap_bytes,
             "rounding_floor": 2 * rounding,
             "seconds": time.perf_counter() - t0}
    return SurfaceDistance(distance=measured, lower=lower, upper=upper,
                           point_a=out_f[2:5].copy(), point_b=out_f[5:8].copy(),
                           uv_a=out_f[8:10].copy(), uv_b=out_f[10:12].copy(),
                           surface_a=int(out_i[0]), surface_b=int(out_i[1]) - nA,
                           certified=bool(upper - lower <= tol), tol=tol,
                           regions_refined=int(out_i[3]), stats=stats)
