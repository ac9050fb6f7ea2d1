"""Surface–surface distance kernels, part 3: curved 1-Lipschitz separators.

For any point ``c`` or line ``L``, ``phi`` = the distance to it is 1-Lipschitz, so for
``x`` in A and ``y`` in B

    |x - y|  >=  phi(y) - phi(x)   (and >= phi(x) - phi(y)),

hence ``dist(A, B) >= min_B phi - max_A phi``.  Over a rational Bézier patch
``P = X / w`` (homogeneous net ``X_ij``, weights ``w_ij > 0``) the square
``phi(P)^2 = |Z|^2 / w^2`` with ``Z = X - c w`` (point) or ``Z = (X - c w) x d``
(line through ``c``, unit direction ``d``) is a ratio of two polynomials of degree
(2p, 2q) whose Bernstein coefficients are, up to the same positive factor
``1 / (C(2p, k) C(2q, l))``,

    N_kl = sum_{i+i'=k, j+j'=l} C(p,i) C(p,i') C(q,j) C(q,j') Z_ij . Z_i'j'
    D_kl = same sum with w_ij w_i'j'  (> 0).

A ratio of polynomials with a positive denominator lies between the smallest and the
largest ratio of their coefficients, so ``min_kl N_kl / D_kl <= phi^2 <= max_kl N_kl /
D_kl`` on the patch.  On a sphere about ``c`` (a cylinder about ``L``) ``|Z|^2 = r^2
w^2`` identically, so every ratio is ``r^2``: the bound is exact at the root, which a
plane separator can never be along a curved continuum of minima.

The separators are chosen from the feet of the first Newton run: at each foot the two
centres of principal curvature (points) and the lines through them along the other
principal direction (the axis of a cylinder, of a surface of revolution at its
equator), and the centre of a sphere fitted exactly to a root patch of the best pair;
only those on a level set of which one of the two best root patches lies are kept
(so freeform pairs pay nothing).  Rounding: each ratio is widened by ``(8 n + 64) eps S^2`` (``n`` control
points, ``S`` = largest ``|X / w| + |c|``), a bound on the error of the sums, and the
square roots are widened by a further 4 ulps.
"""

from __future__ import annotations

import math

import numpy as np

from .numba_ext.policy import jit_plain as jit

NSEP = 10         # 2 fitted sphere centres, 2 points + 2 lines per foot
SEP_W = 7         # sep rows: kind (0 point, 1 line), centre (3), direction (3)
EPS = 2.220446049250313e-16


@jit
def _add_sep(sep, nsep, kind, c0, c1, c2, d0, d1, d2, tol_same):
    """Append a separator unless an equal one is already there; returns the count."""
    for k in range(nsep):
        if sep[k, 0] != kind:
            continue
        e = math.sqrt((sep[k, 1] - c0) ** 2 + (sep[k, 2] - c1) ** 2 + (sep[k, 3] - c2) ** 2)
        if kind == 0:
            if e <= tol_same:
                return nsep
        else:
            # same line: parallel directions and c on the other line
            cr0 = sep[k, 5] * d2 - sep[k, 6] * d1
            cr1 = sep[k, 6] * d0 - sep[k, 4] * d2
            cr2 = sep[k, 4] * d1 - sep[k, 5] * d0
            if math.sqrt(cr0 * cr0 + cr1 * cr1 + cr2 * cr2) <= 1e-9:
                x0 = c0 - sep[k, 1]
                x1 = c1 - sep[k, 2]
                x2 = c2 - sep[k, 3]
                t = x0 * d0 + x1 * d1 + x2 * d2
                off = math.sqrt(max(0.0, x0 * x0 + x1 * x1 + x2 * x2 - t * t))
                if off <= tol_same:
                    return nsep
    if nsep >= sep.shape[0]:
        return nsep
    sep[nsep, 0] = kind
    sep[nsep, 1] = c0
    sep[nsep, 2] = c1
    sep[nsep, 3] = c2
    sep[nsep, 4] = d0
    sep[nsep, 5] = d1
    sep[nsep, 6] = d2
    return nsep + 1


