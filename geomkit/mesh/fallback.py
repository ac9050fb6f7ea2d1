"""The fallback route for a face whose triangulation failed: no single face sinks a model.

The primary route (:func:`geomkit.mesh.tessellate.tessellate`) clips cut cells and
triangulates trimmed planes with GEOS (via shapely), whose overlay and constrained
triangulation can refuse an input ("Unable to find a convex corner" on nearly
collinear trim points).  The fallback uses neither:

1. **Trim loops** as the primary route makes them (:class:`~geomkit.mesh.trim_polylines.
   TrimPolylines`, the same 3-D chord error); a face whose loops cannot be built fails
   here too, and says so.
2. **Staircase.**  The *untrimmed* surface's lattice cells (:mod:`geomkit.mesh.quadtree`):
   a cell that a trim segment crosses (exact segment-rectangle test) is halved until its
   3-D corner chords are within ``trim_target * tol``; any other cell is wholly in or
   out, by the even-odd rule on the loops (a ray from its centre).  A crossed cell is
   kept whole, so the mesh covers the trimmed region and overhangs it by at most one
   such cell; ``stats["fallback_overhang"]`` states the largest 3-D corner chord of a
   crossed cell.
3. **Measured guarantee.**  The kept cells go through the adaptive rounds of
   :func:`geomkit.mesh.cells.adaptive_cells`: every triangle is measured against the
   exact surface and is within ``tol``, as on the primary route.

Only the segments' r-tree (bounding boxes) is asked of GEOS.
"""

from __future__ import annotations

import time

import numpy as np

from geomkit.mesh import quadtree as qt
from geomkit.mesh.cells import adaptive_cells, breakpoints, closed_directions
from geomkit.mesh.trim_polylines import TrimPolylines
from geomkit.mesh.weld import points
from geomkit.errors import MeshingError
from geomkit.nurbs.surface import Surface

__all__ = ["fallback_face", "FALLBACK_CELLS"]

FALLBACK_CELLS = 200_000
"""The staircase stops halving crossed cells before it would hold more cells than this
(a face with a very long boundary at a fine tolerance); its overhang is then larger than
``trim_target * tol`` and ``stats["fallback_overhang"]`` states it."""


class Staircase:
    """Lattice cells against trim loops (UV polylines), without polygon overlays.

    ``classify(lat, cells)`` gives 0 (outside the trimmed region), 1 (inside) or 2 (a
    trim segment meets the cell's rectangle).  The region is the even-odd region of
    the loops, complemented when ``domain_loop`` (a loop was the domain rectangle),
    as :attr:`TrimPolylines.region` makes it."""

    def __init__(self, loops, domain_loop: bool):
        import shapely

        A = np.concatenate([p[:-1] for p in loops])
        B = np.concatenate([p[1:] for p in loops])
        keep = np.any(A != B, axis=1)
        self.A, self.B = A[keep], B[keep]
        self.base = bool(domain_loop)
        self.tree = shapely.STRtree(shapely.linestrings(np.stack([self.A, self.B], axis=1)))
        self.u_far = float(max(self.A[:, 0].max(), self.B[:, 0].max()))

    def crossed(self, uv: np.ndarray) -> np.ndarray:
        """(N,) bool: a segment meets the rectangle ``u0, u1, v0, v1`` (N, 4) (boxes
        overlap from the r-tree, then the four corners not all strictly on one side
        of the segment's line)."""
        import shapely

        out = np.zeros(len(uv), dtype=bool)
        ci, si = self.tree.query(shapely.box(uv[:, 0], uv[:, 2], uv[:, 1], uv[:, 3]))
        if not len(ci):
            return out
        A, d = self.A[si], self.B[si] - self.A[si]
        c = uv[ci]
        side = np.stack([d[:, 0] * (c[:, 2 + j] - A[:, 1]) - d[:, 1] * (c[:, i] - A[:, 0])
                         for i, j in ((0, 0), (1, 0), (1, 1), (0, 1))], axis=1)
        hit = (side.min(axis=1) <= 0) & (side.max(axis=1) >= 0)
        out[ci[hit]] = True
        return out

    def inside(self, P: np.ndarray) -> np.ndarray:
        """(n,) bool for points (n, 2) off the segments: the even-odd rule along the
        ray ``v = const`` towards +u."""
        import shapely

        n = len(P)
        ray = np.empty((n, 2, 2))
        ray[:, 0] = P
        ray[:, 1, 0] = max(self.u_far, float(P[:, 0].max())) + 1.0
        ray[:, 1, 1] = P[:, 1]
        pi, si = self.tree.query(shapely.linestrings(ray))
        A, B = self.A[si], self.B[si]
        y = P[pi, 1]
        straddle = (A[:, 1] > y) != (B[:, 1] > y)
        with np.errstate(divide="ignore", invalid="ignore"):
            u = A[:, 0] + (y - A[:, 1]) * (B[:, 0] - A[:, 0]) / (B[:, 1] - A[:, 1])
        cross = straddle & (u > P[pi, 0])
        odd = np.bincount(pi[cross], minlength=n) % 2 == 1
        return odd != self.base

    def classify(self, lat, cells: np.ndarray) -> np.ndarray:
        uv = lat.cells_uv(cells)
        state = np.where(self.crossed(uv), 2, 0).astype(np.int8)
        rest = np.nonzero(state == 0)[0]
        if len(rest):
            c = uv[rest]
            P = np.c_[0.5 * (c[:, 0] + c[:, 1]), 0.5 * (c[:, 2] + c[:, 3])]
            state[rest] = self.inside(P)
        return state

    def kept(self, lat, cells: np.ndarray) -> np.ndarray:
        """:meth:`classify` with crossed cells kept whole (1): no cell is clipped."""
        return np.minimum(self.classify(lat, cells), 1)


