"""Surface–surface minimum distance kernels: branch and bound over rational Bézier
sub-patch pairs with certified bounds, and a 4-unknown Newton on the exact surfaces.

Data layout (built by :mod:`geomkit.distance`):

* surfaces packed as in :func:`geomkit.projection._pack` (``Pw_all``, ``U_all``,
  ``V_all``, ``meta``, ``dom``), one index space for the surfaces of both scenes;
* trims: ``seg_all`` (S, pmax+1, 3) homogeneous Bézier trim segments of every
  surface, ``seg_deg``, ``seg_loop`` (loop index within its surface), ``seg_box``
  (P, 4) UV control-point boxes of sub-arcs of the segments, and per surface
  ``trim_meta[s] = (first segment, segment count, loop count, first box, box count)`` (count 0: untrimmed);
* sub-patch nodes: control nets in a flat pool ``ctrl`` (row-major (p+1, q+1, 4)
  homogeneous), integer fields ``ni[k] = (offset, p, q, surface, child0, child1,
  state, rep_ok, side, split_dir)`` and float fields ``nf[k] = (u0, u1, v0, v1,
  xmin, ymin, zmin, xmax, ymax, zmax, rep x, y, z, rep u, rep v, size)``.

Certificate.  With positive weights a rational Bézier patch lies in the convex hull of
its Cartesian control points, so for any unit direction d

    min_{x in A, y in B} |x - y|  >=  min_j (Q_j . d) - max_i (P_i . d),

and also >= the gap between the control points' axis boxes.  The lower bound of a
pair is the largest of these (d along the box centres and along the two
representative surface points).  Upper bounds are distances between real surface
points (patch centres by de Casteljau, then Newton) that lie inside their trimmed
faces.  A pair whose lower bound is >= upper - tol cannot improve the answer by more
than tol and is discarded; the search stops when the smallest open lower bound is
>= upper - tol, so [lower, upper] contains the exact distance.
"""

from __future__ import annotations

import math

import numpy as np

from ._numba import jit, jit_inline
from .project import _surface, foot_newton
from .trim_feet import _trim_point, segment_newton
from .voxel import _heap_pop, _heap_push
from .surface import D2, _binomial_table, derivs_scratch, surface_derivs
from .trim import INSIDE, MAX_DEPTH, OUTSIDE, classify_point

NI = 10
NF = 16
# ni columns
I_OFF, I_P, I_Q, I_SURF, I_C0, I_C1, I_STATE, I_REPOK, I_SIDE, I_DIR = range(10)
# nf columns
F_U0, F_U1, F_V0, F_V1 = 0, 1, 2, 3
F_BOX = 4
F_REP = 10
F_REPUV = 13
F_SIZE = 15
# node trim states
ST_INSIDE = 1
ST_MIXED = 2
ST_OUTSIDE = 0

NEWTON_MAX_ITER = 60

# stop codes
STOP_CERTIFIED = 0
STOP_MAX_PAIRS = 1
STOP_EXHAUSTED = 2


# --------------------------------------------------------------------------- growth
@jit_inline
def _grow2(a, need):
    n = a.shape[0]
    if need <= n:
        return a
    m = max(need, 2 * n)
    b = np.empty((m, a.shape[1]), dtype=a.dtype)
    for i in range(n):
        for j in range(a.shape[1]):
            b[i, j] = a[i, j]
    return b


@jit_inline
def _grow1(a, need):
    n = a.shape[0]
    if need <= n:
        return a
    m = max(need, 2 * n)
    b = np.empty(m, dtype=a.dtype)
    for i in range(n):
        b[i] = a[i]
    return b


@jit_inline
def _max_loops(trim_meta):
    """``max(1, trim_meta[:, 2].max())`` without numpy's max (slow to compile)."""
    m = 1
    for s in range(trim_meta.shape[0]):
        m = max(m, trim_meta[s, 2])
    return m


# --------------------------------------------------------------------------- patches
@jit
def _patch_eval(ctrl, off, p, q, s, t, tmp, out):
    """Point of the rational Bézier patch at local (s, t) in [0, 1]^2 (de Casteljau)."""
    # rows: for each i, de Casteljau in v
    for i in range(p + 1):
        base = off + i * (q + 1) * 4
        for j in range(q + 1):
            for c in range(4):
                tmp[j, c] = ctrl[base + j * 4 + c]
        for r in range(1, q + 1):
            for j in range(q + 1 - r):
                for c in range(4):
                    tmp[j, c] = (1.0 - t) * tmp[j, c] + t * tmp[j + 1, c]
        for c in range(4):
            tmp[q + 1 + i, c] = tmp[0, c]
    # column of row results at tmp[q+1 : q+2+p]
    b = q + 1
    for r in range(1, p + 1):
        for i in range(p + 1 - r):
            for c in range(4):
                tmp[b + i, c] = (1.0 - s) * tmp[b + i, c] + s * tmp[b + i + 1, c]
    w = tmp[b, 3]
    out[0] = tmp[b, 0] / w
    out[1] = tmp[b, 1] / w
    out[2] = tmp[b, 2] / w


