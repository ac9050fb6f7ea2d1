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

from ._kernels.tess import cell_errors

LEVELS = 24
UNIT = 1 << LEVELS
KEY = 1 << 31  # key = major * KEY + minor, both < 2**31


class Lattice:
    """Maps lattice integers to UV values for root breakpoints ``ub`` x ``vb``."""

    def __init__(self, ub: np.ndarray, vb: np.ndarray):
        self.ub = np.asarray(ub, dtype=np.float64)
        self.vb = np.asarray(vb, dtype=np.float64)
        self.gu_max = (len(self.ub) - 1) * UNIT
        self.gv_max = (len(self.vb) - 1) * UNIT

    @staticmethod
    def _map(g, b):
        g = np.asarray(g, dtype=np.int64)
        span = g >> LEVELS
        s = np.minimum(span, len(b) - 2)
        f = (g - s * UNIT) / float(UNIT)
        out = b[s] + f * (b[s + 1] - b[s])
        exact = (g & (UNIT - 1)) == 0
        out = np.where(exact, b[np.minimum(span, len(b) - 1)], out)
        return out

    def u(self, g):
        return self._map(g, self.ub)

    def v(self, g):
        return self._map(g, self.vb)

    def roots(self) -> np.ndarray:
        nu, nv = len(self.ub) - 1, len(self.vb) - 1
        i, j = np.meshgrid(np.arange(nu), np.arange(nv), indexing="ij")
        i, j = i.ravel(), j.ravel()
        return np.stack([i * UNIT, (i + 1) * UNIT, j * UNIT, (j + 1) * UNIT], axis=1)

    def cells_uv(self, cells: np.ndarray) -> np.ndarray:
        """(N, 4) float ``u0, u1, v0, v1``."""
        return np.stack([self.u(cells[:, 0]), self.u(cells[:, 1]),
                         self.v(cells[:, 2]), self.v(cells[:, 3])], axis=1)


