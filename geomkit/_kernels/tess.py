"""Tessellation kernels: cell error estimates and measured triangle deviation.

The deviation of a flat triangle from the surface is measured *parametrically*: for
a UV triangle with corners ``a, b, c`` and 3-D vertices ``S(a), S(b), S(c)``, the
sample at barycentric ``(l0, l1, l2)`` compares ``S(l0 a + l1 b + l2 c)`` with
``l0 S(a) + l1 S(b) + l2 S(c)``.  The parametric gap bounds both one-sided
distances (surface point to triangle, triangle point to surface) at that sample.
"""

from __future__ import annotations

import numpy as np

from ._numba import jit, pjit, prange
from .surface import surface_point


@jit
def _dist3(a0, a1, a2, b0, b1, b2):
    d0 = a0 - b0
    d1 = a1 - b1
    d2 = a2 - b2
    return np.sqrt(d0 * d0 + d1 * d1 + d2 * d2)


@pjit
def cell_errors(Pw, p, q, U, V, cells, m, out):
    """Error estimates for axis-aligned UV cells (parallel over cells).

    Parameters
    ----------
    cells : (N, 4) float, ``u0, u1, v0, v1`` per cell.
    m : samples per side (>= 3).
    out : (N, 5) float, filled with
        0: max parametric deviation of the two triangles split along (u0,v0)-(u1,v1);
        1: the same for the other diagonal (u1,v0)-(u0,v1);
        2: max chord deviation of u-lines (v fixed) across the cell (need to split u);
        3: max chord deviation of v-lines (u fixed) across the cell (need to split v);
        4: largest 3-D edge length of the cell's corners (for ``max_edge``).
    """
    N = cells.shape[0]
    mm = max(p, q) + 1
    for c in prange(N):
        Nu = np.empty(p + 1)
        Nv = np.empty(q + 1)
        left = np.empty(mm)
        right = np.empty(mm)
        tmp = np.empty(4)
        G = np.empty((m, m, 3))
        u0 = cells[c, 0]
        u1 = cells[c, 1]
        v0 = cells[c, 2]
        v1 = cells[c, 3]
        for i in range(m):
            u = u0 + (u1 - u0) * i / (m - 1)
            for j in range(m):
                v = v0 + (v1 - v0) * j / (m - 1)
                surface_point(Pw, p, q, U, V, u, v, Nu, Nv, left, right, tmp, G[i, j])
        e_d0 = 0.0
        e_d1 = 0.0
        e_u = 0.0
        e_v = 0.0
        last = m - 1
        for i in range(m):
            s = i / last
            for j in range(m):
                t = j / last
                # diagonal (0,0)-(1,1): triangles below (s >= t) and above
                if s >= t:
                    l0 = 1.0 - s
                    l1 = s - t
                    l2 = t
                    # corners: A=(0,0), B=(1,0), C=(1,1)
                    for k in range(3):
                        tmp[k] = (l0 * G[0, 0, k] + l1 * G[last, 0, k] + l2 * G[last, last, k])
                else:
                    l0 = 1.0 - t
                    l1 = t - s
                    l2 = s
                    # corners: A=(0,0), D=(0,1), C=(1,1)
                    for k in range(3):
                        tmp[k] = (l0 * G[0, 0, k] + l1 * G[0, last, k] + l2 * G[last, last, k])
                e_d0 = max(e_d0, _dist3(tmp[0], tmp[1], tmp[2], G[i, j, 0], G[i, j, 1], G[i, j, 2]))
                # diagonal (1,0)-(0,1)
                if s + t <= 1.0:
                    # corners B=(1,0), D=(0,1), A=(0,0): point = A + s(B-A) + t(D-A)
                    for k in range(3):
                        tmp[k] = (G[0, 0, k] + s * (G[last, 0, k] - G[0, 0, k])
                                  + t * (G[0, last, k] - G[0, 0, k]))
                else:
                    # corners C=(1,1), B=(1,0), D=(0,1): point = C + (1-s)(D-C) + (1-t)(B-C)
                    for k in range(3):
                        tmp[k] = (G[last, last, k] + (1.0 - s) * (G[0, last, k] - G[last, last, k])
                                  + (1.0 - t) * (G[last, 0, k] - G[last, last, k]))
                e_d1 = max(e_d1, _dist3(tmp[0], tmp[1], tmp[2], G[i, j, 0], G[i, j, 1], G[i, j, 2]))
                # u-line chord (row j fixed) and v-line chord (column i fixed)
                for k in range(3):
                    tmp[k] = (1.0 - s) * G[0, j, k] + s * G[last, j, k]
                e_u = max(e_u, _dist3(tmp[0], tmp[1], tmp[2], G[i, j, 0], G[i, j, 1], G[i, j, 2]))
                for k in range(3):
                    tmp[k] = (1.0 - t) * G[i, 0, k] + t * G[i, last, k]
                e_v = max(e_v, _dist3(tmp[0], tmp[1], tmp[2], G[i, j, 0], G[i, j, 1], G[i, j, 2]))
        edge = 0.0
        edge = max(edge, _dist3(G[0, 0, 0], G[0, 0, 1], G[0, 0, 2], G[last, 0, 0], G[last, 0, 1], G[last, 0, 2]))
        edge = max(edge, _dist3(G[0, last, 0], G[0, last, 1], G[0, last, 2], G[last, last, 0], G[last, last, 1], G[last, last, 2]))
        edge = max(edge, _dist3(G[0, 0, 0], G[0, 0, 1], G[0, 0, 2], G[0, last, 0], G[0, last, 1], G[0, last, 2]))
        edge = max(edge, _dist3(G[last, 0, 0], G[last, 0, 1], G[last, 0, 2], G[last, last, 0], G[last, last, 1], G[last, last, 2]))
        out[c, 0] = e_d0
        out[c, 1] = e_d1
        out[c, 2] = e_u
        out[c, 3] = e_v
        out[c, 4] = edge


