"""A trimmed face's first grid of the estimates, clipped, measured and welded in one call.

:func:`geomkit.mesh.tessellate._trimmed_grid` takes a trimmed face through a dozen
kernel and numpy calls (the grid of the estimates, its triangles, the cells' classes
against the trim, the cut cells clipped, the groups, the distinct corners and their
points, the grouped measure, the weld): on a face of a few dozen cells that glue cost
a third of the face's time.  :func:`trimmed_first` makes the same calls with the same
kernels and inputs, in the same order, on its first grid: the same mesh, bit for bit.
Whatever the compiled clip leaves to GEOS, a grid above ``max_small`` cells, and every
later grid stay with the Python route.
"""

from __future__ import annotations

import numpy as np

from .numba_ext.policy import jit
from .surface import surface_points_range
from .tess_clip import CLIP_DONE, clip_cells
from .tess_grid import GRID_OK, _smaller, diagonals, grid_triangles, plan_cells
from .tess_lattice import _group_deviation_range, classify_cells
from .tess_rings import prepared_rings
from .tess_weld import unique_uv, weld_merge

FACE_OK = 0
"""Every kept triangle measures within ``tol``: the face's mesh."""
FACE_REFUSED = 1
"""The grid would exceed ``max_cells`` (:func:`.tess_grid.grid_plan`): no grid."""
FACE_FAILED = 2
"""A triangle above ``tol`` (or NaN): the next grid, smaller by ``worst``."""
FACE_LEFT = 3
"""Left to the Python route: more than ``max_small`` cells, a cut cell the compiled
clip does not take, or pieces whose area misses the region's."""
FACE_EMPTY = 4
"""No triangle is kept."""


