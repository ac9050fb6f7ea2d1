"""Adaptive UV cells for tessellation: an anisotropic quadtree on an integer lattice.

Each root cell is one non-empty knot span (a Bézier patch), so creases (C0 knots)
always lie on cell edges.  A root span is divided into ``2**LEVELS`` lattice units per
direction; a cell is ``(iu0, iu1, iv0, iv1)`` in lattice units and splits in halves in
u, in v or in both.  Integer corners make vertex identity exact: two cells share a
corner exactly when the integers agree, and the UV value of a lattice point is one
fixed function of its integers.
"""

from __future__ import annotations

import numpy as np

from geomkit._kernels.tess import cell_deviation, cell_errors
from geomkit._kernels.tess_lattice import edge_counts, fill_rings
from geomkit._kernels.tess_lattice import split_counts as split_counts_kernel
from geomkit._kernels.tess_grid import (GRID_FAILED, GRID_OK, GRID_REFUSED, grid_plan,
                                       grid_triangles, small_grid)

LEVELS = 24
UNIT = 1 << LEVELS
KEY = 1 << 31  # key = major * KEY + minor, both < 2**31
SMALL_GRID = 64
"""A whole-domain grid of at most this many cells is tried in one compiled call
(:func:`geomkit._kernels.tess_grid.small_grid`, in the calling thread: the numpy and
kernel calls per face cost more than such a grid's arithmetic); larger ones, and any
grid whose first try fails, by the steps of :func:`uniform_grid` (the same grid)."""


class Lattice:
    """Maps lattice integers to UV values for root breakpoints ``ub`` x ``vb``."""

    def __init__(self, ub: np.ndarray, vb: np.ndarray):
        self.ub = np.asarray(ub, dtype=np.float64)
        self.vb = np.asarray(vb, dtype=np.float64)
        self.dub = np.diff(self.ub)
        self.dvb = np.diff(self.vb)
        self.gu_max = (len(self.ub) - 1) * UNIT
        self.gv_max = (len(self.vb) - 1) * UNIT

    @staticmethod
    def _map(g, b, db):
        g = np.asarray(g, dtype=np.int64)
        s = np.minimum(g >> LEVELS, len(b) - 2)
        f = (g - s * UNIT) / float(UNIT)
        out = b[s] + f * db[s]  # exact at span starts: f == 0
        out[g == (len(b) - 1) * UNIT] = b[-1]  # the last breakpoint exactly
        return out

    def u(self, g):
        return self._map(g, self.ub, self.dub)

    def v(self, g):
        return self._map(g, self.vb, self.dvb)

    def roots(self) -> np.ndarray:
        nu, nv = len(self.ub) - 1, len(self.vb) - 1
        i, j = np.meshgrid(np.arange(nu), np.arange(nv), indexing="ij")
        i, j = i.ravel(), j.ravel()
        return np.stack([i * UNIT, (i + 1) * UNIT, j * UNIT, (j + 1) * UNIT], axis=1)

    def cells_uv(self, cells: np.ndarray) -> np.ndarray:
        """(N, 4) float ``u0, u1, v0, v1``."""
        return np.stack([self.u(cells[:, 0]), self.u(cells[:, 1]),
                         self.v(cells[:, 2]), self.v(cells[:, 3])], axis=1)


def split(cells: np.ndarray, nu: np.ndarray, nv: np.ndarray) -> np.ndarray:
    """Split each cell into ``nu x nv`` children on integer boundaries (1 x 1 keeps it)."""
    out = [cells[(nu == 1) & (nv == 1)]]
    pairs = np.unique(np.stack([nu, nv], axis=1), axis=0)
    for a, b in pairs:
        if a == 1 and b == 1:
            continue
        c = cells[(nu == a) & (nv == b)]
        wu = c[:, 1] - c[:, 0]
        wv = c[:, 3] - c[:, 2]
        ou = _offsets(c[:, 0], wu, a)
        ov = _offsets(c[:, 2], wv, b)
        for i in range(a):
            for j in range(b):
                out.append(np.stack([ou[:, i], ou[:, i + 1], ov[:, j], ov[:, j + 1]], axis=1))
    return np.concatenate(out)


