"""Measured points in memory: :class:`PointSet` and :func:`read_points`.

Text files (CSV / XYZ) are parsed by :mod:`geomkit.exchange.text`; STL files are read
through trimesh (their unique vertices are the points); PLY, ``.npy`` and LAS / LAZ
scans through :mod:`geomkit.exchange.scans` (every vertex, in order).

Files are only read, never modified.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from geomkit.errors import FileFormatError, InvalidInputError
from geomkit.exchange.scans import iter_scan, mesh_vertices
from geomkit.exchange.text import TEXT_FORMATS, check_path, iter_text

__all__ = ["PointSet", "read_points", "as_measured_points", "TEXT_FORMATS", "SCAN_FORMATS"]

SCAN_FORMATS = (".stl", ".ply", ".npy", ".las", ".laz")


@dataclass(eq=False)
class PointSet:
    """Measured points.

    Attributes
    ----------
    points : (n, 3) float
    normals : (n, 3) float unit vectors, or None when the file has none.
    source : str, the file read.
    """

    points: np.ndarray
    normals: np.ndarray | None = None
    source: str = ""

    def __len__(self) -> int:
        return int(self.points.shape[0])


def _read_text(p: Path) -> PointSet:
    pts, nrm = [], []
    for P, N in iter_text(p):
        pts.append(P)
        nrm.append(N)
    if not pts:
        raise FileFormatError(f"{p}: no points (empty point set)")
    normals = None if nrm[0] is None else np.concatenate(nrm)
    return PointSet(np.concatenate(pts), normals, str(p))

def read_points(path) -> PointSet:
    """Read measured points from a text (CSV / XYZ) or scan (STL / PLY / NPY / LAS) file
(all in memory; :func:`geomkit.exchange.scans.iter_scan` streams).

    Parameters
    ----------
    path : str or Path

    Returns
    -------
    PointSet
        ``points`` (n, 3), n >= 1, all finite; ``normals`` (n, 3) unit vectors when
        the file has i, j, k columns, else None.

    Raises
    ------
    FileFormatError
        Missing file, unknown extension, malformed or non-finite rows (naming the
        line), or no points at all.
    """
    p = check_path(path)
    ext = p.suffix.lower()
    if ext in (".ply", ".npy", ".las", ".laz", ".e57"):
        parts = list(iter_scan(p))
        N = None if parts[0][1] is None else np.concatenate([c[1] for c in parts])
        return PointSet(np.concatenate([c[0] for c in parts]), N, str(p))
    if ext in SCAN_FORMATS:
        return PointSet(mesh_vertices(p), None, str(p))
    if ext in TEXT_FORMATS or ext == "":
        return _read_text(p)
    raise FileFormatError(f"{p}: unknown point file type {p.suffix!r}; use one of "
                          f"{', '.join(TEXT_FORMATS + SCAN_FORMATS)}")


def as_measured_points(points, normals=None):
    """Validate in-memory points (and optional normals) -> ``(n, 3)`` arrays."""
    P = np.asarray(points, dtype=np.float64)
    if P.ndim == 1 and P.shape[0] == 3:
        P = P[None, :]
    if P.ndim != 2 or P.shape[1] != 3:
        raise InvalidInputError(f"expected shape (n, 3), got {P.shape}", "points")
    if P.shape[0] == 0:
        raise InvalidInputError("empty point set", "points")
    bad = ~np.isfinite(P).all(axis=1)
    if bad.any():
        i = int(np.nonzero(bad)[0][0])
        raise InvalidInputError(f"non-finite coordinates in row {i}: {P[i].tolist()}",
                                "points")
    N = None
    if normals is not None:
        N = np.asarray(normals, dtype=np.float64)
        if N.shape != P.shape:
            raise InvalidInputError(f"expected shape {P.shape}, got {N.shape}", "normals")
        ln = np.linalg.norm(N, axis=1)
        if not np.all(np.isfinite(ln) & (ln > 0)):
            i = int(np.nonzero(~(np.isfinite(ln) & (ln > 0)))[0][0])
            raise InvalidInputError(f"zero or non-finite normal in row {i}", "normals")
        N = N / ln[:, None]
    return np.ascontiguousarray(P), N