def split(cells: np.ndarray, su: np.ndarray, sv: np.ndarray) -> np.ndarray:
    """Split cells in halves along u where ``su``, along v where ``sv`` (both: 4 kids)."""
    keep = cells[~(su | sv)]
    out = [keep]
    both = cells[su & sv]
    only_u = cells[su & ~sv]
    only_v = cells[sv & ~su]
    for c, du, dv in ((both, True, True), (only_u, True, False), (only_v, False, True)):
        if not len(c):
            continue
        us = [(c[:, 0], (c[:, 0] + c[:, 1]) // 2), ((c[:, 0] + c[:, 1]) // 2, c[:, 1])] if du \
            else [(c[:, 0], c[:, 1])]
        vs = [(c[:, 2], (c[:, 2] + c[:, 3]) // 2), ((c[:, 2] + c[:, 3]) // 2, c[:, 3])] if dv \
            else [(c[:, 2], c[:, 3])]
        for a0, a1 in us:
            for b0, b1 in vs:
                out.append(np.stack([a0, a1, b0, b1], axis=1))
    return np.concatenate(out)


def estimate(surface, lat: Lattice, cells: np.ndarray, m: int) -> np.ndarray:
    """(N, 5) cell error estimates (see :func:`geomkit._kernels.tess.cell_errors`)."""
    E = np.empty((cells.shape[0], 5))
    if cells.shape[0]:
        cell_errors(surface.homogeneous, surface.degree_u, surface.degree_v, surface.knots_u,
                    surface.knots_v, lat.cells_uv(cells), m, E)
    return E


def corner_angle(surface, lat: Lattice, cells: np.ndarray) -> np.ndarray:
    """Largest angle (radians) between the unit normals at a cell's four corners."""
    from .evaluation import normals

    uv = lat.cells_uv(cells)
    corners = np.stack([uv[:, [0, 2]], uv[:, [1, 2]], uv[:, [1, 3]], uv[:, [0, 3]]], axis=1)
    N = normals(surface, corners.reshape(-1, 2)).reshape(-1, 4, 3)
    worst = np.zeros(cells.shape[0])
    for a in range(4):
        for b in range(a + 1, 4):
            c = np.clip(np.einsum("ij,ij->i", N[:, a], N[:, b]), -1.0, 1.0)
            worst = np.maximum(worst, np.arccos(c))
    return worst


def refine(surface, lat: Lattice, cells: np.ndarray, target: float, m: int,
           max_edge=None, max_angle=None, active=None, force=None, max_rounds: int = 60):
    """Split cells until each cell's best two-triangle split deviates <= ``target``.

    ``active(cells) -> bool mask`` restricts refinement (e.g. to cells not trimmed
    away); ``force`` is a mask of cells to split once regardless of their estimate.
    The split direction follows the estimates: a direction is split when its chord
    error is at least a quarter of the larger one (halving cuts a chord error by 4),
    both when the error is twist (neither direction's chords explain it).
    Returns ``(cells, E)`` with the final estimates.
    """
    for _ in range(max_rounds):
        E = estimate(surface, lat, cells, m)
        e = np.minimum(E[:, 0], E[:, 1])
        need = e > target
        if max_edge is not None:
            need |= E[:, 4] > max_edge
        if max_angle is not None:
            need |= corner_angle(surface, lat, cells) > max_angle
        if force is not None:
            need |= force
            force = None
        if active is not None and need.any():
            need &= active(cells)
        can_u = (cells[:, 1] - cells[:, 0]) > 1
        can_v = (cells[:, 3] - cells[:, 2]) > 1
        eu, ev = E[:, 2], E[:, 3]
        big = np.maximum(eu, ev)
        twist = big < 0.25 * e
        su = need & can_u & ((eu >= 0.25 * big) | twist)
        sv = need & can_v & ((ev >= 0.25 * big) | twist)
        # a cell that must split but whose preferred direction is exhausted uses the other
        su |= need & ~sv & can_u
        sv |= need & ~su & can_v
        if not (su | sv).any():
            return cells, E
        cells = split(cells, su, sv)
    return cells, estimate(surface, lat, cells, m)


def lattice_points(cells: np.ndarray) -> np.ndarray:
    """(k, 2) unique lattice corners ``(gu, gv)`` of the cells."""
    c = np.concatenate([cells[:, [0, 2]], cells[:, [1, 2]], cells[:, [1, 3]], cells[:, [0, 3]]])
    return np.unique(c, axis=0)


class EdgeIndex:
    """Finds lattice points strictly inside cell edges (the hanging nodes)."""

    def __init__(self, pts: np.ndarray):
        self.h = np.sort(pts[:, 1] * KEY + pts[:, 0])  # rows: v major
        self.v = np.sort(pts[:, 0] * KEY + pts[:, 1])  # columns: u major

    def _range(self, keys, major, lo, hi):
        a = np.searchsorted(keys, major * KEY + lo, side="right")
        b = np.searchsorted(keys, major * KEY + hi, side="left")
        return a, b

    def counts(self, cells: np.ndarray) -> np.ndarray:
        """(N, 4) numbers of hanging nodes on the bottom, right, top, left edges."""
        out = np.empty((cells.shape[0], 4), dtype=np.int64)
        a, b = self._range(self.h, cells[:, 2], cells[:, 0], cells[:, 1])
        out[:, 0] = b - a
        a, b = self._range(self.v, cells[:, 1], cells[:, 2], cells[:, 3])
        out[:, 1] = b - a
        a, b = self._range(self.h, cells[:, 3], cells[:, 0], cells[:, 1])
        out[:, 2] = b - a
        a, b = self._range(self.v, cells[:, 0], cells[:, 2], cells[:, 3])
        out[:, 3] = b - a
        return out

    def ring(self, c) -> np.ndarray:
        """(k, 2) lattice points around cell ``c`` counter-clockwise, from (iu0, iv0)."""
        iu0, iu1, iv0, iv1 = (int(x) for x in c)
        pts = [(iu0, iv0)]
        a, b = self._range(self.h, iv0, iu0, iu1)
        pts += [(int(k % KEY), iv0) for k in self.h[a:b]]
        pts.append((iu1, iv0))
        a, b = self._range(self.v, iu1, iv0, iv1)
        pts += [(iu1, int(k % KEY)) for k in self.v[a:b]]
        pts.append((iu1, iv1))
        a, b = self._range(self.h, iv1, iu0, iu1)
        pts += [(int(k % KEY), iv1) for k in self.h[a:b][::-1]]
        pts.append((iu0, iv1))
        a, b = self._range(self.v, iu0, iv0, iv1)
        pts += [(iu0, int(k % KEY)) for k in self.v[a:b][::-1]]
        return np.array(pts, dtype=np.int64)