@jit
def _node_box(ctrl, off, p, q, nf, k):
    lo0 = lo1 = lo2 = np.inf
    hi0 = hi1 = hi2 = -np.inf
    for i in range((p + 1) * (q + 1)):
        b = off + 4 * i
        w = ctrl[b + 3]
        x = ctrl[b] / w
        y = ctrl[b + 1] / w
        z = ctrl[b + 2] / w
        lo0 = min(lo0, x)
        lo1 = min(lo1, y)
        lo2 = min(lo2, z)
        hi0 = max(hi0, x)
        hi1 = max(hi1, y)
        hi2 = max(hi2, z)
    nf[k, F_BOX] = lo0
    nf[k, F_BOX + 1] = lo1
    nf[k, F_BOX + 2] = lo2
    nf[k, F_BOX + 3] = hi0
    nf[k, F_BOX + 4] = hi1
    nf[k, F_BOX + 5] = hi2
    nf[k, F_SIZE] = math.sqrt((hi0 - lo0) ** 2 + (hi1 - lo1) ** 2 + (hi2 - lo2) ** 2)


@jit
def _split_dir(ctrl, off, p, q):
    """0: split in u (the net is longer along u), 1: in v."""
    lu = 0.0
    lv = 0.0
    for i in range(p + 1):
        for j in range(q + 1):
            b = off + (i * (q + 1) + j) * 4
            wa = ctrl[b + 3]
            if i < p:
                b2 = b + (q + 1) * 4
                wb = ctrl[b2 + 3]
                d = 0.0
                for c in range(3):
                    e = ctrl[b2 + c] / wb - ctrl[b + c] / wa
                    d += e * e
                lu = max(lu, d)
            if j < q:
                b2 = b + 4
                wb = ctrl[b2 + 3]
                d = 0.0
                for c in range(3):
                    e = ctrl[b2 + c] / wb - ctrl[b + c] / wa
                    d += e * e
                lv = max(lv, d)
    lu *= p * p
    lv *= q * q
    return 0 if lu >= lv else 1


@jit
def _split_into(ctrl, off, p, q, d, offL, offR):
    """de Casteljau at 1/2 along u (d = 0) or v (d = 1) of the net at ``off``; the two
    halves are written at ``offL`` and ``offR``."""
    if d == 0:
        n = p
        ncurves = q + 1
        stride = (q + 1) * 4  # step between curve points
        cstep = 4             # step between curves
    else:
        n = q
        ncurves = p + 1
        stride = 4
        cstep = (q + 1) * 4
    for cv in range(ncurves):
        base = cv * cstep
        for c in range(4):
            # copy curve into right, then reduce
            for i in range(n + 1):
                ctrl[offR + base + i * stride + c] = ctrl[off + base + i * stride + c]
            ctrl[offL + base + c] = ctrl[off + base + c]
            for r in range(1, n + 1):
                for i in range(n - r + 1):
                    a = offR + base + i * stride + c
                    ctrl[a] = 0.5 * (ctrl[a] + ctrl[a + stride])
                ctrl[offL + base + r * stride + c] = ctrl[offR + base + c]


# --------------------------------------------------------------------------- trims
@jit
def _box_trim_state(seg_all, seg_deg, seg_loop, seg_box, trim_meta, s, u0, u1, v0, v1,
                    tol, winding, stack, depths, left, right):
    """INSIDE / OUTSIDE if the UV box is entirely inside / outside the trimmed face,
    MIXED if a trim segment's control box meets it (conservative)."""
    first = trim_meta[s, 0]
    cnt = trim_meta[s, 1]
    if cnt == 0:
        return ST_INSIDE
    for k in range(trim_meta[s, 3], trim_meta[s, 3] + trim_meta[s, 4]):
        if (seg_box[k, 0] <= u1 + tol and seg_box[k, 1] >= u0 - tol
                and seg_box[k, 2] <= v1 + tol and seg_box[k, 3] >= v0 - tol):
            return ST_MIXED
    c = classify_point(seg_all[first:first + cnt], seg_deg[first:first + cnt],
                       seg_loop[first:first + cnt], trim_meta[s, 2], 0.5 * (u0 + u1),
                       0.5 * (v0 + v1), tol, winding, stack, depths, left, right)
    if c == INSIDE:
        return ST_INSIDE
    if c == OUTSIDE:
        return ST_OUTSIDE
    return ST_MIXED


@jit_inline
def _uv_inside(seg_all, seg_deg, seg_loop, trim_meta, s, u, v, tol, winding, stack,
               depths, left, right):
    first = trim_meta[s, 0]
    cnt = trim_meta[s, 1]
    if cnt == 0:
        return True
    c = classify_point(seg_all[first:first + cnt], seg_deg[first:first + cnt],
                       seg_loop[first:first + cnt], trim_meta[s, 2], u, v, tol, winding,
                       stack, depths, left, right)
    return c == INSIDE


