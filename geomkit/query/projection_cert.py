"""True bounds of a NURBS surface's first and second derivatives over small parameter
boxes, for the projection's second-order certificate
(:func:`geomkit._kernels.project_cert.cert_settle`).

Each knot span of a surface is split into ``mu x mv`` equal sub-spans (its rational
Bézier patch, :func:`geomkit.nurbs.bezier.bezier_patches`, restricted to each sub-box by
de Casteljau subdivision), and for every sub-span five numbers bound, over all of it,
``|S_u|``, ``|S_v|``, ``|S_uu|``, ``|S_uv|`` and ``|S_vv|`` (Euclidean norms).  They
are proven, not sampled:

* the homogeneous derivatives ``A_u, w_u, A_uu, ...`` of ``A = w (S - c)`` (control
  points translated by the sub-patch's centre ``c``) are Bézier patches whose control
  points are the scaled differences of the sub-patch's net; Bernstein polynomials are
  non-negative and sum to 1, so their norms are at most the largest difference
  point's (convex hull property);
* ``|S - c| <= r`` (the largest distance of a control point from ``c``: a rational
  patch with positive weights lies in the convex hull of its control points) and
  ``w >= wmin`` (the smallest weight of the sub-patch);
* the quotient rule: ``S_u = (A_u - w_u (S - c)) / w``, ``S_uu = (A_uu - 2 w_u S_u -
  w_uu (S - c)) / w``, ``S_uv = (A_uv - w_u S_v - w_v S_u - w_uv (S - c)) / w``, each
  term bounded by the above (for a non-rational surface the weight terms vanish).

The homogeneous bounds carry an absolute allowance for the rounding of the
subdivision (``CERT_ROUNDING`` times the net's magnitude over the sub-span's width, per
order) and every bound a relative ``ROUND``.  Finer sub-spans give tighter bounds
(the control net converges to the surface quadratically); the count per surface
follows its number of candidate triangles (:func:`pack_span_bounds`).
"""

from __future__ import annotations

import math

import numpy as np

from geomkit.tolerances import CERT_ROUNDING
from geomkit.nurbs.bezier import bezier_patches

ROUND = 1.0 + 1e-12
"""Relative inflation of every bound."""
MAX_SUBSPANS = 64
"""Largest number of sub-spans per direction of one surface."""


def _split(P, t):
    """de Casteljau along axis 0 at ``t``: (left, right) nets."""
    L, R, Q = [P[0]], [P[-1]], P
    for _ in range(P.shape[0] - 1):
        Q = (1.0 - t) * Q[:-1] + t * Q[1:]
        L.append(Q[0])
        R.append(Q[-1])
    return np.stack(L), np.stack(R[::-1])


def _sub_matrices(p, m):
    """(m, p+1, p+1): the Bézier net of the k-th of m equal sub-intervals is
    ``M[k] @ P``."""
    out = np.empty((m, p + 1, p + 1))
    eye = np.eye(p + 1)
    for k in range(m):
        s0, s1 = k / m, (k + 1) / m
        left, _ = _split(eye, s1)
        out[k] = left if s0 == 0.0 else _split(left, s0 / s1)[1]
    return out


def _bound(Q, c, h, order, mag):
    """Largest ``|Q_xyz - c Q_w|`` and ``|Q_w|`` over each sub-patch's difference net
    ``Q`` (n, a, b, 4) (zeros for an empty net), plus the rounding allowance."""
    n = c.shape[0]
    if Q.shape[1] == 0 or Q.shape[2] == 0:
        return np.zeros(n), np.zeros(n)
    xyz = Q[..., :3] - c[:, None, None, :] * Q[..., 3:4]
    slack = CERT_ROUNDING * mag / h ** order
    return (np.sqrt((xyz ** 2).sum(axis=-1)).max(axis=(1, 2)) + slack,
            np.abs(Q[..., 3]).max(axis=(1, 2)) + slack)