def _diagonals(s: Surface, lat, cells: np.ndarray) -> np.ndarray:
    """(N,) the longer 3-D chord between opposite corners of each cell."""
    uv = lat.cells_uv(cells)
    C = np.stack([uv[:, [0, 2]], uv[:, [1, 2]], uv[:, [1, 3]], uv[:, [0, 3]]], axis=1)
    P = points(s, C.reshape(-1, 2)).reshape(-1, 4, 3)
    return np.maximum(np.linalg.norm(P[:, 2] - P[:, 0], axis=1),
                      np.linalg.norm(P[:, 3] - P[:, 1], axis=1))


def staircase_cells(s: Surface, lat, cells: np.ndarray, stair: Staircase, h: float):
    """``cells`` with every crossed cell halved until its corner chords are within ``h``
    (or it is one lattice unit wide, or the cells would exceed :data:`FALLBACK_CELLS`);
    returns ``(cells, overhang)``: the largest such chord left."""
    for _ in range(qt.LEVELS + 1):
        cut = np.nonzero(stair.classify(lat, cells) == 2)[0]
        if not len(cut):
            return cells, 0.0
        chord = _diagonals(s, lat, cells[cut])
        wu = cells[cut, 1] - cells[cut, 0]
        wv = cells[cut, 3] - cells[cut, 2]
        need = (chord > h) & ((wu > 1) | (wv > 1))
        if not need.any() or len(cells) + 3 * int(need.sum()) > FALLBACK_CELLS:
            return cells, float(chord.max())
        moved = np.zeros(len(cells), dtype=bool)
        moved[cut[need]] = True
        nu = np.minimum(2, wu[need])
        nv = np.minimum(2, wv[need])
        cells = np.concatenate([cells[~moved], qt.split(cells[moved], nu, nv)])
    cut = stair.classify(lat, cells) == 2
    return cells, float(_diagonals(s, lat, cells[cut]).max()) if cut.any() else 0.0


def fallback_face(s: Surface, tol: float, max_angle, max_edge, k: int, trim_target: float,
                  why: str, pair_tol: float | None = None, cross_knots: bool = False):
    """One face meshed by the fallback route (see the module docstring), after the
    primary route failed with ``why``: ``(V, F, UV, dev, tri_uv, stats)`` with every
    triangle measured within ``tol``; ``stats["fallback"]`` is ``why``; ``pair_tol``,
    ``cross_knots``: the trim polylines' (those of the primary route,
    :class:`~geomkit.mesh.trim_polylines.TrimPolylines`).  Raises
    :class:`~geomkit.errors.MeshingError` when the trim loops cannot be built."""
    t0 = time.perf_counter()
    size = s.size
    trim = None
    if s.trim:
        try:
            trim = TrimPolylines(s, trim_target * tol, pair_tol=pair_tol,
                                 cross_knots=cross_knots)
        except Exception as exc:  # noqa: BLE001 - named: the face cannot be bounded
            raise MeshingError(f"its trim loops could not be built "
                               f"({type(exc).__name__}: {exc})") from exc
    lat = qt.Lattice(breakpoints(s.knots_u, s.degree_u), breakpoints(s.knots_v, s.degree_v))
    cells = lat.roots()
    overhang = 0.0
    classify = None
    if trim is not None and trim.loops:
        stair = Staircase(trim.loops, trim.domain_loop)
        cells, overhang = staircase_cells(s, lat, cells, stair, trim_target * tol)
        classify = stair.kept
        if not np.any(classify(lat, cells)):
            raise MeshingError("the trimmed region holds no cell of the surface")
    m = max(5, 2 * max(s.degree_u, s.degree_v) + 1)
    V, F, UV, dev, tri_uv, stats = adaptive_cells(
        s, tol, max_angle, max_edge, k, m, lat, cells, classify, None,
        closed_directions(s, size), size, t0)
    if not len(F):
        raise MeshingError("the fallback kept no triangle")
    stats.update({"fallback": why, "fallback_overhang": overhang})
    return V, F, UV, dev, tri_uv, stats