# --------------------------------------------------------------------------- bounds
@jit_inline
def _slab(ctrl, offa, na, offb, nb, d0, d1, d2):
    hi = -np.inf
    for i in range(na):
        b = offa + 4 * i
        w = ctrl[b + 3]
        x = (ctrl[b] * d0 + ctrl[b + 1] * d1 + ctrl[b + 2] * d2) / w
        hi = max(hi, x)
    lo = np.inf
    for i in range(nb):
        b = offb + 4 * i
        w = ctrl[b + 3]
        x = (ctrl[b] * d0 + ctrl[b + 1] * d1 + ctrl[b + 2] * d2) / w
        lo = min(lo, x)
    return lo - hi


@jit
def pair_lower_bound(ctrl, ni, nf, a, b):
    """Certified lower bound of the distance between nodes a and b (hull property)."""
    g = 0.0
    for c in range(3):
        e = max(nf[a, F_BOX + c] - nf[b, F_BOX + 3 + c], nf[b, F_BOX + c] - nf[a, F_BOX + 3 + c])
        if e > 0.0:
            g += e * e
    lb = math.sqrt(g)
    na = (ni[a, I_P] + 1) * (ni[a, I_Q] + 1)
    nb = (ni[b, I_P] + 1) * (ni[b, I_Q] + 1)
    for kind in range(2):
        if kind == 0:
            d0 = 0.5 * (nf[b, F_BOX] + nf[b, F_BOX + 3] - nf[a, F_BOX] - nf[a, F_BOX + 3])
            d1 = 0.5 * (nf[b, F_BOX + 1] + nf[b, F_BOX + 4] - nf[a, F_BOX + 1] - nf[a, F_BOX + 4])
            d2 = 0.5 * (nf[b, F_BOX + 2] + nf[b, F_BOX + 5] - nf[a, F_BOX + 2] - nf[a, F_BOX + 5])
        else:
            d0 = nf[b, F_REP] - nf[a, F_REP]
            d1 = nf[b, F_REP + 1] - nf[a, F_REP + 1]
            d2 = nf[b, F_REP + 2] - nf[a, F_REP + 2]
        L = math.sqrt(d0 * d0 + d1 * d1 + d2 * d2)
        if L <= 0.0 or not np.isfinite(L):
            continue
        s = _slab(ctrl, ni[a, I_OFF], na, ni[b, I_OFF], nb, d0 / L, d1 / L, d2 / L)
        if s > lb:
            lb = s
    return lb


# --------------------------------------------------------------------------- Newton
@jit
def _chol_solve(H, g, free, n, x):
    """Solve H x = -g on the free variables by Cholesky; False if not PD."""
    L = np.zeros((4, 4))
    idx = np.empty(4, dtype=np.int64)
    m = 0
    for i in range(n):
        if free[i]:
            idx[m] = i
            m += 1
    for i in range(m):
        for j in range(i + 1):
            s = H[idx[i], idx[j]]
            for k in range(j):
                s -= L[i, k] * L[j, k]
            if i == j:
                if s <= 0.0:
                    return False
                L[i, i] = math.sqrt(s)
            else:
                L[i, j] = s / L[j, j]
    y = np.zeros(4)
    for i in range(m):
        s = -g[idx[i]]
        for k in range(i):
            s -= L[i, k] * y[k]
        y[i] = s / L[i, i]
    for i in range(n):
        x[i] = 0.0
    z = np.zeros(4)
    for i in range(m - 1, -1, -1):
        s = y[i]
        for k in range(i + 1, m):
            s -= L[k, i] * z[k]
        z[i] = s / L[i, i]
        x[idx[i]] = z[i]
    return True


@jit
def _eval2(Pw_all, U_all, V_all, meta, s, u, v, bin_, scr, SKL):
    Pw, p, q, U, V = _surface(Pw_all, U_all, V_all, meta, s)
    surface_derivs(Pw, p, q, U, V, u, v, D2, bin_, scr, SKL)


