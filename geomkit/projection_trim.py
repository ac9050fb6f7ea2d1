"""Trim data of the projector: trim-boundary triangles of the candidate mesh and
samples on the trim curves' images that seed the trim-boundary Newton."""

from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree

from ._kernels import trim_feet as _tf
from .evaluation import evaluate
from .trimming import _segments
from .types import Surface

TRIM_SAMPLES = 32
"""Samples per trim segment that seed the trim-boundary Newton."""
TRIM_STARTS = 3
"""Trim-boundary Newton starts per point: from its nearest boundary samples."""


def _trim_boundary_triangles(mesh, trimmed) -> np.ndarray:
    """(m,) bool: triangles of trimmed faces with an edge on the mesh boundary.

    Their deviation bound must also carry the trim polyline's 3-D chord error
    (:data:`geomkit.projection.PROJ_TRIM_TARGET` times the mesh tolerance): along a trim
    curve the face runs past the mesh (outer loops) or the mesh past the face (over a
    hole), so ``d(x, t) + e_t`` measured on the parametric gap alone is no upper bound
    of the distance to the trimmed face there — it pruned the nearest face of a real
    part (a disk above a plate's hole)."""
    F = mesh.faces
    on = trimmed[mesh.face_surface] != 0
    out = np.zeros(F.shape[0], bool)
    if not on.any():
        return out
    idx = np.flatnonzero(on)
    E = np.sort(np.stack([F[idx][:, [0, 1]], F[idx][:, [1, 2]], F[idx][:, [2, 0]]],
                         axis=1), axis=2).reshape(-1, 2)  # (3k, 2), vertex ids
    _, inv, cnt = np.unique(E, axis=0, return_inverse=True, return_counts=True)
    single = (cnt[inv.ravel()] == 1).reshape(-1, 3)
    out[idx] = single.any(axis=1)
    return out



class _TrimData:
    """Trim segments of one surface and dense samples on their images."""

    def __init__(self, s: Surface):
        seg, deg, _, _ = _segments(s)
        self.seg = np.ascontiguousarray(seg)
        self.deg = deg
        M = seg.shape[0] * TRIM_SAMPLES
        uv = np.empty((M, 2))
        self.samp_seg = np.empty(M, dtype=np.int64)
        self.samp_t = np.empty(M)
        _tf.trim_samples(self.seg, deg, TRIM_SAMPLES, uv, self.samp_seg, self.samp_t)
        (u0, u1), (v0, v1) = s.domain
        uv[:, 0] = np.clip(uv[:, 0], u0, u1)
        uv[:, 1] = np.clip(uv[:, 1], v0, v1)
        self.samp_xyz = np.ascontiguousarray(evaluate(s, uv))
        self.tree = cKDTree(self.samp_xyz)

    def nearest_samples(self, P):
        """Indices (n, 3) of the :data:`TRIM_STARTS` boundary samples nearest to each
        point (-1 where there are fewer samples)."""
        k = min(TRIM_STARTS, self.samp_xyz.shape[0])
        _, idx = self.tree.query(P, k=k)
        near = np.full((P.shape[0], TRIM_STARTS), -1, dtype=np.int64)
        near[:, :k] = np.asarray(idx, dtype=np.int64).reshape(P.shape[0], k)
        return near
