"""A small uniform grid of cells in one compiled call (the first try of
:func:`geomkit.mesh.quadtree.uniform_grid` on a whole domain or a face's box).

The Python route makes a dozen numpy and kernel calls per face (root estimates,
children counts, grid lines, cells, their estimates, the measurement, the better
diagonal, the triangles): on the small grids of most cylinders and cones of real parts
that glue costs more than the arithmetic.  :func:`small_grid` does the same steps with
the same kernels (:func:`.tess._cell_errors_box_range` with the domain as the box,
:func:`.tess_lattice.split_counts`, :func:`.tess._cell_deviation_range`, each over its
whole range in this thread, as the Python route runs a range of at most one chunk) and the glue's formulas without
contraction (each ``a * b + c`` rounded twice, as numpy): the same grid, bit for bit.
"""

from __future__ import annotations

import numpy as np

from .numba_ext.policy import jit_exact as jit
from .surface import surface_points_range
from .tess import _cell_deviation_range, _cell_errors_box_range
from .tess_lattice import split_counts

GRID_OK = 0
"""The grid's cells all measure within ``tol``."""
GRID_REFUSED = 1
"""More cells than ``max_cells``: the Python route refuses the grid too."""
GRID_BIG = 2
"""More cells than ``max_small``: the Python route measures them (its threads)."""
GRID_FAILED = 3
"""A cell above ``tol`` (or NaN): the Python route tries its next grid."""


@jit
def _tensor(u, v):
    """:func:`geomkit.mesh.quadtree._tensor_cells`: row-major cells ``u0, u1, v0, v1``."""
    nu = u.shape[0] - 1
    nv = v.shape[0] - 1
    c = np.empty((nu * nv, 4))
    for i in range(nu):
        for j in range(nv):
            r = i * nv + j
            c[r, 0] = u[i]
            c[r, 1] = u[i + 1]
            c[r, 2] = v[j]
            c[r, 3] = v[j + 1]
    return c


@jit
def _lines(b, counts):
    """:func:`geomkit.mesh.quadtree._lines`: ``b[i] + (b[i+1] - b[i]) * (j / c_i)``."""
    n = 0
    for c in counts:
        n += c
    out = np.empty(n + 1)
    r = 0
    for i in range(counts.shape[0]):
        c = counts[i]
        d = b[i + 1] - b[i]
        for j in range(c):
            out[r] = b[i] + d * (j / c)
            r += 1
    out[n] = b[b.shape[0] - 1]
    return out


@jit
def _plan(Pw, p, q, U, V, ub, vb, m, target, max_cells, max_small, fold):
    """The grid of the estimates (``fold``: the edge lines whose sags the estimates
    take, :func:`.tess._cell_errors_box_range`'s ``bu0, bu1, bv0, bv1``): ``(status, u, v, cells, first, E, cu, cv)``, the
    grid lines, cells (N, 4) and each cell's diagonal of the smaller estimate
    (:data:`GRID_OK`), or :data:`GRID_BIG` / :data:`GRID_REFUSED` with empty ones; the
    root spans' estimates ``E`` and children counts ``cu``, ``cv`` (but for a refusal
    before them)."""
    status, u, v, cells, E, cu, cv = plan_cells(Pw, p, q, U, V, ub, vb, m, target,
                                                max_cells, max_small, fold)
    if status != GRID_OK:
        return status, u, v, cells, np.empty(0, dtype=np.int64), E, cu, cv
    if cells.shape[0] == E.shape[0]:  # the root spans themselves: their estimates
        return status, u, v, cells, _smaller(E), E, cu, cv
    return status, u, v, cells, diagonals(Pw, p, q, U, V, cells, m, fold), E, cu, cv


@jit
def _smaller(Ec):
    """1 where a cell's second diagonal's estimate ``Ec[:, 1]`` is below its first's."""
    first = np.empty(Ec.shape[0], dtype=np.int64)
    for i in range(Ec.shape[0]):
        first[i] = 1 if Ec[i, 1] < Ec[i, 0] else 0
    return first


@jit
def diagonals(Pw, p, q, U, V, cells, m, fold):
    """Each cell's diagonal of the smaller estimate (:func:`.tess._cell_errors_box_range`,
    ``fold`` its edge lines): 1 when the second's is smaller, else 0."""
    Ec = np.empty((cells.shape[0], 5))
    _cell_errors_box_range(0, cells.shape[0], Pw, p, q, U, V, cells, m, fold[0], fold[1],
                           fold[2], fold[3], Ec)
    return _smaller(Ec)