@jit
def newton4(Pw_all, U_all, V_all, meta, dom, sa, sb, x, step_tol, bin_, scra, scrb,
            SA, SB):
    """Local minimiser of |S_a(u, v) - S_b(s, t)|^2 / 2 over the two domain boxes.

    ``x`` (4,) = (u, v, s, t) is updated in place.  Exact Hessian with Levenberg
    damping when it is not positive definite, active set on the box bounds (the
    edge–surface, edge–edge and corner cases), monotone backtracking.  Returns the
    distance at ``x``.
    """
    lo = np.empty(4)
    hi = np.empty(4)
    lo[0] = dom[sa, 0]
    hi[0] = dom[sa, 1]
    lo[1] = dom[sa, 2]
    hi[1] = dom[sa, 3]
    lo[2] = dom[sb, 0]
    hi[2] = dom[sb, 1]
    lo[3] = dom[sb, 2]
    hi[3] = dom[sb, 3]
    for i in range(4):
        x[i] = min(hi[i], max(lo[i], x[i]))
    _eval2(Pw_all, U_all, V_all, meta, sa, x[0], x[1], bin_, scra, SA)
    _eval2(Pw_all, U_all, V_all, meta, sb, x[2], x[3], bin_, scrb, SB)
    D = np.empty(3)
    J = np.empty((4, 3))
    H = np.empty((4, 4))
    Hd = np.empty((4, 4))
    g = np.empty(4)
    dx = np.empty(4)
    xn = np.empty(4)
    free = np.empty(4, dtype=np.bool_)
    f = 0.0
    for c in range(3):
        D[c] = SA[0, 0, c] - SB[0, 0, c]
        f += D[c] * D[c]
    mu = 0.0
    for it in range(NEWTON_MAX_ITER):
        for c in range(3):
            J[0, c] = SA[1, 0, c]
            J[1, c] = SA[0, 1, c]
            J[2, c] = -SB[1, 0, c]
            J[3, c] = -SB[0, 1, c]
        for i in range(4):
            s = 0.0
            for c in range(3):
                s += J[i, c] * D[c]
            g[i] = s
            for j in range(4):
                s = 0.0
                for c in range(3):
                    s += J[i, c] * J[j, c]
                H[i, j] = s
        for c in range(3):
            H[0, 0] += SA[2, 0, c] * D[c]
            H[0, 1] += SA[1, 1, c] * D[c]
            H[1, 1] += SA[0, 2, c] * D[c]
            H[2, 2] -= SB[2, 0, c] * D[c]
            H[2, 3] -= SB[1, 1, c] * D[c]
            H[3, 3] -= SB[0, 2, c] * D[c]
        H[1, 0] = H[0, 1]
        H[3, 2] = H[2, 3]
        nfree = 0
        scale = 0.0
        for i in range(4):
            fix = (x[i] <= lo[i] and g[i] > 0.0) or (x[i] >= hi[i] and g[i] < 0.0)
            free[i] = not fix
            if free[i]:
                nfree += 1
                scale = max(scale, abs(H[i, i]))
        if nfree == 0 or f == 0.0:
            break
        if scale == 0.0:
            scale = 1.0
        accepted = False
        fn = f
        for tries in range(40):
            for i in range(4):
                for j in range(4):
                    Hd[i, j] = H[i, j]
                Hd[i, i] += mu * scale + 1e-15 * scale
            if not _chol_solve(Hd, g, free, 4, dx):
                mu = max(4.0 * mu, 1e-8)
                continue
            for i in range(4):
                xn[i] = min(hi[i], max(lo[i], x[i] + dx[i]))
            _eval2(Pw_all, U_all, V_all, meta, sa, xn[0], xn[1], bin_, scra, SA)
            _eval2(Pw_all, U_all, V_all, meta, sb, xn[2], xn[3], bin_, scrb, SB)
            fn = 0.0
            for c in range(3):
                e = SA[0, 0, c] - SB[0, 0, c]
                fn += e * e
            if fn <= f:
                accepted = True
                break
            mu = max(4.0 * mu, 1e-8)
        if not accepted:
            # restore derivatives at x
            _eval2(Pw_all, U_all, V_all, meta, sa, x[0], x[1], bin_, scra, SA)
            _eval2(Pw_all, U_all, V_all, meta, sb, x[2], x[3], bin_, scrb, SB)
            break
        # 3-D size of the step
        st = 0.0
        for c in range(3):
            e = J[0, c] * (xn[0] - x[0]) + J[1, c] * (xn[1] - x[1])
            e2 = J[2, c] * (xn[2] - x[2]) + J[3, c] * (xn[3] - x[3])
            st += e * e + e2 * e2
        for i in range(4):
            x[i] = xn[i]
        for c in range(3):
            D[c] = SA[0, 0, c] - SB[0, 0, c]
        f_old = f
        f = fn
        mu = mu * 0.25 if mu > 1e-12 else 0.0
        if math.sqrt(st) <= step_tol or f_old - f <= 1e-30 * (1.0 + f_old):
            break
    return math.sqrt(f)


# --------------------------------------------------------------------------- trim edges
TRIM_STARTS = 5
ALT_MAX_ITER = 200


@jit
def _trim_foot(Pw, p, q, U, V, dom_s, seg, deg, x, step_tol, bin_, scr, SKL, B, B1, B2, Cd,
               out):
    """Nearest point to ``x`` on the trim boundary of one surface (1-D Newton on every
    segment from TRIM_STARTS starts).  ``out = (u, v, X, Y, Z)``; returns the distance."""
    best = np.inf
    for k in range(seg.shape[0]):
        nd = deg[k]
        Q = seg[k]
        for r in range(TRIM_STARTS):
            t = r / (TRIM_STARTS - 1.0)
            t, f = segment_newton(Pw, p, q, U, V, dom_s, Q, nd, t, x, step_tol, bin_, scr,
                                  SKL, B, B1, B2, Cd)
            d = math.sqrt(2.0 * f)
            if d < best:
                best = d
                _trim_point(Pw, p, q, U, V, dom_s, Q, nd, t, x, bin_, scr, SKL, B, B1, B2, Cd)
                out[0] = min(dom_s[1], max(dom_s[0], Cd[0, 0]))
                out[1] = min(dom_s[3], max(dom_s[2], Cd[0, 1]))
                out[2] = SKL[0, 0, 0]
                out[3] = SKL[0, 0, 1]
                out[4] = SKL[0, 0, 2]
    return best


