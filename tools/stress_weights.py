"""Tessellation of random rational surfaces with independent weights: a long run.

``python tools/stress_weights.py [count] [seed] [max_seconds]``: draws ``count``
surfaces from ``tests/mesh/test_tessellate_weights.py``'s generator with independent
weights (ratios up to 1e6 between neighbouring control points), tessellates each at a
tolerance of 1e-4 to 1e-2 of its size and prints the surfaces that end above
``tol`` (a :class:`~geomkit.errors.ToleranceNotMetWarning`) or take longer than
``max_seconds`` (a bilinear patch with neighbouring weights 1e5 apart can need
millions of uniform UV cells), then a summary line.
"""

from __future__ import annotations

import sys
import time
import warnings
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
# tests/ for the helpers package the test module imports, tests/mesh/ for the module
sys.path[:0] = [str(ROOT), str(ROOT / "tests"), str(ROOT / "tests" / "mesh")]

import geomkit  # noqa: E402
from test_tessellate_weights import random_rational  # noqa: E402


def main(count=300, seed=0, max_seconds=30.0):
    rng = np.random.default_rng(seed)
    failed = slow = 0
    total = 0.0
    for i in range(count):
        s = random_rational(rng)
        # the generator's independent family, at the full ratio
        ratio = 10 ** rng.uniform(0, 6)
        W = np.exp(rng.uniform(0, np.log(ratio), s.weights.shape))
        s = geomkit.Surface(s.degree_u, s.degree_v, s.knots_u, s.knots_v,
                            s.control_points, W)
        tol = 10 ** rng.uniform(-4, -2) * s.size
        t0 = time.perf_counter()
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always", geomkit.errors.ToleranceNotMetWarning)
            mesh = geomkit.tessellate(s, tol)
        dt = time.perf_counter() - t0
        total += dt
        over = bool(caught) or not mesh.max_deviation <= tol
        failed += over
        slow += dt > max_seconds
        if over or dt > max_seconds:
            print(f"surface {i}: max_deviation / tol = {mesh.max_deviation / tol:.3f}, "
                  f"{len(mesh.faces)} faces, {dt:.1f} s, weight ratio {ratio:.3g}")
    print(f"{count} surfaces (seed {seed}): {failed} above tol, {slow} slower than "
          f"{max_seconds} s, {total:.0f} s in all")
    return failed


if __name__ == "__main__":
    args = sys.argv[1:]
    sys.exit(1 if main(int(args[0]) if args else 300, int(args[1]) if len(args) > 1 else 0,
                       float(args[2]) if len(args) > 2 else 30.0) else 0)