@jit
def plan_cells(Pw, p, q, U, V, ub, vb, m, target, max_cells, max_small, fold):
    """The cells of :func:`_plan`'s grid without their diagonals: ``(status, u, v,
    cells, E, cu, cv)``."""
    nsu = ub.shape[0] - 1
    nsv = vb.shape[0] - 1
    empty1 = np.empty(0)
    empty2 = np.empty((0, 4))
    empty5 = np.empty((0, 5))
    noint = np.empty(0, dtype=np.int64)
    if nsu * nsv > max_cells:
        return GRID_REFUSED, empty1, empty1, empty2, empty5, noint, noint
    roots = _tensor(ub, vb)
    nr = roots.shape[0]
    E = np.empty((nr, 5))
    _cell_errors_box_range(0, nr, Pw, p, q, U, V, roots, m, fold[0], fold[1], fold[2],
                           fold[3], E)
    e = np.empty(nr)
    for i in range(nr):
        e[i] = min(E[i, 0], E[i, 1]) if not (np.isnan(E[i, 0]) or np.isnan(E[i, 1])) \
            else np.nan
    nu = np.empty(nr, dtype=np.int64)
    nv = np.empty(nr, dtype=np.int64)
    split_counts(e, np.ascontiguousarray(E[:, 2]), np.ascontiguousarray(E[:, 3]), target,
                 max_cells, nu, nv)
    cu = np.zeros(nsu, dtype=np.int64)
    cv = np.zeros(nsv, dtype=np.int64)
    for i in range(nsu):
        for j in range(nsv):
            cu[i] = max(cu[i], nu[i * nsv + j])
            cv[j] = max(cv[j], nv[i * nsv + j])
    su = 0
    sv = 0
    for c in cu:
        su += c
    for c in cv:
        sv += c
    if su * sv > max_cells:
        return GRID_REFUSED, empty1, empty1, empty2, E, cu, cv
    if su * sv > max_small:
        return GRID_BIG, empty1, empty1, empty2, E, cu, cv
    if su == nsu and sv == nsv:  # every count 1: the root spans themselves
        return GRID_OK, ub, vb, roots, E, cu, cv
    u = _lines(ub, cu)
    v = _lines(vb, cv)
    return GRID_OK, u, v, _tensor(u, v), E, cu, cv


@jit
def grid_plan(Pw, p, q, U, V, ub, vb, m, target, max_cells, fold):
    """The grid :func:`small_grid` would measure, unmeasured: ``(ok, u, v, cells,
    first)``, each cell's diagonal the one of the smaller estimate; not ``ok`` (empty
    arrays) when it would exceed ``max_cells``."""
    status, u, v, cells, first, _, _, _ = _plan(Pw, p, q, U, V, ub, vb, m, target,
                                                max_cells, max_cells, fold)
    return status == GRID_OK, u, v, cells, first


@jit
def small_grid(Pw, p, q, U, V, ub, vb, m, k, tol, target, exact_above, max_cells,
               max_small, u0, u1, v0, v1, pair, fold):
    """The first grid of :func:`geomkit.mesh.quadtree.uniform_grid` (``u0, u1, v0, v1``:
    its box, or the domain, where the measurement's feet stay; ``fold``: the edge lines
    whose sags the estimates take, NaN for none):
    ``(status, u, v, cells, dev, diag, E, cu, cv, worst)``: status :data:`GRID_OK` with
    the grid lines, cells (N, 4), each cell's measured deviation and better diagonal;
    :data:`GRID_FAILED` with the same and the largest deviation ``worst`` (NaN if one
    is); :data:`GRID_BIG` or :data:`GRID_REFUSED` with empty ones.  Always (but for a
    refusal before them) the root spans' estimates ``E`` and the children counts per
    span row ``cu`` and column ``cv``, for the Python route to go on from."""
    status, u, v, cells, first, E, cu, cv = _plan(Pw, p, q, U, V, ub, vb, m, target,
                                                  max_cells, max_small, fold)
    if status != GRID_OK:
        return status, u, v, cells, np.empty(0), first, E, cu, cv, np.nan
    n = cells.shape[0]
    M = np.empty((n, 2))
    _cell_deviation_range(0, n, Pw, p, q, U, V, cells, first, k, u0, u1, v0, v1,
                          exact_above, tol, pair, M)
    dev = np.empty(n)
    diag = np.empty(n, dtype=np.int64)
    worst = -np.inf
    for i in range(n):
        a = M[i, 0]
        b = M[i, 1]
        d = 0 if (np.isnan(a) or (not np.isnan(b) and not b < a)) else 1  # np.argmin
        diag[i] = d
        dev[i] = M[i, d]
        if np.isnan(dev[i]) or np.isnan(worst):  # np.max: NaN if one is
            worst = np.nan
        else:
            worst = max(worst, dev[i])
    status = GRID_OK if worst <= tol else GRID_FAILED
    return status, u, v, cells, dev, diag, E, cu, cv, worst