def sub_span_bounds(surface, mu, mv):
    """Bounds of ``surface``'s derivatives on its knot spans split ``mu x mv`` times.

    Returns ``(bu, bv, B)``: the sub-span borders in u and v and ``B`` (len(bu) - 1,
    len(bv) - 1, 5) = (Mu, Mv, Muu, Muv, Mvv) per sub-span.  A degree below 1 gives
    ``inf`` (no certificate)."""
    p, q = surface.degree_u, surface.degree_v
    bz = bezier_patches(surface)
    ub, vb = bz.u_breaks, bz.v_breaks
    bu = np.concatenate([ub[i] + (ub[i + 1] - ub[i]) * np.arange(mu) / mu
                         for i in range(ub.size - 1)] + [ub[-1:]])
    bv = np.concatenate([vb[j] + (vb[j + 1] - vb[j]) * np.arange(mv) / mv
                         for j in range(vb.size - 1)] + [vb[-1:]])
    nsu, nsv = ub.size - 1, vb.size - 1
    if p < 1 or q < 1:
        return bu, bv, np.full((nsu * mu, nsv * mv, 5), np.inf)
    Mu_, Mv_ = _sub_matrices(p, mu), _sub_matrices(q, mv)
    # (nsu, mu, nsv, mv, p+1, q+1, 4) sub-patch nets
    H = np.einsum("kia,xyabc,ljb->xkylijc", Mu_, bz.homogeneous, Mv_, optimize=True)
    n = nsu * mu * nsv * mv
    H = H.reshape(n, p + 1, q + 1, 4)
    hu = np.broadcast_to(np.diff(ub)[:, None, None, None] / mu,
                         (nsu, mu, nsv, mv)).reshape(n)
    hv = np.broadcast_to(np.diff(vb)[None, None, :, None] / mv,
                         (nsu, mu, nsv, mv)).reshape(n)
    w = H[..., 3]
    X = H[..., :3] / w[..., None]
    c = X.mean(axis=(1, 2))
    r = np.sqrt(((X - c[:, None, None, :]) ** 2).sum(axis=-1)).max(axis=(1, 2))
    wmin = w.min(axis=(1, 2))
    mag = np.abs(H).max(axis=(1, 2, 3))
    hu3, hv3 = hu[:, None, None, None], hv[:, None, None, None]
    Du = p * np.diff(H, axis=1) / hu3
    Dv = q * np.diff(H, axis=2) / hv3
    Au, wu = _bound(Du, c, hu, 1, mag * 2 * p)
    Av, wv = _bound(Dv, c, hv, 1, mag * 2 * q)
    Auu, wuu = _bound((p - 1) * np.diff(Du, axis=1) / hu3, c, hu, 2, mag * 4 * p * p)
    Auv, wuv = _bound(q * np.diff(Du, axis=2) / hv3, c, np.sqrt(hu * hv), 2,
                      mag * 4 * p * q)
    Avv, wvv = _bound((q - 1) * np.diff(Dv, axis=2) / hv3, c, hv, 2, mag * 4 * q * q)
    B = np.empty((n, 5))
    B[:, 0] = Mu = (Au + wu * r) / wmin * ROUND
    B[:, 1] = Mv = (Av + wv * r) / wmin * ROUND
    B[:, 2] = (Auu + 2.0 * wu * Mu + wuu * r) / wmin * ROUND
    B[:, 3] = (Auv + wu * Mv + wv * Mu + wuv * r) / wmin * ROUND
    B[:, 4] = (Avv + 2.0 * wv * Mv + wvv * r) / wmin * ROUND
    return bu, bv, B.reshape(nsu * mu, nsv * mv, 5)


def pack_span_bounds(surfaces, ntri):
    """Sub-span bounds of all surfaces for the kernel: ``brk`` (the sub-span borders,
    concatenated), ``bnd`` (total sub-spans, 5) and ``bnd_off[s]`` = (first row of
    surface s in ``bnd``, offset and count of its u borders in ``brk``, the same for
    v); rows ``iu * (count_v - 1) + iv`` follow.  Surface s with ``ntri[s]``
    candidate triangles gets about ``2 sqrt(ntri[s] / 2)`` sub-spans per direction
    (at least one per knot span, at most :data:`MAX_SUBSPANS`)."""
    brk, bnd = [], []
    off = np.zeros((len(surfaces), 5), dtype=np.int64)
    ob = oc = 0
    for i, s in enumerate(surfaces):
        nsu = np.unique(s.knots_u[s.degree_u:-s.degree_u]).size - 1
        nsv = np.unique(s.knots_v[s.degree_v:-s.degree_v]).size - 1
        target = min(MAX_SUBSPANS, max(4, math.ceil(2.0 * math.sqrt(ntri[i] / 2.0))))
        mu = max(1, min(MAX_SUBSPANS // max(nsu, 1), math.ceil(target / max(nsu, 1))))
        mv = max(1, min(MAX_SUBSPANS // max(nsv, 1), math.ceil(target / max(nsv, 1))))
        bu, bv, B = sub_span_bounds(s, mu, mv)
        off[i] = (ob, oc, bu.size, oc + bu.size, bv.size)
        brk += [bu, bv]
        oc += bu.size + bv.size
        bnd.append(B.reshape(-1, 5))
        ob += bnd[-1].shape[0]
    return (np.ascontiguousarray(np.concatenate(brk)),
            np.ascontiguousarray(np.concatenate(bnd)), off)