def _offsets(start: np.ndarray, width: np.ndarray, n: int) -> np.ndarray:
    """(N, n+1) lattice boundaries splitting ``[start, start + width]`` into n parts.

    Interior boundaries snap to a power-of-two grid of about an eighth of a part, so
    that cells split independently put nearby lines on the same lattice value
    (otherwise lines one unit apart leave sliver triangles between neighbours).
    """
    k = np.arange(n + 1)
    exact = start[:, None] + (width[:, None] * k[None, :]) // n
    g = np.maximum(width // (8 * n), 1)
    g = 1 << (np.floor(np.log2(g)).astype(np.int64))
    snapped = ((exact + g[:, None] // 2) // g[:, None]) * g[:, None]
    snapped[:, 0] = start
    snapped[:, -1] = start + width
    ok = np.all(np.diff(snapped, axis=1) > 0, axis=1)
    return np.where(ok[:, None], snapped, exact)


def split_counts(e, eu, ev, target, max_parts=8):
    """Children per direction so that the predicted error meets ``target``.

    Chord errors fall with the square of the cell size, and a cell's triangle error
    is about ``eu + ev`` (plus twist), so ``nu x nv`` is chosen to minimise the child
    count subject to ``eu / nu**2 + ev / nv**2 <= target`` (both halves of the budget
    when both directions matter); pure twist (neither direction's chords explain the
    error) splits both ways.
    """
    n = len(e)
    nu = np.empty(n, dtype=np.int64)
    nv = np.empty(n, dtype=np.int64)
    if n:  # one kernel call (the numpy formulas cost ~20 calls on a few cells)
        split_counts_kernel(e, eu, ev, float(target), int(max_parts), nu, nv)
    return nu, nv


def estimate(surface, lat: Lattice, cells: np.ndarray, m: int) -> np.ndarray:
    """(N, 5) cell error estimates (see :func:`geomkit._kernels.tess.cell_errors`)."""
    E = np.empty((cells.shape[0], 5))
    if cells.shape[0]:
        cell_errors(surface.homogeneous, surface.degree_u, surface.degree_v, surface.knots_u,
                    surface.knots_v, lat.cells_uv(cells), m, E)
    return E


def corner_angle(surface, lat: Lattice, cells: np.ndarray) -> np.ndarray:
    """Largest angle (radians) between the unit normals at a cell's four corners."""
    from geomkit.nurbs.evaluation import normals

    uv = lat.cells_uv(cells)
    corners = np.stack([uv[:, [0, 2]], uv[:, [1, 2]], uv[:, [1, 3]], uv[:, [0, 3]]], axis=1)
    N = normals(surface, corners.reshape(-1, 2)).reshape(-1, 4, 3)
    worst = np.zeros(cells.shape[0])
    for a in range(4):
        for b in range(a + 1, 4):
            c = np.clip(np.einsum("ij,ij->i", N[:, a], N[:, b]), -1.0, 1.0)
            worst = np.maximum(worst, np.arccos(c))
    return worst


def measure(surface, lat: Lattice, cells: np.ndarray, E: np.ndarray, k: int,
            exact_above: float, target: float):
    """(N, 2) measured deviation of each cell's two splits (see ``cell_deviation``).

    Only cells whose estimate passes ``target`` are measured (the others will be
    split anyway: their entries are +inf); the diagonal the estimate prefers is
    measured first and the other only if the first fails (+inf when skipped).
    """
    M = np.full((cells.shape[0], 2), np.inf)
    todo = np.nonzero(np.minimum(E[:, 0], E[:, 1]) <= target)[0]
    if len(todo):
        (u0, u1), (v0, v1) = surface.domain
        first = (E[todo, 1] < E[todo, 0]).astype(np.int64)
        out = np.empty((len(todo), 2))
        cell_deviation(surface.homogeneous, surface.degree_u, surface.degree_v,
                       surface.knots_u, surface.knots_v, lat.cells_uv(cells[todo]), first,
                       k, u0, u1, v0, v1, exact_above, target, out)
        M[todo] = out
    return M


def _replace(surface, lat, cells, E, M, moved, nu, nv, m, k, exact_above, target):
    """Split the ``moved`` cells and estimate/measure only their children."""
    kids = split(cells[moved], nu[moved], nv[moved])
    Ek = estimate(surface, lat, kids, m)
    return (np.concatenate([cells[~moved], kids]), np.concatenate([E[~moved], Ek]),
            np.concatenate([M[~moved], measure(surface, lat, kids, Ek, k, exact_above, target)]))


def refine(surface, lat: Lattice, cells: np.ndarray, target: float, m: int, k: int,
           exact_above: float, max_edge=None, max_angle=None, active=None, force=None,
           known=None, max_rounds: int = 60):
    """Split cells until each cell's better two-triangle split measures <= ``target``.

    Acceptance uses the measured deviation (:func:`measure`); how many children a
    failing cell gets comes from the chord estimates (:func:`split_counts`), or from
    the measured excess when the estimates see no need.  ``active(cells) -> mask``
    restricts refinement (e.g. to cells not trimmed away); ``force`` marks cells to
    halve once in both directions.  Values of unsplit cells are kept between rounds;
    ``known = (E, M)`` passes them in for ``cells`` from an earlier call.
    Returns ``(cells, E, M)``: estimates and measurements of the final cells.
    """
    if known is not None:
        E, M = known
    else:
        E = estimate(surface, lat, cells, m)
        M = measure(surface, lat, cells, E, k, exact_above, target)
    for _ in range(max_rounds):
        dev = np.minimum(M[:, 0], M[:, 1])
        need = dev > target
        nu, nv = split_counts(np.minimum(E[:, 0], E[:, 1]), E[:, 2], E[:, 3], target)
        if max_edge is not None:
            long_ = E[:, 4] > max_edge
            need |= long_
            kk = np.ceil(E[:, 4] / max_edge).astype(np.int64)
            nu = np.where(long_, np.maximum(nu, np.minimum(kk, 8)), nu)
            nv = np.where(long_, np.maximum(nv, np.minimum(kk, 8)), nv)
        if max_angle is not None:
            bent = corner_angle(surface, lat, cells) > max_angle
            need |= bent
            nu = np.where(bent, np.maximum(nu, 2), nu)
            nv = np.where(bent, np.maximum(nv, 2), nv)
        if force is not None:
            need |= force
            nu = np.where(force, np.maximum(nu, 2), nu)
            nv = np.where(force, np.maximum(nv, 2), nv)
            force = None
        if active is not None and need.any():
            need &= active(cells)
        wu = cells[:, 1] - cells[:, 0]
        wv = cells[:, 3] - cells[:, 2]
        # measured excess the estimates did not predict: split by the measured ratio
        miss = need & (nu == 1) & (nv == 1)
        excess = np.where(np.isfinite(dev), dev, np.minimum(E[:, 0], E[:, 1]))
        r = np.ceil(np.sqrt(np.clip(excess, target, 64 * target) / target)).astype(np.int64)
        r = np.clip(r, 2, 8)
        nu = np.where(miss, r, nu)
        nv = np.where(miss, r, nv)
        nu = np.where(need, np.minimum(nu, wu), 1)
        nv = np.where(need, np.minimum(nv, wv), 1)
        moved = (nu > 1) | (nv > 1)
        if not moved.any():
            return cells, E, M
        cells, E, M = _replace(surface, lat, cells, E, M, moved, nu, nv, m, k, exact_above,
                               target)
    return cells, E, M


def balance(surface, lat: Lattice, cells: np.ndarray, E: np.ndarray, M: np.ndarray, m: int,
            k: int, exact_above: float, target: float, max_hang: int = 2,
            max_rounds: int = 30):
    """Grade the cells: split any cell with more than ``max_hang`` hanging nodes on an
    edge, so no cell borders a much finer region.  Sampled measurements stay
    trustworthy (a coarse cell next to a sharply curved region is where sampling
    would miss the peak) and the conforming fans stay well shaped.
    Returns ``(cells, E, M)``."""
    for _ in range(max_rounds):
        cnt = EdgeIndex(lattice_points(cells), sorted_rows=True).counts(cells)
        hu = np.maximum(cnt[:, 0], cnt[:, 2])
        hv = np.maximum(cnt[:, 1], cnt[:, 3])
        wu = cells[:, 1] - cells[:, 0]
        wv = cells[:, 3] - cells[:, 2]
        nu = np.where(hu > max_hang, -(-(hu + 1) // (max_hang + 1)), 1)
        nv = np.where(hv > max_hang, -(-(hv + 1) // (max_hang + 1)), 1)
        nu = np.minimum(nu, wu)
        nv = np.minimum(nv, wv)
        moved = (nu > 1) | (nv > 1)
        if not moved.any():
            break
        cells, E, M = _replace(surface, lat, cells, E, M, moved, nu, nv, m, k, exact_above,
                               target)
    return cells, E, M


def lattice_points(cells: np.ndarray) -> np.ndarray:
    """(k, 2) unique lattice corners ``(gu, gv)`` of the cells, sorted by ``(gv, gu)``."""
    keys = unique_ints(np.concatenate([cells[:, 2] * KEY + cells[:, 0],
                                       cells[:, 2] * KEY + cells[:, 1],
                                       cells[:, 3] * KEY + cells[:, 1],
                                       cells[:, 3] * KEY + cells[:, 0]]))
    return np.stack([keys % KEY, keys // KEY], axis=1)


def unique_ints(a: np.ndarray) -> np.ndarray:
    """Sorted unique values of a 1-D integer array.  ``np.unique`` hashes integer
    arrays in numpy 2.x, measured 13x slower here than a sort and a neighbour test."""
    a = np.sort(a)
    if len(a) < 2:
        return a
    keep = np.empty(len(a), dtype=bool)
    keep[0] = True
    np.not_equal(a[1:], a[:-1], out=keep[1:])
    return a[keep]


class EdgeIndex:
    """Finds lattice points strictly inside cell edges (the hanging nodes)."""

    def __init__(self, pts: np.ndarray, sorted_rows: bool = False):
        h = pts[:, 1] * KEY + pts[:, 0]
        self.h = h if sorted_rows else np.sort(h)  # rows: v major
        self.v = np.sort(pts[:, 0] * KEY + pts[:, 1])  # columns: u major

    def counts(self, cells: np.ndarray) -> np.ndarray:
        """(N, 4) numbers of hanging nodes on the bottom, right, top, left edges."""
        out = np.empty((cells.shape[0], 4), dtype=np.int64)
        if len(cells):
            edge_counts(self.h, self.v, KEY, np.ascontiguousarray(cells), out)
        return out

    def rings(self, cells: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Lattice points around each cell counter-clockwise from (iu0, iv0).

        Returns ``(starts, points)``: cell i's ring is ``points[starts[i]:starts[i+1]]``.
        """
        sizes = 4 + self.counts(cells).sum(axis=1)
        starts = np.zeros(len(cells) + 1, dtype=np.int64)
        np.cumsum(sizes, out=starts[1:])
        out = np.empty((starts[-1], 2), dtype=np.int64)
        if len(cells):
            fill_rings(self.h, self.v, KEY, np.ascontiguousarray(cells), starts, out)
        return starts, out


def _tensor_cells(u: np.ndarray, v: np.ndarray) -> np.ndarray:
    """(len(u)-1) * (len(v)-1) cells ``u0, u1, v0, v1`` of the tensor grid of lines
    ``u`` x ``v``, row-major (cell ``i * (len(v)-1) + j`` spans ``u[i:i+2] x v[j:j+2]``)."""
    c = np.empty((len(u) - 1, len(v) - 1, 4))
    c[..., 0] = u[:-1, None]
    c[..., 1] = u[1:, None]
    c[..., 2] = v[:-1]
    c[..., 3] = v[1:]
    return c.reshape(-1, 4)




def uniform_grid(surface, ub: np.ndarray, vb: np.ndarray, m: int, k: int, tol: float,
                 target: float, exact_above: float, max_cells: int, box=None,
                 pair: bool = False, closed=(False, False), first=None):
    """One tensor grid of cells for a surface whose first estimate asks for few cells.

    Each root span gets ``nu x nv`` equal children from :func:`split_counts` of its
    estimate for ``target`` (the largest count of its row / column, so the grid has
    no hanging nodes); every cell's two-triangle split is measured (``cell_deviation``,
    as in :func:`measure`) and its better diagonal kept; if a cell fails ``tol``, one
    more grid is tried with ``target`` scaled down by the excess, then, on a surface
    with a pole (the estimates miss what the measurement sees at a cone's apex), one
    with the failing grid's lines multiplied by the square root of its excess.
    Returns ``(tri_uv
    (M, 3, 2), dev (M,), cells, (u, v, diag))``: triangles counter-clockwise in UV, two
    per cell (row-major, see :func:`_tensor_cells`), the grid lines and each cell's
    diagonal (0: (u0,v0)-(u1,v1), 1: (u1,v0)-(u0,v1)); or None when the grid would
    exceed ``max_cells`` or a cell fails ``tol`` (the adaptive path then takes over).
    The measurement is the one adaptive refinement accepts cells with, so the stated
    bound is the same.  ``box`` ``(u0, u1, v0, v1)``: the face's rectangle when it is
    a part of the domain (``ub``, ``vb`` then run from its corners): the measurement's
    feet stay in it.  The estimates include the sag of the box's edges, or of the
    domain's without a box (``cell_errors``' ``box``: the normal gap misses a boundary
    that bends in the tangent plane, as a cone's rim does, which the measurement
    sees), but for the edges of a direction the surface is ``closed`` in that the grid
    spans: a seam, not a boundary (:func:`fold_lines`).  ``first``: the first grid's
    ``(status, E, cu, cv, worst)`` from :func:`geomkit._kernels.tess_grid.small_grid`
    when the caller has measured it (the grid kept is not: a status other than
    ``GRID_OK``), to go on from.  ``pair``: the grid is the face (untrimmed, or ``box``):
    cells are measured with ``cell_deviation``'s ``pair``.
    """
    nsu, nsv = len(ub) - 1, len(vb) - 1
    if nsu * nsv > max_cells:
        return None
    Pw, p, q, U, V = (surface.homogeneous, surface.degree_u, surface.degree_v,
                      surface.knots_u, surface.knots_v)
    start = 0
    # the measurement's feet: the box's, else the domain's (the edge sags: fold_lines)
    u0, u1, v0, v1 = (*surface.domain[0], *surface.domain[1]) if box is None else box
    # the first grid in one compiled call (the same grid): kept when it is small and
    # passes; else the steps below go on from its estimates (and its measurement)
    fold = fold_lines(surface, box, closed)
    if first is None:
        status, u, v, cells, dev, diag, E, cu, cv, worst = small_grid(
            Pw, p, q, U, V, ub, vb, m, k, float(tol), float(target), float(exact_above),
            int(max_cells), SMALL_GRID, float(u0), float(u1), float(v0), float(v1),
            bool(pair), fold)
    else:
        status, E, cu, cv, worst = first
    if status == GRID_REFUSED:
        return None
    if status == GRID_OK:
        return _grid_triangles(cells, dev, diag) + (cells, (u, v, diag))
    if status == GRID_FAILED:  # as the loop below after its first grid
        grow = (cu, cv, min(np.sqrt(worst / target), 2.0) if np.isfinite(worst) else 2.0)
        target *= max(0.25, target / worst) if np.isfinite(worst) else 0.25
        start = 1
    for attempt in range(start, 3):  # the target scaled by the excess measured
        nu, nv = split_counts(np.minimum(E[:, 0], E[:, 1]), E[:, 2], E[:, 3], target,
                              max_parts=max_cells)
        cu = nu.reshape(nsu, nsv).max(axis=1)
        cv = nv.reshape(nsu, nsv).max(axis=0)
        if attempt == 2:  # at least the last grid's lines times its measured excess
            cu = np.maximum(cu, np.ceil(grow[0] * grow[2]).astype(np.int64))
            cv = np.maximum(cv, np.ceil(grow[1] * grow[2]).astype(np.int64))
        if int(cu.sum()) * int(cv.sum()) > max_cells:
            return None
        if cu.max() == 1 and cv.max() == 1:  # the root spans themselves
            u, v, cells, Ec = ub, vb, _tensor_cells(ub, vb), E
        else:
            u = _lines(ub, cu)
            v = _lines(vb, cv)
            cells = _tensor_cells(u, v)
            Ec = np.empty((len(cells), 5))
            cell_errors(Pw, p, q, U, V, cells, m, Ec, box=fold)
        first = (Ec[:, 1] < Ec[:, 0]).astype(np.int64)
        M = np.empty((len(cells), 2))
        cell_deviation(Pw, p, q, U, V, cells, first, k, u0, u1, v0, v1, exact_above, tol, M,
                       pair)
        diag = np.argmin(M, axis=1)
        rows = np.arange(len(cells))
        dev = M[rows, diag]
        worst = float(dev.max())
        if worst <= tol:
            break
        if attempt == 1 and not _has_pole(surface):
            return None
        # the estimates can miss what the measurement sees (a cone's apex): the
        # last try also refines the grid before it, by the square root of the excess
        grow = (cu, cv, min(np.sqrt(worst / target), 2.0) if np.isfinite(worst) else 2.0)
        # errors fall with the square of the cell size: aim the retry below target
        target *= max(0.25, target / worst) if np.isfinite(worst) else 0.25
    else:
        return None
    return _grid_triangles(cells, dev, diag) + (cells, (u, v, diag))


def fold_lines(surface, box, closed) -> np.ndarray:
    """``(u0, u1, v0, v1)``: the edge lines of ``box`` (else the domain) whose sags the
    grid estimates take, NaN (none) in a direction the surface is ``closed`` in
    (``(closed_u, closed_v)``) where the grid spans the whole domain: those edges are the
    seam, across which the mesh goes on."""
    (d0, d1), (e0, e1) = surface.domain
    a0, a1, b0, b1 = (d0, d1, e0, e1) if box is None else box
    nan = float("nan")
    fu = (nan, nan) if closed[0] and a0 == d0 and a1 == d1 else (a0, a1)
    fv = (nan, nan) if closed[1] and b0 == e0 and b1 == e1 else (b0, b1)
    return np.array(fu + fv, dtype=np.float64)


def planned_grid(surface, ub: np.ndarray, vb: np.ndarray, m: int, target: float,
                 max_cells: int, closed=(False, False)):
    """The first grid :func:`uniform_grid` would measure (the root spans' children from
    the estimates, :func:`geomkit._kernels.tess_grid.grid_plan`), unmeasured: ``(cells,
    diag)``, each cell's diagonal the one of the smaller estimate; None above
    ``max_cells``.  For a trimmed face, whose kept triangles are measured once clipped."""
    ok, _, _, cells, diag = grid_plan(surface.homogeneous, surface.degree_u,
                                      surface.degree_v, surface.knots_u, surface.knots_v,
                                      ub, vb, m, float(target), int(max_cells),
                                      fold_lines(surface, None, closed))
    return (cells, diag) if ok else None


def _grid_triangles(cells, dev, diag):
    """``(tri_uv (2N, 3, 2), dev (2N,))``: each cell's two triangles by its diagonal,
    counter-clockwise in UV, and their cell's deviation
    (:func:`geomkit._kernels.tess_grid.grid_triangles`)."""
    return grid_triangles(np.ascontiguousarray(cells, dtype=np.float64),
                          np.ascontiguousarray(dev, dtype=np.float64),
                          np.ascontiguousarray(diag, dtype=np.int64))


def _has_pole(surface) -> bool:
    """Whether an edge row or column of the net is one point (a cone's apex, a sphere's
    pole): there the chord estimates miss what the measurement sees."""
    P = surface.control_points
    eps = 1e-12 * surface.size
    return any(float(np.ptp(e, axis=0).max()) <= eps for e in (P[0], P[-1], P[:, 0], P[:, -1]))


def _lines(b: np.ndarray, counts: np.ndarray) -> np.ndarray:
    """Breakpoints ``b`` with ``counts[i]`` equal parts in span i (span ends exact)."""
    n = int(counts.sum())
    out = np.empty(n + 1)
    out[n] = b[-1]
    if n == len(counts):  # one part a span: the spans' starts
        out[:n] = b[:-1]
        return out
    # span i's j-th line b[i] + (b[i+1] - b[i]) * (j / c_i), as the per-span formula
    span = np.repeat(np.arange(len(counts)), counts)
    starts = np.cumsum(counts) - counts
    j = np.arange(n) - starts[span]
    out[:n] = b[span] + (b[span + 1] - b[span]) * (j / counts[span])
    return out