@jit
def _face_foot(Pw_all, U_all, V_all, meta, dom, seg_all, seg_deg, seg_loop, trim_meta, s, x,
               u, v, uv_tol, step_tol, bin_, scr, SKL, B, B1, B2, Cd, winding, stack, depths,
               tleft, tright, out):
    """Nearest point of the trimmed face ``s`` to ``x`` near (u, v): the surface foot if
    it is inside the face, else the nearest trim-boundary point."""
    Pw, p, q, U, V = _surface(Pw_all, U_all, V_all, meta, s)
    # "not closed" as a runtime bool and explicit border allowances: literal arguments
    # would compile a second foot_newton (~5 s on a fresh install) beside projection's
    no_seam = s < 0
    u, v, d, it, st = foot_newton(Pw, p, q, U, V, dom[s, 0], dom[s, 1], dom[s, 2], dom[s, 3],
                                  no_seam, no_seam, x, u, v, step_tol, bin_, scr, SKL, 0.0, 0.0)
    if _uv_inside(seg_all, seg_deg, seg_loop, trim_meta, s, u, v, uv_tol, winding, stack,
                  depths, tleft, tright):
        out[0] = u
        out[1] = v
        out[2] = SKL[0, 0, 0]
        out[3] = SKL[0, 0, 1]
        out[4] = SKL[0, 0, 2]
        return d
    first = trim_meta[s, 0]
    cnt = trim_meta[s, 1]
    return _trim_foot(Pw, p, q, U, V, dom[s], seg_all[first:first + cnt],
                      seg_deg[first:first + cnt], x, step_tol, bin_, scr, SKL, B, B1, B2, Cd,
                      out)


@jit
def alternate_feet(Pw_all, U_all, V_all, meta, dom, seg_all, seg_deg, seg_loop, trim_meta,
                   sa, sb, x4, uv_tol, step_tol, bin_, scr, SKL, winding, stack, depths, tleft,
                   tright, res):
    """Alternating projections between two trimmed faces (the trim-edge cases:
    trim edge–surface, trim edge–trim edge), from parameters ``x4``.  Converges
    linearly; ``res = (ua, va, XA, YA, ZA, ub, vb, XB, YB, ZB)``.  Returns the distance
    of the final pair (a pair of face points: an upper bound)."""
    pmax1 = seg_all.shape[1]
    B = np.empty(pmax1)
    B1 = np.empty(pmax1)
    B2 = np.empty(pmax1)
    Cd = np.empty((3, 2))
    fa = np.empty(5)
    fb = np.empty(5)
    xa = np.empty(3)
    xb = np.empty(3)
    # start: the point of b at its parameters
    Pw, p, q, U, V = _surface(Pw_all, U_all, V_all, meta, sb)
    surface_derivs(Pw, p, q, U, V, min(dom[sb, 1], max(dom[sb, 0], x4[2])),
                   min(dom[sb, 3], max(dom[sb, 2], x4[3])), D2, bin_, scr, SKL)
    for c in range(3):
        xb[c] = SKL[0, 0, c]
    fb[0] = x4[2]
    fb[1] = x4[3]
    fa[0] = x4[0]
    fa[1] = x4[1]
    d = np.inf
    for it in range(ALT_MAX_ITER):
        _face_foot(Pw_all, U_all, V_all, meta, dom, seg_all, seg_deg, seg_loop, trim_meta, sa,
                   xb, fa[0], fa[1], uv_tol, step_tol, bin_, scr, SKL, B, B1, B2, Cd, winding,
                   stack, depths, tleft, tright, fa)
        for c in range(3):
            xa[c] = fa[2 + c]
        dn = _face_foot(Pw_all, U_all, V_all, meta, dom, seg_all, seg_deg, seg_loop, trim_meta,
                        sb, xa, fb[0], fb[1], uv_tol, step_tol, bin_, scr, SKL, B, B1, B2, Cd,
                        winding, stack, depths, tleft, tright, fb)
        moved = 0.0
        for c in range(3):
            moved += (fb[2 + c] - xb[c]) ** 2
            xb[c] = fb[2 + c]
        if dn < d:
            d = dn
            for c in range(5):
                res[c] = fa[c]
                res[5 + c] = fb[c]
        if math.sqrt(moved) <= step_tol:
            break
    return d