@jit
def curvature_separators(S, sep, nsep, extent):
    """Add the centres of principal curvature of the surface point with derivatives
    ``S`` (``S[k, l]`` = d^(k+l) / du^k dv^l, as filled by Newton) and the lines
    through them along the other principal direction.  Centres farther than
    ``1e3 * extent`` (nearly flat directions) are skipped.  Returns the new count."""
    su0, su1, su2 = S[1, 0, 0], S[1, 0, 1], S[1, 0, 2]
    sv0, sv1, sv2 = S[0, 1, 0], S[0, 1, 1], S[0, 1, 2]
    n0 = su1 * sv2 - su2 * sv1
    n1 = su2 * sv0 - su0 * sv2
    n2 = su0 * sv1 - su1 * sv0
    ln = math.sqrt(n0 * n0 + n1 * n1 + n2 * n2)
    if not (ln > 0.0) or not np.isfinite(ln):
        return nsep
    n0 /= ln
    n1 /= ln
    n2 /= ln
    E = su0 * su0 + su1 * su1 + su2 * su2
    F = su0 * sv0 + su1 * sv1 + su2 * sv2
    G = sv0 * sv0 + sv1 * sv1 + sv2 * sv2
    L = S[2, 0, 0] * n0 + S[2, 0, 1] * n1 + S[2, 0, 2] * n2
    M = S[1, 1, 0] * n0 + S[1, 1, 1] * n1 + S[1, 1, 2] * n2
    N = S[0, 2, 0] * n0 + S[0, 2, 1] * n1 + S[0, 2, 2] * n2
    a = E * G - F * F
    if not (a > 0.0):
        return nsep
    b = E * N + G * L - 2.0 * F * M
    c = L * N - M * M
    disc = math.sqrt(max(0.0, b * b - 4.0 * a * c))
    kap = np.empty(2)
    kap[0] = (b + disc) / (2.0 * a)
    kap[1] = (b - disc) / (2.0 * a)
    dirs = np.zeros((2, 3))
    for i in range(2):
        k = kap[i]
        du1 = M - k * F
        dv1 = -(L - k * E)
        du2 = N - k * G
        dv2 = -(M - k * F)
        if du1 * du1 + dv1 * dv1 >= du2 * du2 + dv2 * dv2:
            du, dv = du1, dv1
        else:
            du, dv = du2, dv2
        if du == 0.0 and dv == 0.0:  # umbilic: any direction
            du = 1.0 if i == 0 else 0.0
            dv = 0.0 if i == 0 else 1.0
        t0 = su0 * du + sv0 * dv
        t1 = su1 * du + sv1 * dv
        t2 = su2 * du + sv2 * dv
        lt = math.sqrt(t0 * t0 + t1 * t1 + t2 * t2)
        if lt > 0.0:
            dirs[i, 0] = t0 / lt
            dirs[i, 1] = t1 / lt
            dirs[i, 2] = t2 / lt
    if disc <= 1e-12 * abs(b):  # umbilic: make the second direction orthogonal
        d0, d1, d2 = dirs[0, 0], dirs[0, 1], dirs[0, 2]
        dirs[1, 0] = n1 * d2 - n2 * d1
        dirs[1, 1] = n2 * d0 - n0 * d2
        dirs[1, 2] = n0 * d1 - n1 * d0
    same = 1e-9 * extent
    for i in range(2):
        k = kap[i]
        if not (abs(k) * 1e3 * extent > 1.0):
            continue
        c0 = S[0, 0, 0] + n0 / k
        c1 = S[0, 0, 1] + n1 / k
        c2 = S[0, 0, 2] + n2 / k
        nsep = _add_sep(sep, nsep, 0, c0, c1, c2, 0.0, 0.0, 0.0, same)
        j = 1 - i
        if dirs[j, 0] ** 2 + dirs[j, 1] ** 2 + dirs[j, 2] ** 2 > 0.5:
            nsep = _add_sep(sep, nsep, 1, c0, c1, c2, dirs[j, 0], dirs[j, 1], dirs[j, 2],
                            same)
    return nsep