@jit
def trimmed_first(Pw, p, q, U, V, ub, vb, m, target, max_cells, max_small, fold, CP,
                  cstarts, n_cut, RP, rstarts, tiny, k, tol, exact_above, near_r, near_w,
                  u0, u1, v0, v1, weld_eps, weld_r, weld_w):
    """The first try of :func:`geomkit.mesh.tessellate._trimmed_grid` for the surface
    ``Pw, p, q, U, V`` (domain ``u0, u1, v0, v1``): the grid of
    :func:`.tess_grid.grid_plan` (``ub, vb, m, target, max_cells, fold``; the
    diagonals' estimates taken for the cells inside the region only: the others are
    clipped or dropped), its triangles, the cells classified
    (:func:`.tess_lattice.classify_cells` on the rings ``CP[cstarts[i]:cstarts[i+1]]``,
    the first ``n_cut`` the trim loops), the cut ones
    clipped (:func:`.tess_clip.clip_cells` on the region's rings ``RP``, ``rstarts``
    made ready by :func:`.tess_rings.prepared_rings` with ``tiny``), the inside cells'
    triangle pairs and the pieces measured in their cells' groups
    (:func:`.tess_lattice._group_deviation_range`, ``k``, ``exact_above``) at their
    distinct corners' points (:func:`.tess_weld.unique_uv`, ``near_r``, ``near_w``
    when a cell is cut) and welded (:func:`.tess_weld.weld_merge`, ``weld_eps``,
    ``weld_r``, ``weld_w``).

    Returns ``(status, V, F, UV, good, dev, tri, n_cells, n_cut_cells, worst)``: with
    :data:`FACE_OK` the weld's vertices, faces, UVs and kept faces, each triangle's
    deviation and UV corners; else empty arrays (``worst``: the largest deviation,
    for :data:`FACE_FAILED`)."""
    e3 = np.empty((0, 3))
    eF = np.empty((0, 3), dtype=np.int64)
    e2 = np.empty((0, 2))
    eb = np.empty(0, dtype=np.bool_)
    e1 = np.empty(0)
    et = np.empty((0, 3, 2))
    status, _, _, cells, E, _, _ = plan_cells(Pw, p, q, U, V, ub, vb, m, target, max_cells,
                                              max_cells, fold)
    nc = cells.shape[0]
    if status != GRID_OK:
        return FACE_REFUSED, e3, eF, e2, eb, e1, et, 0, 0, np.nan
    if nc > max_small:
        return FACE_LEFT, e3, eF, e2, eb, e1, et, nc, 0, np.nan
    state = np.empty(nc, dtype=np.int8)
    classify_cells(CP, cstarts, n_cut, cells, state)
    # the diagonals of the smaller estimate (grid_plan's) of the inside cells only: a
    # cut cell is clipped, an outside one dropped
    diag = np.zeros(nc, dtype=np.int64)
    if nc == E.shape[0]:  # the root spans themselves: their estimates
        diag = _smaller(E)
    else:
        n_in = 0
        for c in range(nc):
            if state[c] == 1:
                n_in += 1
        inside = np.empty((n_in, 4))
        r = 0
        for c in range(nc):
            if state[c] == 1:
                inside[r] = cells[c]
                r += 1
        d_in = diagonals(Pw, p, q, U, V, inside, m, fold)
        r = 0
        for c in range(nc):
            if state[c] == 1:
                diag[c] = d_in[r]
                r += 1
    tri, _ = grid_triangles(cells, np.zeros(nc), diag)
    n_in = 0
    n_cut_cells = 0
    inside_area = 0.0
    for c in range(nc):
        if state[c] == 1:
            n_in += 1
            inside_area += (cells[c, 1] - cells[c, 0]) * (cells[c, 3] - cells[c, 2])
        elif state[c] == 2:
            n_cut_cells += 1
    cut = np.empty((n_cut_cells, 4))
    ctri = et
    cown = np.empty(0, dtype=np.int64)
    if n_cut_cells:
        r = 0
        cut_area = 0.0
        for c in range(nc):
            if state[c] == 2:
                cut[r] = cells[c]
                cut_area += (cells[c, 1] - cells[c, 0]) * (cells[c, 3] - cells[c, 2])
                r += 1
        Q, qs, dirs, region_area = prepared_rings(RP, rstarts, tiny)
        ctri, cown, status, area = clip_cells(cut, Q, qs, dirs)
        total = inside_area
        for c in range(n_cut_cells):
            if status[c] != CLIP_DONE:
                return FACE_LEFT, e3, eF, e2, eb, e1, et, nc, n_cut_cells, np.nan
            total += area[c]
        if abs(total - region_area) > 1e-9 * cut_area:
            return FACE_LEFT, e3, eF, e2, eb, e1, et, nc, n_cut_cells, np.nan
    # the inside cells' pairs (in cell order), then the pieces (in cut cell order)
    nt = 2 * n_in + ctri.shape[0]
    if nt == 0:
        return FACE_EMPTY, e3, eF, e2, eb, e1, et, nc, n_cut_cells, np.nan
    T = np.empty((nt, 3, 2))
    group = np.empty(nt, dtype=np.int64)
    r = 0
    for c in range(nc):
        if state[c] == 1:
            T[2 * r] = tri[2 * c]
            T[2 * r + 1] = tri[2 * c + 1]
            group[2 * r] = r
            group[2 * r + 1] = r
            r += 1
    g = n_in - 1
    for i in range(ctri.shape[0]):
        if i == 0 or cown[i] != cown[i - 1]:
            g += 1
        T[2 * n_in + i] = ctri[i]
        group[2 * n_in + i] = g
    starts = np.empty(g + 2, dtype=np.int64)
    starts[0] = 0
    for i in range(1, nt):
        if group[i] != group[i - 1]:
            starts[group[i]] = i
    starts[g + 1] = nt
    # distinct corners, their points (the measure's corners and the weld's vertices)
    uniq, inv, pairs = unique_uv(T.reshape((3 * nt, 2)), n_cut_cells > 0, near_r, near_w)
    P = np.empty((uniq.shape[0], 3))
    surface_points_range(0, uniq.shape[0], Pw, p, q, U, V, uniq, P)
    X = np.empty((nt, 3, 3))
    for t in range(nt):
        for c in range(3):
            X[t, c] = P[inv[3 * t + c]]
    dev = np.empty(nt)
    _group_deviation_range(0, nt, Pw, p, q, U, V, T, X, group, starts, k, exact_above, dev)
    worst = -np.inf
    bad = False
    for t in range(nt):
        if np.isnan(dev[t]) or np.isnan(worst):
            worst = np.nan
        else:
            worst = max(worst, dev[t])
        if not dev[t] <= tol:
            bad = True
    if bad:
        return FACE_FAILED, e3, eF, e2, eb, e1, et, nc, n_cut_cells, worst
    Vx, F, UV, good = weld_merge(P, uniq, inv, pairs, u0, u1, v0, v1, weld_eps, weld_r,
                                 weld_w)
    return FACE_OK, Vx, F, UV, good, dev, T, nc, n_cut_cells, worst