# --------------------------------------------------------------------------- B&B
@jit
def branch_and_bound(ctrl, ni, nf, n_nodes, nodes_a, nodes_b, Pw_all, U_all, V_all, meta,
                     dom, seg_all, seg_deg, seg_loop, seg_box, trim_meta, uv_tol, tol,
                     min_size, max_pairs, max_newton, step_tol, out_f, out_i):
    """Best-first branch and bound over pairs (node of scene A, node of scene B).

    ``ctrl``, ``ni``, ``nf`` hold the ``n_nodes`` root nodes (the Bézier patches,
    boxes and representative points filled, children -1); the pools grow as needed.
    Results: ``out_f = (upper, lower, xa, ya, za, xb, yb, zb, ua, va, ub, vb)``,
    ``out_i = (surface a, surface b, pairs popped, pairs split, pairs pushed,
    nodes, newton runs, stop code, peak heap, pruned pairs)``.
    Returns the final pools (for inspection and memory accounting).
    """
    pmax1 = seg_all.shape[1]
    winding = np.zeros(_max_loops(trim_meta), dtype=np.int64)
    stack = np.empty((MAX_DEPTH + 2, pmax1, 3))
    depths = np.empty(MAX_DEPTH + 2, dtype=np.int64)
    tleft = np.empty((pmax1, 3))
    tright = np.empty((pmax1, 3))
    maxdeg = np.int64(1)  # not a literal: one compile of derivs_scratch
    for s in range(meta.shape[0]):
        maxdeg = max(maxdeg, max(meta[s, 3], meta[s, 4]))
    tmp = np.empty((2 * maxdeg + 3, 4))
    bin_ = _binomial_table(2 * maxdeg + 2)
    scra = derivs_scratch(maxdeg, maxdeg, D2)
    scrb = derivs_scratch(maxdeg, maxdeg, D2)
    SA = np.zeros((3, 3, 3))
    SB = np.zeros((3, 3, 3))
    x4 = np.empty(4)
    alt = np.empty(10)

    cap = max(1024, 4 * nodes_a.shape[0] * nodes_b.shape[0])
    hlb = np.empty(cap)
    hab = np.empty(cap, dtype=np.int64)  # a pair (a, b) packed as a << 32 | b
    nh = 0
    upper = np.inf
    best_a = -1
    best_b = -1
    bx = np.zeros(12)
    pruned_min = np.inf
    final_min = np.inf
    pushed = 0
    popped = 0
    splits = 0
    newton_runs = 0
    peak = 0
    pruned = 0

    # initial upper bound from representative points, then the root pairs
    for ia in range(nodes_a.shape[0]):
        a = nodes_a[ia]
        for ib in range(nodes_b.shape[0]):
            b = nodes_b[ib]
            if ni[a, I_REPOK] and ni[b, I_REPOK]:
                d = 0.0
                for c in range(3):
                    e = nf[a, F_REP + c] - nf[b, F_REP + c]
                    d += e * e
                d = math.sqrt(d)
                if d < upper:
                    upper = d
                    best_a = a
                    best_b = b
                    for c in range(3):
                        bx[2 + c] = nf[a, F_REP + c]
                        bx[5 + c] = nf[b, F_REP + c]
                    bx[8] = nf[a, F_REPUV]
                    bx[9] = nf[a, F_REPUV + 1]
                    bx[10] = nf[b, F_REPUV]
                    bx[11] = nf[b, F_REPUV + 1]
    bsa = ni[best_a, I_SURF] if best_a >= 0 else -1
    bsb = ni[best_b, I_SURF] if best_b >= 0 else -1
    # Newton from the best root pair
    if best_a >= 0:
        x4[0] = bx[8]
        x4[1] = bx[9]
        x4[2] = bx[10]
        x4[3] = bx[11]
        d = newton4(Pw_all, U_all, V_all, meta, dom, bsa, bsb, x4, step_tol, bin_, scra,
                    scrb, SA, SB)
        newton_runs += 1
        if d < upper and _uv_inside(seg_all, seg_deg, seg_loop, trim_meta, bsa, x4[0], x4[1],
                                    uv_tol, winding, stack, depths, tleft, tright) \
                and _uv_inside(seg_all, seg_deg, seg_loop, trim_meta, bsb, x4[2], x4[3],
                               uv_tol, winding, stack, depths, tleft, tright):
            upper = d
            for c in range(3):
                bx[2 + c] = SA[0, 0, c]
                bx[5 + c] = SB[0, 0, c]
            for c in range(4):
                bx[8 + c] = x4[c]
    for ia in range(nodes_a.shape[0]):
        a = nodes_a[ia]
        for ib in range(nodes_b.shape[0]):
            b = nodes_b[ib]
            lb = pair_lower_bound(ctrl, ni, nf, a, b)
            if lb >= upper - tol:
                pruned += 1
                pruned_min = min(pruned_min, lb)
                continue
            hlb, hab, nh = _heap_push(hlb, hab, nh, lb, (a << 32) | b)
            pushed += 1
    peak = nh
    stop = STOP_CERTIFIED
    ctrl_top = np.int64(0)  # not a literal: one compile of _split_into
    for k in range(n_nodes):
        ctrl_top = max(ctrl_top, ni[k, I_OFF] + (ni[k, I_P] + 1) * (ni[k, I_Q] + 1) * 4)
    kids = np.empty(2, dtype=np.int64)
    while nh > 0:
        lb = hlb[0]
        a = hab[0] >> 32
        b = hab[0] & 0xFFFFFFFF
        if lb >= upper - tol:
            break
        if popped >= max_pairs:
            stop = STOP_MAX_PAIRS
            break
        nh = _heap_pop(hlb, hab, nh)
        popped += 1
        # upper bound from the pair's representative points (+ Newton when it improves)
        if ni[a, I_REPOK] and ni[b, I_REPOK]:
            d = 0.0
            for c in range(3):
                e = nf[a, F_REP + c] - nf[b, F_REP + c]
                d += e * e
            d = math.sqrt(d)
            if d < upper:
                upper = d
                bsa = ni[a, I_SURF]
                bsb = ni[b, I_SURF]
                for c in range(3):
                    bx[2 + c] = nf[a, F_REP + c]
                    bx[5 + c] = nf[b, F_REP + c]
                bx[8] = nf[a, F_REPUV]
                bx[9] = nf[a, F_REPUV + 1]
                bx[10] = nf[b, F_REPUV]
                bx[11] = nf[b, F_REPUV + 1]
                if newton_runs < max_newton:
                    x4[0] = bx[8]
                    x4[1] = bx[9]
                    x4[2] = bx[10]
                    x4[3] = bx[11]
                    sa = ni[a, I_SURF]
                    sb = ni[b, I_SURF]
                    d = newton4(Pw_all, U_all, V_all, meta, dom, sa, sb, x4, step_tol, bin_,
                                scra, scrb, SA, SB)
                    newton_runs += 1
                    if d < upper and _uv_inside(seg_all, seg_deg, seg_loop, trim_meta, sa,
                                                x4[0], x4[1], uv_tol, winding, stack, depths,
                                                tleft, tright) \
                            and _uv_inside(seg_all, seg_deg, seg_loop, trim_meta, sb, x4[2],
                                           x4[3], uv_tol, winding, stack, depths, tleft,
                                           tright):
                        upper = d
                        bsa = sa
                        bsb = sb
                        for c in range(3):
                            bx[2 + c] = SA[0, 0, c]
                            bx[5 + c] = SB[0, 0, c]
                        for c in range(4):
                            bx[8 + c] = x4[c]
                    elif trim_meta[sa, 1] > 0 or trim_meta[sb, 1] > 0:
                        x4[0] = nf[a, F_REPUV]
                        x4[1] = nf[a, F_REPUV + 1]
                        x4[2] = nf[b, F_REPUV]
                        x4[3] = nf[b, F_REPUV + 1]
                        d = alternate_feet(Pw_all, U_all, V_all, meta, dom, seg_all, seg_deg,
                                           seg_loop, trim_meta, sa, sb, x4, uv_tol, step_tol,
                                           bin_, scra, SA, winding, stack, depths, tleft,
                                           tright, alt)
                        newton_runs += 1
                        if d < upper:
                            upper = d
                            bsa = sa
                            bsb = sb
                            for c in range(3):
                                bx[2 + c] = alt[2 + c]
                                bx[5 + c] = alt[7 + c]
                            bx[8] = alt[0]
                            bx[9] = alt[1]
                            bx[10] = alt[5]
                            bx[11] = alt[6]
            if lb >= upper - tol:
                pruned += 1
                pruned_min = min(pruned_min, lb)
                continue
        # split the larger node
        sz_a = nf[a, F_SIZE]
        sz_b = nf[b, F_SIZE]
        if sz_a <= min_size and sz_b <= min_size:
            final_min = min(final_min, lb)
            continue
        k = a if sz_a >= sz_b else b
        other = b if k == a else a
        if ni[k, I_C0] < 0:
            # create the two children of k
            need = n_nodes + 2
            if need > ni.shape[0]:
                ni = _grow2(ni, need)
                nf = _grow2(nf, need)
            p = ni[k, I_P]
            q = ni[k, I_Q]
            m = (p + 1) * (q + 1) * 4
            if ctrl_top + 2 * m > ctrl.shape[0]:
                ctrl = _grow1(ctrl, ctrl_top + 2 * m)
            dirn = _split_dir(ctrl, ni[k, I_OFF], p, q)
            _split_into(ctrl, ni[k, I_OFF], p, q, dirn, ctrl_top, ctrl_top + m)
            s = ni[k, I_SURF]
            for h in range(2):
                c = n_nodes + h
                kids[h] = c
                ni[c, I_OFF] = ctrl_top + h * m
                ni[c, I_P] = p
                ni[c, I_Q] = q
                ni[c, I_SURF] = s
                ni[c, I_C0] = -1
                ni[c, I_C1] = -1
                ni[c, I_SIDE] = ni[k, I_SIDE]
                ni[c, I_DIR] = 0
                u0 = nf[k, F_U0]
                u1 = nf[k, F_U1]
                v0 = nf[k, F_V0]
                v1 = nf[k, F_V1]
                if dirn == 0:
                    um = 0.5 * (u0 + u1)
                    if h == 0:
                        u1 = um
                    else:
                        u0 = um
                else:
                    vm = 0.5 * (v0 + v1)
                    if h == 0:
                        v1 = vm
                    else:
                        v0 = vm
                nf[c, F_U0] = u0
                nf[c, F_U1] = u1
                nf[c, F_V0] = v0
                nf[c, F_V1] = v1
                _node_box(ctrl, ni[c, I_OFF], p, q, nf, c)
                st = ni[k, I_STATE]
                if st == ST_MIXED:
                    st = _box_trim_state(seg_all, seg_deg, seg_loop, seg_box, trim_meta, s,
                                         u0, u1, v0, v1, uv_tol, winding, stack, depths,
                                         tleft, tright)
                ni[c, I_STATE] = st
                _patch_eval(ctrl, ni[c, I_OFF], p, q, 0.5, 0.5, tmp, nf[c, F_REP:F_REP + 3])
                nf[c, F_REPUV] = 0.5 * (u0 + u1)
                nf[c, F_REPUV + 1] = 0.5 * (v0 + v1)
                ok = st == ST_INSIDE
                if st == ST_MIXED:
                    ok = _uv_inside(seg_all, seg_deg, seg_loop, trim_meta, s,
                                    nf[c, F_REPUV], nf[c, F_REPUV + 1], uv_tol, winding,
                                    stack, depths, tleft, tright)
                ni[c, I_REPOK] = 1 if ok else 0
            ni[k, I_C0] = kids[0]
            ni[k, I_C1] = kids[1]
            ni[k, I_DIR] = dirn
            n_nodes += 2
            ctrl_top += 2 * m
        splits += 1
        for h in range(2):
            c = ni[k, I_C0 + h]
            if ni[c, I_STATE] == ST_OUTSIDE:
                continue
            ca = c if k == a else other
            cb = other if k == a else c
            lb2 = pair_lower_bound(ctrl, ni, nf, ca, cb)
            if lb2 < lb:
                lb2 = lb  # the parent's bound holds for the child too
            if lb2 >= upper - tol:
                pruned += 1
                pruned_min = min(pruned_min, lb2)
                continue
            hlb, hab, nh = _heap_push(hlb, hab, nh, lb2, (ca << 32) | cb)
            pushed += 1
        peak = max(peak, nh)
    lower = upper
    if nh > 0:
        lower = min(lower, hlb[0])
    lower = min(lower, pruned_min, final_min)
    if lower < 0.0:
        lower = 0.0
    out_f[0] = upper
    out_f[1] = lower
    for c in range(2, 12):
        out_f[c] = bx[c]
    out_i[0] = bsa
    out_i[1] = bsb
    out_i[2] = popped
    out_i[3] = splits
    out_i[4] = pushed
    out_i[5] = n_nodes
    out_i[6] = newton_runs
    out_i[7] = stop
    out_i[8] = peak
    out_i[9] = pruned
    return ctrl, ni, nf