@jit
def sphere_fit_separator(ctrl, off, p, q, bin_, sep, nsep, extent):
    """Add the centre of the sphere through the patch at ``off`` when the patch lies on
    one: ``|X - c w|^2 = r^2 w^2`` as polynomials is linear in ``(c, r^2 - |c|^2)``
    coefficient by coefficient (``A_kl - 2 c . B_kl = (r^2 - |c|^2) D_kl``), solved in
    least squares; kept when every coefficient ratio agrees to 1e-9 relative.  Exact
    to rounding where curvature estimated by Newton's derivatives is not."""
    n = (p + 1) * (q + 1)
    H = np.zeros((4, 5))
    m = (2 * p + 1) * (2 * q + 1)
    rows = np.zeros((m, 5))
    r = 0
    for kk in range(2 * p + 1):
        for ll in range(2 * q + 1):
            A = 0.0
            B0 = 0.0
            B1 = 0.0
            B2 = 0.0
            D = 0.0
            for i in range(max(0, kk - p), min(p, kk) + 1):
                i2 = kk - i
                bi = bin_[p, i] * bin_[p, i2]
                for j in range(max(0, ll - q), min(q, ll) + 1):
                    j2 = ll - j
                    beta = bi * bin_[q, j] * bin_[q, j2]
                    b1 = off + 4 * (i * (q + 1) + j)
                    b2 = off + 4 * (i2 * (q + 1) + j2)
                    A += beta * (ctrl[b1] * ctrl[b2] + ctrl[b1 + 1] * ctrl[b2 + 1]
                                 + ctrl[b1 + 2] * ctrl[b2 + 2])
                    B0 += beta * ctrl[b1] * ctrl[b2 + 3]
                    B1 += beta * ctrl[b1 + 1] * ctrl[b2 + 3]
                    B2 += beta * ctrl[b1 + 2] * ctrl[b2 + 3]
                    D += beta * ctrl[b1 + 3] * ctrl[b2 + 3]
            rows[r, 0] = 2.0 * B0 / D
            rows[r, 1] = 2.0 * B1 / D
            rows[r, 2] = 2.0 * B2 / D
            rows[r, 3] = 1.0
            rows[r, 4] = A / D
            r += 1
    for r in range(m):
        for i in range(4):
            for j in range(5):
                H[i, j] += rows[r, i] * rows[r, j]
    # Gaussian elimination with partial pivoting on the 4 x 4 normal equations
    for c in range(4):
        piv = c
        for i in range(c + 1, 4):
            if abs(H[i, c]) > abs(H[piv, c]):
                piv = i
        if not (abs(H[piv, c]) > 0.0):
            return nsep
        for j in range(5):
            H[c, j], H[piv, j] = H[piv, j], H[c, j]
        for i in range(c + 1, 4):
            f = H[i, c] / H[c, c]
            for j in range(c, 5):
                H[i, j] -= f * H[c, j]
    x = np.zeros(4)
    for c in range(3, -1, -1):
        t = H[c, 4]
        for j in range(c + 1, 4):
            t -= H[c, j] * x[j]
        x[c] = t / H[c, c]
    if not (np.isfinite(x[0]) and np.isfinite(x[1]) and np.isfinite(x[2])):
        return nsep
    cc = x[0] * x[0] + x[1] * x[1] + x[2] * x[2]
    r2 = x[3] + cc
    if not (r2 > 0.0) or math.sqrt(r2) > 1e3 * extent:
        return nsep
    for r in range(m):
        e = rows[r, 4] - (rows[r, 0] * x[0] + rows[r, 1] * x[1] + rows[r, 2] * x[2] + x[3])
        if abs(e) > 1e-9 * (r2 + cc):
            return nsep
    return _add_sep(sep, nsep, 0, x[0], x[1], x[2], 0.0, 0.0, 0.0, 0.0)


