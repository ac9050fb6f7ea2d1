"""What every projector shares: the checked query (points, ``max_distance``,
``chunk_size``, ``tol``), chunked streaming and the concatenated answer.  A projector
subclass gives ``surfaces``, ``size``, ``build_time``, ``approx_error`` and
``_chunk(P, max_distance, step_tol) -> Projection``."""

from __future__ import annotations

import math
import time

import numpy as np

from geomkit.errors import InvalidInputError
from geomkit.query import results as R
from geomkit.query.results import Projection
from geomkit.tolerances import NEWTON_STEP_TOL

__all__ = ["QueryBase", "empty_projection", "CHUNK_SIZE"]

CHUNK_SIZE = 1 << 16

_FIELDS = ("point", "uv", "surface", "distance", "signed_distance", "normal", "status",
           "lower_bound", "residual", "feet_tried")


def empty_projection(n: int) -> Projection:
    """``n`` rows answered BEYOND (NaN values, surface -1)."""
    nan3 = np.full((n, 3), np.nan)
    return Projection(point=nan3, uv=np.full((n, 2), np.nan),
                      surface=np.full(n, -1, dtype=np.int32),
                      distance=np.full(n, np.nan), signed_distance=np.full(n, np.nan),
                      normal=nan3.copy(), status=np.full(n, R.BEYOND, dtype=np.int8),
                      lower_bound=np.zeros(n), residual=np.full(n, np.nan),
                      feet_tried=np.zeros(n, dtype=np.int8), stats={})


class QueryBase:
    """Chunked, checked projection queries over a subclass's ``_chunk``."""

    surfaces: list
    size: float
    build_time: float
    approx_error: float

    @staticmethod
    def check_mesh_tol(mesh_tol) -> float:
        try:
            mesh_tol = float(mesh_tol)
        except (TypeError, ValueError):
            raise InvalidInputError(f"must be a finite number > 0, got {mesh_tol!r}",
                                    "mesh_tol") from None
        if not (math.isfinite(mesh_tol) and mesh_tol > 0):
            raise InvalidInputError(f"must be a finite number > 0, got {mesh_tol!r}",
                                    "mesh_tol")
        return mesh_tol

    def _chunk(self, P: np.ndarray, max_distance: float, step_tol: float) -> Projection:
        raise NotImplementedError

    def _stats(self) -> dict:
        """Whole-query stats added to :meth:`project`'s answer."""
        return {}

    def iter_project(self, points, max_distance: float | None = None,
                     chunk_size: int = CHUNK_SIZE, progress=None, tol: float | None = None):
        """Project in chunks, yielding one :class:`Projection` per chunk (bounded
        memory for any number of points, e.g. a ``numpy.memmap``)."""
        step_tol = NEWTON_STEP_TOL * self.size if tol is None else float(tol)
        if not (math.isfinite(step_tol) and step_tol > 0):
            raise InvalidInputError(f"must be a finite number > 0, got {tol!r}", "tol")
        arr = points if isinstance(points, np.ndarray) else np.asarray(points, dtype=float)
        if arr.ndim == 0 or arr.shape[-1] != 3:
            raise InvalidInputError(f"expected an array of shape (..., 3), got {arr.shape}",
                                    "points")
        arr = arr.reshape(-1, 3)
        md = np.inf if max_distance is None else float(max_distance)
        if math.isnan(md) or md < 0:
            raise InvalidInputError(f"must be a number >= 0, got {max_distance!r}",
                                    "max_distance")
        chunk_size = int(chunk_size)
        if chunk_size < 1:
            raise InvalidInputError(f"must be >= 1, got {chunk_size}", "chunk_size")
        n = arr.shape[0]
        for a in range(0, n, chunk_size):
            b = min(n, a + chunk_size)
            P = np.ascontiguousarray(arr[a:b], dtype=np.float64)
            bad = ~np.isfinite(P).all(axis=1)
            if bad.any():
                i = a + int(np.nonzero(bad)[0][0])
                raise InvalidInputError(f"non-finite coordinates in row {i}: "
                                        f"{arr[i].tolist()}", "points")
            yield self._chunk(P, md, step_tol)
            if progress is not None:
                progress(b, n)

    def project(self, points, max_distance: float | None = None,
                chunk_size: int = CHUNK_SIZE, progress=None,
                tol: float | None = None) -> Projection:
        """Project all points; see :func:`geomkit.project_points`."""
        t0 = time.perf_counter()
        parts = list(self.iter_project(points, max_distance, chunk_size, progress, tol))
        if not parts:
            out = empty_projection(0)
            out.stats = {"time": 0.0}
            return out
        out = Projection(*(np.concatenate([getattr(p, f) for p in parts])
                           for f in _FIELDS))
        keys = {k for p in parts for k in p.stats}
        out.stats = {k: sum(p.stats.get(k, 0) for p in parts) for k in sorted(keys)}
        # ``faces_failed``: face index -> why it has no candidate (left out of the
        # mesh, named by a FaceFailedWarning when it was built)
        out.stats.update(time=time.perf_counter() - t0, build_time=self.build_time,
                         approx_error=self.approx_error, **self._stats())
        return out