@jit
def init_nodes(ctrl, ni, nf, n, seg_all, seg_deg, seg_loop, seg_box, trim_meta, uv_tol):
    """Fill boxes, trim states and representative points of the root nodes ``0..n-1``
    (offset, degrees, surface and UV box already set)."""
    pmax1 = seg_all.shape[1]
    winding = np.zeros(_max_loops(trim_meta), dtype=np.int64)
    stack = np.empty((MAX_DEPTH + 2, pmax1, 3))
    depths = np.empty(MAX_DEPTH + 2, dtype=np.int64)
    tleft = np.empty((pmax1, 3))
    tright = np.empty((pmax1, 3))
    for k in range(n):
        p = ni[k, I_P]
        q = ni[k, I_Q]
        tmp = np.empty((p + q + 3, 4))
        _node_box(ctrl, ni[k, I_OFF], p, q, nf, k)
        s = ni[k, I_SURF]
        u0 = nf[k, F_U0]
        u1 = nf[k, F_U1]
        v0 = nf[k, F_V0]
        v1 = nf[k, F_V1]
        st = _box_trim_state(seg_all, seg_deg, seg_loop, seg_box, trim_meta, s, u0, u1, v0,
                             v1, uv_tol, winding, stack, depths, tleft, tright)
        ni[k, I_STATE] = st
        ni[k, I_C0] = -1
        ni[k, I_C1] = -1
        _patch_eval(ctrl, ni[k, I_OFF], p, q, 0.5, 0.5, tmp, nf[k, F_REP:F_REP + 3])
        nf[k, F_REPUV] = 0.5 * (u0 + u1)
        nf[k, F_REPUV + 1] = 0.5 * (v0 + v1)
        ok = st == ST_INSIDE
        if st == ST_MIXED:
            ok = _uv_inside(seg_all, seg_deg, seg_loop, trim_meta, s, nf[k, F_REPUV],
                            nf[k, F_REPUV + 1], uv_tol, winding, stack, depths, tleft, tright)
        ni[k, I_REPOK] = 1 if ok else 0