@jit
def grid_vertices(Pw, p, q, U, V, u, v, diag, u0, u1, v0, v1, eps, r):
    """:func:`geomkit.mesh.weld.weld_grid`'s arrays in one call: ``(ok, P, UV, inv, bnd,
    near)``: the grid's vertices ``S(UV)`` (row-major, ``UV[i * len(v) + j] = (u[i],
    v[j])``), the corners ``inv`` (6 per cell by its diagonal), the vertices on the
    domain's edges ``bnd`` (within ``eps``) and whether two of them may lie within
    ``r`` in 3-D (their projections on an oblique unit direction, sorted, have a gap
    below ``2 r`` plus rounding: :func:`geomkit.mesh.weld.boundary_pairs` decides); ``ok``
    False (and empty arrays) when the lines are not strictly increasing."""
    nu1 = u.shape[0]
    nv1 = v.shape[0]
    ok = True
    for i in range(nu1 - 1):
        if not u[i + 1] > u[i]:
            ok = False
    for j in range(nv1 - 1):
        if not v[j + 1] > v[j]:
            ok = False
    if not ok:
        return (False, np.empty((0, 3)), np.empty((0, 2)), np.empty(0, dtype=np.int64),
                np.empty(0, dtype=np.int64), False)
    n = nu1 * nv1
    UV = np.empty((n, 2))
    for i in range(nu1):
        for j in range(nv1):
            UV[i * nv1 + j, 0] = u[i]
            UV[i * nv1 + j, 1] = v[j]
    P = np.empty((n, 3))
    surface_points_range(0, n, Pw, p, q, U, V, UV, P)
    nb = 0
    flag = np.empty(n, dtype=np.bool_)
    for i in range(nu1):
        on_u = u[i] <= u0 + eps or u[i] >= u1 - eps
        for j in range(nv1):
            f = on_u or v[j] <= v0 + eps or v[j] >= v1 - eps
            flag[i * nv1 + j] = f
            if f:
                nb += 1
    bnd = np.empty(nb, dtype=np.int64)
    nb = 0
    for i in range(n):
        if flag[i]:
            bnd[nb] = i
            nb += 1
    inv = np.empty(6 * (nu1 - 1) * (nv1 - 1), dtype=np.int64)
    r6 = 0
    for i in range(nu1 - 1):
        for j in range(nv1 - 1):
            b = i * nv1 + j
            if diag[i * (nv1 - 1) + j] == 0:  # (u0,v0)-(u1,v1): ABC, ACD
                inv[r6] = b
                inv[r6 + 1] = b + nv1
                inv[r6 + 2] = b + nv1 + 1
                inv[r6 + 3] = b
                inv[r6 + 4] = b + nv1 + 1
                inv[r6 + 5] = b + 1
            else:  # (u1,v0)-(u0,v1): ABD, BCD
                inv[r6] = b
                inv[r6 + 1] = b + nv1
                inv[r6 + 2] = b + 1
                inv[r6 + 3] = b + nv1
                inv[r6 + 4] = b + nv1 + 1
                inv[r6 + 5] = b + 1
            r6 += 6
    near = False
    if nb >= 2:
        proj = np.empty(nb)
        big = 0.0
        for a in range(nb):
            x = P[bnd[a], 0]
            y = P[bnd[a], 1]
            z = P[bnd[a], 2]
            proj[a] = x * 0.35 + y * 0.48 + z * 0.8  # weld.WELD_DIRECTION
            big = max(big, abs(x), abs(y), abs(z))
        proj.sort()
        lim = 2.0 * r + 1e-14 * big
        for a in range(nb - 1):
            if not proj[a + 1] - proj[a] > lim:
                near = True
                break
    return True, P, UV, inv, bnd, near


@jit
def edge_gaps(Pw, p, q, U, V, u0, u1, v0, v1, t):
    """:func:`geomkit.mesh.cells.closed_directions`' measure in one call: the largest
    coordinate difference between ``S(u0, v)`` and ``S(u1, v)``, and between
    ``S(u, v0)`` and ``S(u, v1)``, at ``v = v0 + (v1 - v0) t`` (``u`` alike); NaN if
    one is (as numpy's max)."""
    m = t.shape[0]
    uv = np.empty((4 * m, 2))
    for i in range(m):
        v = v0 + (v1 - v0) * t[i]
        u = u0 + (u1 - u0) * t[i]
        uv[i, 0] = u0
        uv[i, 1] = v
        uv[m + i, 0] = u1
        uv[m + i, 1] = v
        uv[2 * m + i, 0] = u
        uv[2 * m + i, 1] = v0
        uv[3 * m + i, 0] = u
        uv[3 * m + i, 1] = v1
    P = np.empty((4 * m, 3))
    surface_points_range(0, 4 * m, Pw, p, q, U, V, uv, P)
    cu = 0.0
    cv = 0.0
    for i in range(m):
        for c in range(3):
            a = abs(P[i, c] - P[m + i, c])
            b = abs(P[2 * m + i, c] - P[3 * m + i, c])
            cu = np.nan if (np.isnan(a) or np.isnan(cu)) else max(cu, a)
            cv = np.nan if (np.isnan(b) or np.isnan(cv)) else max(cv, b)
    return cu, cv