@pjit
def triangle_deviation(Pw, p, q, U, V, tri_uv, tri_xyz, k, out):
    """Measured deviation of flat triangles from the surface (parallel over triangles).

    Parameters
    ----------
    tri_uv : (M, 3, 2) float, UV corners of each triangle.
    tri_xyz : (M, 3, 3) float, 3-D corners (normally ``S`` at the UV corners).
    k : int, samples per edge: barycentric points ``(i/k, j/k, 1 - i/k - j/k)``,
        ``(k+1)(k+2)/2`` per triangle (edges included).
    out : (M,) float, max over samples of ``|S(uv) - flat triangle point|``.
    """
    M = tri_uv.shape[0]
    mm = max(p, q) + 1
    for t in prange(M):
        Nu = np.empty(p + 1)
        Nv = np.empty(q + 1)
        left = np.empty(mm)
        right = np.empty(mm)
        tmp = np.empty(4)
        P = np.empty(3)
        worst = 0.0
        for i in range(k + 1):
            for j in range(k + 1 - i):
                l1 = i / k
                l2 = j / k
                l0 = 1.0 - l1 - l2
                if (i == 0 and j == 0) or i == k or j == k:
                    continue  # the corners are exact
                u = l0 * tri_uv[t, 0, 0] + l1 * tri_uv[t, 1, 0] + l2 * tri_uv[t, 2, 0]
                v = l0 * tri_uv[t, 0, 1] + l1 * tri_uv[t, 1, 1] + l2 * tri_uv[t, 2, 1]
                surface_point(Pw, p, q, U, V, u, v, Nu, Nv, left, right, tmp, P)
                x = l0 * tri_xyz[t, 0, 0] + l1 * tri_xyz[t, 1, 0] + l2 * tri_xyz[t, 2, 0]
                y = l0 * tri_xyz[t, 0, 1] + l1 * tri_xyz[t, 1, 1] + l2 * tri_xyz[t, 2, 1]
                z = l0 * tri_xyz[t, 0, 2] + l1 * tri_xyz[t, 1, 2] + l2 * tri_xyz[t, 2, 2]
                worst = max(worst, _dist3(x, y, z, P[0], P[1], P[2]))
        out[t] = worst


@pjit
def chord_deviation(Pw, p, q, U, V, uv_a, uv_b, xyz_a, xyz_b, mid_uv, out):
    """Deviation of 3-D chords from the surface curve through given UV samples.

    For each chord i, ``mid_uv[i, s]`` are UV points of the exact curve between its
    ends (e.g. a trim curve at interior parameters); ``out[i]`` is the largest
    distance from ``S(mid_uv[i, s])`` to the 3-D segment ``xyz_a[i]``–``xyz_b[i]``.
    """
    n = mid_uv.shape[0]
    ns = mid_uv.shape[1]
    mm = max(p, q) + 1
    for i in prange(n):
        Nu = np.empty(p + 1)
        Nv = np.empty(q + 1)
        left = np.empty(mm)
        right = np.empty(mm)
        tmp = np.empty(4)
        P = np.empty(3)
        d0 = xyz_b[i, 0] - xyz_a[i, 0]
        d1 = xyz_b[i, 1] - xyz_a[i, 1]
        d2 = xyz_b[i, 2] - xyz_a[i, 2]
        ll = d0 * d0 + d1 * d1 + d2 * d2
        worst = 0.0
        for s in range(ns):
            surface_point(Pw, p, q, U, V, mid_uv[i, s, 0], mid_uv[i, s, 1], Nu, Nv, left, right,
                          tmp, P)
            e0 = P[0] - xyz_a[i, 0]
            e1 = P[1] - xyz_a[i, 1]
            e2 = P[2] - xyz_a[i, 2]
            t = 0.0
            if ll > 0.0:
                t = (e0 * d0 + e1 * d1 + e2 * d2) / ll
                t = min(1.0, max(0.0, t))
            worst = max(worst, _dist3(e0, e1, e2, t * d0, t * d1, t * d2))
        out[i] = worst