@jit
def sep_bounds(ctrl, off, p, q, sep, nsep, bin_, Z, R, ph, k):
    """``ph[k, 2 j : 2 j + 2]`` = certified [min, max] of the distance to separator
    ``j`` over the patch at ``off`` (degrees p, q).  ``Z`` scratch of >= (p+1)(q+1)
    rows x 4, ``R`` of >= (2p+1, 2q+1), ``bin_`` a binomial table to at least
    max(p, q).  ``ph[k, 2 NSEP]`` = the split direction the separators ask for: 1 (v)
    when some separator's coefficient ratios are constant along u (the patch spins
    about the separator: splitting in u cannot tighten it), 0 (u) symmetrically,
    -1 otherwise."""
    n = (p + 1) * (q + 1)
    ph[k, 2 * NSEP] = -1.0
    for s in range(nsep):
        kind = sep[s, 0]
        c0 = sep[s, 1]
        c1 = sep[s, 2]
        c2 = sep[s, 3]
        d0 = sep[s, 4]
        d1 = sep[s, 5]
        d2 = sep[s, 6]
        cn = math.sqrt(c0 * c0 + c1 * c1 + c2 * c2)
        S = 0.0
        for i in range(n):
            b = off + 4 * i
            w = ctrl[b + 3]
            y0 = ctrl[b] - c0 * w
            y1 = ctrl[b + 1] - c1 * w
            y2 = ctrl[b + 2] - c2 * w
            if kind == 1:
                z0 = y1 * d2 - y2 * d1
                z1 = y2 * d0 - y0 * d2
                z2 = y0 * d1 - y1 * d0
                y0, y1, y2 = z0, z1, z2
            Z[i, 0] = y0
            Z[i, 1] = y1
            Z[i, 2] = y2
            Z[i, 3] = w
            xn = math.sqrt(ctrl[b] ** 2 + ctrl[b + 1] ** 2 + ctrl[b + 2] ** 2) / w
            S = max(S, xn + cn)
        rlo = np.inf
        rhi = -np.inf
        for kk in range(2 * p + 1):
            for ll in range(2 * q + 1):
                num = 0.0
                den = 0.0
                for i in range(max(0, kk - p), min(p, kk) + 1):
                    i2 = kk - i
                    bi = bin_[p, i] * bin_[p, i2]
                    for j in range(max(0, ll - q), min(q, ll) + 1):
                        j2 = ll - j
                        beta = bi * bin_[q, j] * bin_[q, j2]
                        r1 = i * (q + 1) + j
                        r2 = i2 * (q + 1) + j2
                        num += beta * (Z[r1, 0] * Z[r2, 0] + Z[r1, 1] * Z[r2, 1]
                                       + Z[r1, 2] * Z[r2, 2])
                        den += beta * (Z[r1, 3] * Z[r2, 3])
                r = num / den
                R[kk, ll] = r
                rlo = min(rlo, r)
                rhi = max(rhi, r)
        err = (8.0 * n + 64.0) * EPS * S * S
        if ph[k, 2 * NSEP] < 0.0:
            su = 0.0
            for ll in range(2 * q + 1):
                a0 = np.inf
                a1 = -np.inf
                for kk in range(2 * p + 1):
                    a0 = min(a0, R[kk, ll])
                    a1 = max(a1, R[kk, ll])
                su = max(su, a1 - a0)
            sv = 0.0
            for kk in range(2 * p + 1):
                a0 = np.inf
                a1 = -np.inf
                for ll in range(2 * q + 1):
                    a0 = min(a0, R[kk, ll])
                    a1 = max(a1, R[kk, ll])
                sv = max(sv, a1 - a0)
            if su <= 1e-6 * sv and sv > 1e3 * err:
                ph[k, 2 * NSEP] = 1.0
            elif sv <= 1e-6 * su and su > 1e3 * err:
                ph[k, 2 * NSEP] = 0.0
        lo = rlo - err
        ph[k, 2 * s] = math.sqrt(lo) * (1.0 - 4.0 * EPS) if lo > 0.0 else 0.0
        ph[k, 2 * s + 1] = math.sqrt(max(0.0, rhi + err)) * (1.0 + 4.0 * EPS)
        if not (np.isfinite(rlo) and np.isfinite(rhi)):
            ph[k, 2 * s] = 0.0
            ph[k, 2 * s + 1] = np.inf


@jit
def keep_level_separators(ctrl, offa, pa, qa, offb, pb, qb, sep, nsep, bin_, Z, R, ph,
                          extent):
    """Keep only the separators on a level set of which one of the two patches lies
    (distance range narrower than ``1e-7 * extent``): elsewhere a separator cannot beat
    the plane bounds by much along a continuum, and it costs time on every node.
    Uses rows 0 and 1 of ``ph`` as scratch; returns the new count."""
    sep_bounds(ctrl, offa, pa, qa, sep, nsep, bin_, Z, R, ph, 0)
    sep_bounds(ctrl, offb, pb, qb, sep, nsep, bin_, Z, R, ph, 1)
    m = 0
    for s in range(nsep):
        wa = ph[0, 2 * s + 1] - ph[0, 2 * s]
        wb = ph[1, 2 * s + 1] - ph[1, 2 * s]
        if min(wa, wb) <= 1e-7 * extent:
            for c in range(sep.shape[1]):
                sep[m, c] = sep[s, c]
            m += 1
    return m


@jit
def sep_lower_bound(ph, nsep, a, b):
    """Largest ``min_B phi - max_A phi`` / ``min_A phi - max_B phi`` over the
    separators (0 when there is none)."""
    lb = 0.0
    for s in range(nsep):
        e = max(ph[b, 2 * s] - ph[a, 2 * s + 1], ph[a, 2 * s] - ph[b, 2 * s + 1])
        if e > lb:
            lb = e
    return lb
