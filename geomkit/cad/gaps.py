"""Edge gaps between neighbouring faces of a CAD model.

Each face's trim boundary is sampled in 3-D (``S(c(t))`` at ``per_piece`` parameters
per trim piece) and every sample's distance to the nearest sample of another face's
boundary is found (k-d tree).  Samples farther than ``free`` (default 1e-2 x the model
size) from every other face are on free edges (no neighbour), not in a gap.  The model
gap is the largest remaining distance: an upper estimate (by at most half the sample
spacing) of how far a shared edge's two sides are apart.  Section chaining across faces
uses ``max(tol, model gap)`` (:func:`geomkit.plane_section`'s ``gap``).
"""

from __future__ import annotations

import numpy as np

from geomkit.nurbs.trimming import evaluate_trim_curve

__all__ = ["boundary_samples", "model_gap"]


def boundary_samples(surfaces, per_piece: int = 64):
    """``(points (m, 3), face index (m,), piece index (m,))`` along every face's trim boundary (the
    domain boundary of an untrimmed face)."""
    pts, ids, pcs = [], [], []
    npc = 0
    for k, s in enumerate(surfaces):
        if s.trim:
            uv = []
            for loop in s.trim:
                for c in loop.pieces:
                    p = c.degree
                    t = np.linspace(c.knots[p], c.knots[-p - 1], per_piece)
                    uv.append(evaluate_trim_curve(c, t)[:, 0, :])
                    pcs.append(np.full(per_piece, npc))
                    npc += 1
            uv = np.concatenate(uv)
        else:
            (a, b), (c0, d) = s.domain
            t = np.linspace(0, 1, per_piece)
            uv = np.concatenate([np.column_stack([a + (b - a) * t, np.full_like(t, c0)]),
                                 np.column_stack([np.full_like(t, b), c0 + (d - c0) * t]),
                                 np.column_stack([b - (b - a) * t, np.full_like(t, d)]),
                                 np.column_stack([np.full_like(t, a), d - (d - c0) * t])])
            pcs.append(np.repeat(np.arange(npc, npc + 4), per_piece))
            npc += 4
        (a, b), (c0, d) = s.domain
        uv = np.column_stack([np.clip(uv[:, 0], a, b), np.clip(uv[:, 1], c0, d)])
        pts.append(s.evaluate(uv))
        ids.append(np.full(len(uv), k))
    return np.concatenate(pts), np.concatenate(ids), np.concatenate(pcs)


def model_gap(surfaces, per_piece: int = 64, free: float | None = None) -> float:
    """Largest edge gap between neighbouring faces (see the module docstring); 0 for a
    single face."""
    from scipy.spatial import cKDTree

    if len(surfaces) < 2:
        return 0.0
    X, ids, pcs = boundary_samples(surfaces, per_piece)
    size = float(np.linalg.norm(X.max(axis=0) - X.min(axis=0)))
    free = 1e-3 * size if free is None else float(free)
    tree = cKDTree(X)
    n = len(X)
    d, j = tree.query(X, k=48, distance_upper_bound=free)
    best = np.full(n, np.inf)
    for col in range(d.shape[1]):
        jj = j[:, col]
        ok = jj < n
        ok[ok] &= ids[jj[ok]] != ids[ok]
        i = np.nonzero(ok)[0]
        jj = jj[i]
        dd = d[i, col]
        # distance to the neighbour's boundary polyline, not just its sample
        for nb in (jj - 1, jj + 1):
            nb = np.clip(nb, 0, n - 1)
            same = pcs[nb] == pcs[jj]
            A, B = X[jj], X[nb]
            AB = B - A
            L2 = np.einsum("ij,ij->i", AB, AB)
            t = np.where(L2 > 0, np.einsum("ij,ij->i", X[i] - A, AB) / np.where(L2 > 0, L2, 1), 0)
            t = np.clip(t, 0, 1)
            seg = np.linalg.norm(X[i] - (A + t[:, None] * AB), axis=1)
            dd = np.where(same, np.minimum(dd, seg), dd)
        best[i] = np.minimum(best[i], dd)
    best = best[np.isfinite(best)]
    return float(best.max()) if best.size else 0.0
