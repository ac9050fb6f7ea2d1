"""The u-line root of the chord refinement is edge_root's, bit for bit.

:func:`geomkit._kernels.section_refine._root_on_u_line` replaced, in ``_midpoint`` on
leaves monotone in u, the plane values at the leaf's sides (``_f_at``) and
:func:`geomkit._kernels.section.edge_root` on the line between them; it sums each
control row over v once per line.  The replaced calls are kept here as the oracle, on
random rational surfaces (repeated knots, degrees 1-4) and lines through knots, leaf
sides on knots, planes through a surface point, and on planes missing the line."""

from __future__ import annotations

import numpy as np

from geomkit._kernels import section as K
from geomkit._kernels import section_refine as R
from geomkit.tolerances import EDGE_ROOT_TOL


def _knots(rng, n, p):
    inner = np.sort(rng.choice(np.round(rng.uniform(0.1, 0.9, 4), 3), n - p - 1))
    return np.concatenate([np.zeros(p + 1), inner, np.ones(p + 1)]) * 3.0 - 1.0


def _scratch(p, q):
    mm = max(p, q) + 1
    return (np.empty(p + 1), np.empty(q + 1), np.empty(mm), np.empty(mm), np.empty(4),
            np.empty(3))


def _oracle(Pw, p, q, U, V, plane, lu, hu, v, zsnap, sp):
    flo = K._f_at(Pw, p, q, U, V, plane, lu, v, *sp)
    fhi = K._f_at(Pw, p, q, U, V, plane, hu, v, *sp)
    flo = 0.0 if abs(flo) <= zsnap else flo
    fhi = 0.0 if abs(fhi) <= zsnap else fhi
    if not flo * fhi < 0:
        return -1.0
    return K.edge_root(Pw, p, q, U, V, plane, lu, v, hu, v, flo, fhi, EDGE_ROOT_TOL, *sp)


def test_u_line_root_is_edge_root_bit_for_bit():
    rng = np.random.default_rng(18)
    checked = 0
    for _ in range(150):
        p, q = rng.integers(1, 5, 2)
        nu, nv = p + 1 + rng.integers(0, 5), q + 1 + rng.integers(0, 5)
        U, V = _knots(rng, nu, p), _knots(rng, nv, q)
        Pw = np.empty((nu, nv, 4))
        Pw[..., 3] = rng.uniform(0.3, 2.0, (nu, nv))
        Pw[..., :3] = rng.normal(size=(nu, nv, 3)) * Pw[..., 3:]
        sp = _scratch(p, q)
        nd = (None, None, None, np.empty((nu, 4)))
        for _ in range(12):
            ends = np.sort(rng.choice(np.concatenate([U, rng.uniform(-1, 2, 4)]), 2))
            lu, hu = float(ends[0]), float(ends[1])
            v = float(rng.choice(np.concatenate([V, rng.uniform(-1, 2, 3)])))
            if v == 0.0 or hu <= lu:
                continue
            X = np.empty(3)
            n = rng.normal(size=3)
            n /= np.linalg.norm(n)
            K._f_at(Pw, p, q, U, V, np.array([*n, 0.0]), rng.uniform(lu, hu), v, *sp[:5], X)
            for off in (0.0, 1e3):       # through a point of the line; far off
                plane = np.array([*n, -n @ X + off])
                for zsnap in (0.0, 1e-12):
                    want = _oracle(Pw, p, q, U, V, plane, lu, hu, v, zsnap, sp)
                    got = R._root_on_u_line(Pw, p, q, U, V, plane, lu, hu, v, zsnap,
                                            EDGE_ROOT_TOL, sp, nd)
                    assert got == want or (np.isnan(got) and np.isnan(want)), \
                        (p, q, U, V, lu, hu, v, plane, zsnap, got, want)
                    checked += want >= 0.0
    assert checked > 500
