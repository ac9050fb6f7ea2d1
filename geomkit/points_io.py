"""Reading measured points: CSV / XYZ text (x, y, z with optional i, j, k) and STL / PLY.

Text files (``.csv``, ``.xyz``, ``.txt``, ``.asc``, ``.pts``) hold one point a line,
3 columns ``x y z`` or 6 columns ``x y z i j k`` (a measured normal or probe
direction), separated by commas, semicolons, tabs or spaces.  An optional header line
naming the columns (``x,y,z,i,j,k`` or ``x,y,z,nx,ny,nz``) and ``#`` comment lines are
allowed.  A row with a missing, non-numeric or non-finite value is an error naming its
line: measured data are never silently dropped.

STL and PLY files are read through trimesh; their vertices are the points (scans).

Files are only read, never modified.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .errors import FileFormatError, InvalidInputError

__all__ = ["PointSet", "read_points", "TEXT_FORMATS", "SCAN_FORMATS"]

TEXT_FORMATS = (".csv", ".xyz", ".txt", ".asc", ".pts")
SCAN_FORMATS = (".stl", ".ply")
_SPLIT = re.compile(r"[,;\s]+")
_NORMAL_NAMES = ({"i", "j", "k"}, {"nx", "ny", "nz"})


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


def _check_path(path) -> Path:
    p = Path(path)
    if not p.exists():
        raise FileFormatError(f"{p}: no such file")
    if p.is_dir():
        raise FileFormatError(f"{p}: is a directory, expected a point file")
    return p


def _read_text(p: Path) -> PointSet:
    try:
        text = p.read_text(encoding="utf-8-sig")
    except UnicodeDecodeError:
        raise FileFormatError(f"{p}: not a text file (expected x, y, z rows)") from None
    except OSError as exc:
        raise FileFormatError(f"{p}: cannot read ({exc.strerror or exc})") from None
    rows, lines = [], []
    ncol = None
    header_seen = False
    for lineno, raw in enumerate(text.splitlines(), start=1):
        line = raw.split("#", 1)[0].strip()
        if not line:
            continue
        fields = [f for f in _SPLIT.split(line) if f]
        if not rows and not header_seen:
            try:
                [float(f) for f in fields]
            except ValueError:
                names = [f.strip().strip('"').lower() for f in fields]
                if names[:3] != ["x", "y", "z"] or len(names) not in (3, 6) or \
                        (len(names) == 6 and set(names[3:]) not in _NORMAL_NAMES):
                    raise FileFormatError(
                        f"{p}: line {lineno}: header {line!r} not understood; expected "
                        "columns x, y, z or x, y, z, i, j, k") from None
                header_seen = True
                ncol = len(names)
                continue
        if ncol is None:
            if len(fields) not in (3, 6):
                raise FileFormatError(f"{p}: line {lineno}: expected 3 (x y z) or 6 "
                                      f"(x y z i j k) columns, got {len(fields)}")
            ncol = len(fields)
        if len(fields) != ncol:
            raise FileFormatError(f"{p}: line {lineno}: expected {ncol} columns, got "
                                  f"{len(fields)}")
        try:
            vals = [float(f) for f in fields]
        except ValueError:
            raise FileFormatError(f"{p}: line {lineno}: not a number in {line!r}") from None
        if not all(math.isfinite(v) for v in vals):
            raise FileFormatError(f"{p}: line {lineno}: non-finite value (NaN or inf) in "
                                  f"{line!r}")
        rows.append(vals)
        lines.append(lineno)
    if not rows:
        raise FileFormatError(f"{p}: no points (empty point set)")
    a = np.array(rows, dtype=np.float64)
    normals = None
    if a.shape[1] == 6:
        n = a[:, 3:]
        ln = np.linalg.norm(n, axis=1)
        if np.any(ln == 0):
            i = int(np.argmin(ln))
            raise FileFormatError(f"{p}: line {lines[i]}: zero normal vector (i, j, k)")
        normals = np.ascontiguousarray(n / ln[:, None])
    return PointSet(np.ascontiguousarray(a[:, :3]), normals, str(p))


def _read_scan(p: Path) -> PointSet:
    import trimesh

    try:
        obj = trimesh.load(str(p), process=False)
    except Exception as exc:  # trimesh raises many kinds on bad files
        raise FileFormatError(f"{p}: cannot read as {p.suffix[1:].upper()} ({exc})") from None
    if isinstance(obj, trimesh.Scene):
        geoms = list(obj.geometry.values())
        verts = [np.asarray(g.vertices) for g in geoms if hasattr(g, "vertices")]
        V = np.concatenate(verts) if verts else np.empty((0, 3))
    else:
        V = np.asarray(getattr(obj, "vertices", np.empty((0, 3))), dtype=np.float64)
    if V.ndim != 2 or V.shape[0] == 0:
        raise FileFormatError(f"{p}: no points (empty point set)")
    V = np.unique(V.reshape(-1, 3), axis=0)
    bad = ~np.isfinite(V).all(axis=1)
    if bad.any():
        raise FileFormatError(f"{p}: {int(bad.sum())} vertices with non-finite coordinates")
    return PointSet(np.ascontiguousarray(V), None, str(p))


def read_points(path) -> PointSet:
    """Read measured points from a text (CSV / XYZ) or scan (STL / PLY) file.

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
    p = _check_path(path)
    ext = p.suffix.lower()
    if ext in SCAN_FORMATS:
        return _read_scan(p)
    if ext in TEXT_FORMATS or ext == "":
        return _read_text(p)
    raise FileFormatError(f"{p}: unknown point file type {p.suffix!r}; use one of "
                          f"{', '.join(TEXT_FORMATS + SCAN_FORMATS)}")


def as_points(points, normals=None):
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
