"""gdt.float_pattern (a composite position's lower segment: the pattern's zones move
together) against a brute-force minimisation of the exact objective."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.optimize import minimize
from scipy.spatial.transform import Rotation

from geomkit import gdt


def _objective(x, ends, N, A, lim, free):
    w, t = np.zeros(3), np.zeros(3)
    for v, name in zip(x, free):
        (w if name[0] == "r" else t)["xyz".index(name[1])] = v
    R = Rotation.from_rotvec(w).as_matrix()
    worst = 0.0
    for X, n, a, L in zip(ends, N, A, lim):
        nm, am = R @ n + t, R @ a
        D = X - nm
        D = D - np.outer(D @ am, am)
        worst = max(worst, 2.0 * np.linalg.norm(D, axis=1).max() / L)
    return worst


def _brute(ends, N, A, lim, free, seed=0):
    rng = np.random.default_rng(seed)
    best = np.inf
    for _ in range(12):
        x0 = rng.normal(scale=1e-3, size=len(free))
        r = minimize(_objective, x0, args=(ends, N, A, lim, free), method="Nelder-Mead",
                     options={"xatol": 1e-12, "fatol": 1e-14, "maxiter": 20000})
        best = min(best, r.fun)
    return best


@pytest.mark.parametrize("seed", [0, 1, 2])
@pytest.mark.parametrize("free", [("tx", "ty", "tz"), ("rz", "tx", "ty", "tz")])
def test_float_pattern_matches_brute_force(seed, free):
    rng = np.random.default_rng(seed)
    centres = rng.uniform(-50, 50, size=(4, 2))
    N = [np.array([x, y, 0.0]) for x, y in centres]
    A = [np.array([0.0, 0.0, 1.0])] * 4
    ends = []
    for n in N:
        d = rng.normal(scale=0.02, size=(2, 3))
        d[:, 2] = 0.0
        ends.append(np.array([n + [0, 0, 0.0], n + [0, 0, 12.0]]) + d)
    lim = [0.1, 0.1, 0.12, 0.1]
    got, motion = gdt.float_pattern(ends, N, A, lim, free)
    ours = max(g / L for g, L in zip(got, lim))
    brute = _brute(ends, N, A, lim, [f for f in ("rx", "ry", "rz", "tx", "ty", "tz")
                                      if f in free])
    # ours is exact at its motion (never below the optimum) and within the polygon factor
    assert ours >= brute - 1e-9
    assert ours <= brute / np.cos(np.pi / 64) + 1e-9
    # translation alone cannot beat translation + rotation
    if "rz" in free:
        got_t, _ = gdt.float_pattern(ends, N, A, lim, ("tx", "ty", "tz"))
        assert ours <= max(g / L for g, L in zip(got_t, lim)) + 1e-12


def test_float_pattern_recovers_a_shifted_pattern():
    N = [np.array([x, y, 0.0]) for x, y in ((0, 0), (40, 0), (40, 30), (0, 30))]
    A = [np.array([0.0, 0.0, 1.0])] * 4
    shift = np.array([0.3, -0.2, 0.0])
    R = Rotation.from_rotvec([0, 0, 0.004]).as_matrix()
    ends = [np.array([R @ n + shift, R @ (n + [0, 0, 10.0]) + shift]) for n in N]
    got, motion = gdt.float_pattern(ends, N, A, [0.05] * 4, ("rz", "tx", "ty", "tz"))
    assert got.max() < 2e-5          # linearised step, exact evaluation: 2nd order left
    got_t, _ = gdt.float_pattern(ends, N, A, [0.05] * 4, ("tx", "ty", "tz"))
    assert got_t.max() > 0.05        # the rotation matters