@jit
def _breakpoints(K, p):
    """The distinct knots of the domain ``K[p : len(K) - p]``."""
    k = K[p:K.shape[0] - p]
    out = np.empty(k.shape[0])
    n = 0
    for i in range(k.shape[0]):
        if i == 0 or k[i] != k[i - 1]:
            out[n] = k[i]
            n += 1
    return out[:n]


# corners of a cell's two triangles as columns of ``u0, u1, v0, v1``: A=(u0,v0)
# B=(u1,v0) C=(u1,v1) D=(u0,v1); diagonal 0 (AC): ABC, ACD; diagonal 1 (BD): ABD, BCD
_CORNER_U = np.array([[0, 1, 1, 0, 1, 0], [0, 1, 0, 1, 1, 0]], dtype=np.int64)
_CORNER_V = np.array([2, 2, 3, 2, 3, 3], dtype=np.int64)


@jit
def grid_triangles(cells, dev, diag):
    """``(tri (2N, 3, 2), dev (2N,))``: each cell's two triangles by its diagonal
    ``diag`` (0: (u0,v0)-(u1,v1), 1: (u1,v0)-(u0,v1)), counter-clockwise in UV, and
    their cell's deviation."""
    n = cells.shape[0]
    tri = np.empty((2 * n, 3, 2))
    dev2 = np.empty(2 * n)
    for c in range(n):
        d = diag[c]
        for h in range(6):
            tri[2 * c + h // 3, h % 3, 0] = cells[c, _CORNER_U[d, h]]
            tri[2 * c + h // 3, h % 3, 1] = cells[c, _CORNER_V[h]]
        dev2[2 * c] = dev[c]
        dev2[2 * c + 1] = dev[c]
    return tri, dev2


@jit
def whole_grid(Pw, p, q, U, V, k, tol, target, exact_above, max_cells, max_small, pair,
               weld_r, closed_eps, t):
    """A face that is its whole surface on one uniform grid, in one call: the first
    grid of :func:`small_grid` over the domain's breakpoints (``m = max(5, 2 max(p, q)
    + 1)`` estimate samples), its triangles (:func:`grid_triangles`),
    their vertices (:func:`grid_vertices`) and whether the surface is closed in u and
    v (:func:`edge_gaps` at ``t`` within ``closed_eps``; the estimates take the sags of
    the domain's edges but for a closed direction's, which is a seam, not a boundary).
    Returns ``(status, tri (2N, 3, 2), dev (2N,), cells (N, 4), welded, P, UV, inv,
    bnd, near, closed_u, closed_v, first)``: for a status other than :data:`GRID_OK`
    empty arrays and ``first``, :func:`small_grid`'s ``(status, E, cu, cv, worst)``
    for the Python route to go on from; ``welded`` False when the grid lines are not
    strictly increasing (the general weld then)."""
    ub = _breakpoints(U, p)
    vb = _breakpoints(V, q)
    m = max(5, 2 * max(p, q) + 1)
    u0 = U[p]
    u1 = U[U.shape[0] - p - 1]
    v0 = V[q]
    v1 = V[V.shape[0] - q - 1]
    gu, gv = edge_gaps(Pw, p, q, U, V, u0, u1, v0, v1, t)
    closed_u = gu <= closed_eps
    closed_v = gv <= closed_eps
    fold = np.array([np.nan if closed_u else u0, np.nan if closed_u else u1,
                     np.nan if closed_v else v0, np.nan if closed_v else v1])
    status, u, v, cells, dev, diag, E, cu, cv, worst = small_grid(
        Pw, p, q, U, V, ub, vb, m, k, tol, target, exact_above, max_cells, max_small, u0,
        u1, v0, v1, pair, fold)
    first = (status, E, cu, cv, worst)
    if status != GRID_OK:
        return (status, np.empty((0, 3, 2)), np.empty(0), cells, False, np.empty((0, 3)),
                np.empty((0, 2)), np.empty(0, dtype=np.int64), np.empty(0, dtype=np.int64),
                False, closed_u, closed_v, first)
    tri, dev2 = grid_triangles(cells, dev, diag)
    eps = 1e-12 * max(u1 - u0, v1 - v0)
    welded, P, UV, inv, bnd, near = grid_vertices(Pw, p, q, U, V, u, v, diag, u0, u1, v0,
                                                  v1, eps, weld_r)
    return (status, tri, dev2, cells, welded, P, UV, inv, bnd, near, closed_u, closed_v,
            first)
