"""Streaming scan input: measured points read in chunks, memory bounded by the chunk.

Formats (by extension):

* ``.npy``: a float array of shape (n, 3) (x y z) or (n, 6) (x y z i j k), read chunk
  by chunk at its offset (plain reads rather than ``numpy.load(mmap_mode="r")``: the
  pages of a memory map stay resident and would grow the RSS to the file's size).
* ``.ply``: binary (little / big endian) or ASCII; the ``vertex`` element's ``x y z``
  (and ``nx ny nz`` when present) properties, read chunk by chunk.
* ``.las`` / ``.laz``: through laspy (``laspy[lazrs]`` for LAZ), scaled coordinates,
  read with laspy's chunk iterator; ``.e57``: every scan of the file through pye57,
  placed by its pose (:mod:`geomkit.exchange.scanlib`).  Their intensity and colours
  are kept (:func:`iter_scan_attrs`).
* text (``.csv .xyz .txt .asc .pts``): :func:`geomkit.exchange.points.iter_text` (headers,
  decimal commas, see :mod:`geomkit.exchange.points`).
* ``.stl``: read whole (its unique vertices, through trimesh); a mesh, not a scan.

Every reader checks its rows: a non-finite coordinate, a truncated file or a file with
no points is a :class:`~geomkit.FileFormatError` naming the file and the row.  Files
are only read, never modified.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from geomkit.errors import FileFormatError
from geomkit.exchange.scanlib import e57_length, iter_e57, iter_las, las_length
from geomkit.exchange.text import TEXT_FORMATS, check_path, iter_text

__all__ = ["iter_scan", "iter_scan_attrs", "scan_length", "STREAM_FORMATS",
           "DEFAULT_CHUNK"]

STREAM_FORMATS = (".npy", ".ply", ".las", ".laz", ".e57") + TEXT_FORMATS
DEFAULT_CHUNK = 1 << 16
"""Points per chunk (~10 MB of per-point results)."""

_PLY_TYPES = {"char": "i1", "int8": "i1", "uchar": "u1", "uint8": "u1", "short": "i2",
              "int16": "i2", "ushort": "u2", "uint16": "u2", "int": "i4", "int32": "i4",
              "uint": "u4", "uint32": "u4", "float": "f4", "float32": "f4",
              "double": "f8", "float64": "f8"}


# ------------------------------------------------------------------ PLY
def _ply_header(p: Path):
    """(format, header byte length, elements [(name, count, [(prop, type)] or None
    for lists)])."""
    with open(p, "rb") as fh:
        if fh.readline().strip() != b"ply":
            raise FileFormatError(f"{p}: not a PLY file (first line is not 'ply')")
        fmt, elements = None, []
        while True:
            raw = fh.readline()
            if not raw:
                raise FileFormatError(f"{p}: truncated PLY header (no end_header)")
            words = raw.decode("ascii", "replace").split()
            if not words or words[0] in ("comment", "obj_info"):
                continue
            line = " ".join(words)[:60]
            if words[0] == "format":
                if len(words) < 2:
                    raise FileFormatError(f"{p}: PLY header line {line!r}: no format")
                fmt = words[1]
            elif words[0] == "element":
                if len(words) != 3 or not (words[2].isascii() and words[2].isdigit()):
                    raise FileFormatError(f"{p}: PLY header line {line!r}: expected "
                                          "'element NAME COUNT'")
                elements.append((words[1], int(words[2]), []))
            elif words[0] == "property":
                if not elements:
                    raise FileFormatError(f"{p}: PLY property before any element")
                if len(words) >= 5 and words[1] == "list":
                    elements[-1][2].append((words[-1], None))
                elif len(words) == 3 and words[1] in _PLY_TYPES:
                    if words[2] in [q for q, _ in elements[-1][2]]:
                        raise FileFormatError(f"{p}: PLY property {words[2]!r} declared "
                                              "twice")
                    elements[-1][2].append((words[2], _PLY_TYPES[words[1]]))
                else:
                    raise FileFormatError(f"{p}: PLY header line {line!r}: expected "
                                          "'property TYPE NAME' with TYPE one of "
                                          + ", ".join(sorted(set(_PLY_TYPES))))
            elif words[0] == "end_header":
                return fmt, fh.tell(), elements
            else:
                raise FileFormatError(f"{p}: PLY header line {line!r} not understood")


def _ply_vertices(p: Path):
    """(kind, data, has_normals, n) where data is a memmap (binary) or the header
    length (ascii)."""
    fmt, hlen, elements = _ply_header(p)
    if fmt not in ("ascii", "binary_little_endian", "binary_big_endian"):
        raise FileFormatError(f"{p}: PLY format {fmt!r} not understood")
    if not elements or elements[0][0] != "vertex":
        raise FileFormatError(f"{p}: the PLY file's first element is not 'vertex'")
    _, n, props = elements[0]
    names = [q for q, _ in props]
    if not {"x", "y", "z"} <= set(names):
        raise FileFormatError(f"{p}: PLY vertices have no x, y, z properties")
    if n == 0:
        raise FileFormatError(f"{p}: no points (the PLY file has 0 vertices)")
    has_n = {"nx", "ny", "nz"} <= set(names)
    if fmt == "ascii":
        return "ascii", (hlen, names), has_n, n
    if any(t is None for _, t in props):
        raise FileFormatError(f"{p}: list property in the PLY vertex element")
    end = "<" if fmt == "binary_little_endian" else ">"
    dt = np.dtype([(q, end + t) for q, t in props])
    size = p.stat().st_size
    have = (size - hlen) // dt.itemsize
    if have < n:
        raise FileFormatError(f"{p}: truncated PLY file: the header declares {n} vertices, "
                              f"the file holds {have} (vertex {have} is incomplete)")
    return "binary", (hlen, dt), has_n, n


def _iter_ply(p: Path, chunk: int):
    kind, data, has_n, n = _ply_vertices(p)
    cols = ["x", "y", "z"] + (["nx", "ny", "nz"] if has_n else [])
    if kind == "binary":  # plain reads (see _iter_npy)
        hlen, dt = data
        with open(p, "rb") as fh:
            fh.seek(hlen)
            for a in range(0, n, chunk):
                rec = np.fromfile(fh, dtype=dt, count=min(chunk, n - a))
                yield a, np.column_stack([rec[c].astype(np.float64) for c in cols])
        return
    hlen, names = data
    idx = [names.index(c) for c in cols]
    with open(p, "rb") as fh:
        fh.seek(hlen)
        rows, a = [], 0
        for k in range(n):
            raw = fh.readline()
            if not raw:
                raise FileFormatError(f"{p}: truncated PLY file: the header declares {n} "
                                      f"vertices, the file holds {k}")
            f = raw.split()
            try:
                rows.append([float(f[i]) for i in idx])
            except (ValueError, IndexError):
                raise FileFormatError(f"{p}: vertex {k}: not {len(names)} numbers: "
                                      f"{raw.decode('ascii', 'replace').strip()!r}") from None
            if len(rows) == chunk:
                yield a, np.array(rows)
                a += len(rows)
                rows = []
        if rows:
            yield a, np.array(rows)


# ------------------------------------------------------------------ NumPy
def _npy(p: Path):
    """(shape, dtype, fortran_order, data offset) of a .npy file, checked."""
    from numpy.lib import format as npf

    try:
        with open(p, "rb") as fh:
            version = npf.read_magic(fh)
            read = npf.read_array_header_1_0 if version == (1, 0) else \
                npf.read_array_header_2_0
            shape, fortran, dtype = read(fh)
            offset = fh.tell()
    except Exception as exc:
        raise FileFormatError(f"{p}: cannot read as .npy ({exc})") from None
    if len(shape) != 2 or shape[1] not in (3, 6) or dtype.kind not in "fiu":
        raise FileFormatError(f"{p}: expected a numeric array of shape (n, 3) or (n, 6), "
                              f"got {dtype} {shape}")
    if shape[0] == 0:
        raise FileFormatError(f"{p}: no points (empty array)")
    have = (p.stat().st_size - offset) // (dtype.itemsize * shape[1])
    if have < shape[0]:
        raise FileFormatError(f"{p}: truncated .npy file: the header declares {shape[0]} "
                              f"rows, the file holds {have}")
    return shape, dtype, fortran, offset


def _iter_npy(p: Path, chunk: int):
    shape, dtype, fortran, offset = _npy(p)
    if fortran:  # column-major: a memory map reads each chunk's columns
        A = np.load(p, mmap_mode="r")
        for a in range(0, shape[0], chunk):
            yield a, np.array(A[a:a + chunk], dtype=np.float64)
        return
    # plain reads, not a memory map: mapped pages would stay resident (they count in
    # the process's RSS until the kernel needs them), reads keep only the chunk
    with open(p, "rb") as fh:
        fh.seek(offset)
        for a in range(0, shape[0], chunk):
            m = min(chunk, shape[0] - a)
            A = np.fromfile(fh, dtype=dtype, count=m * shape[1])
            yield a, A.reshape(m, shape[1]).astype(np.float64, copy=False)


# ------------------------------------------------------------------ public
def scan_length(path) -> int | None:
    """Number of points of a scan file when its header says it (``.npy``, PLY, LAS,
    E57: invalid points included), else None (text files are not counted ahead)."""
    p = check_path(path)
    ext = p.suffix.lower()
    if ext == ".npy":
        return int(_npy(p)[0][0])
    if ext == ".ply":
        return int(_ply_vertices(p)[3])
    if ext in (".las", ".laz"):
        return las_length(p)
    if ext == ".e57":
        return e57_length(p)
    return None


def _check_chunk(p, a, A, what="row"):
    bad = ~np.isfinite(A).all(axis=1)
    if bad.any():
        i = int(np.nonzero(bad)[0][0])
        raise FileFormatError(f"{p}: {what} {a + i}: non-finite value (NaN or inf): "
                              f"{A[i].tolist()}")


def _normals(p, a, A, what):
    N = A[:, 3:6]
    ln = np.linalg.norm(N, axis=1)
    if np.any(ln == 0):
        i = int(np.argmin(ln))
        raise FileFormatError(f"{p}: {what} {a + i}: zero normal vector")
    return np.ascontiguousarray(N / ln[:, None])


def mesh_vertices(p: Path) -> np.ndarray:
    """The unique vertices (n, 3) of a mesh file (STL) read through trimesh."""
    import trimesh  # heavy: loaded when a mesh file is read

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
    return np.ascontiguousarray(V)


def iter_scan(path, chunk_size: int = DEFAULT_CHUNK):
    """Read a scan in chunks of at most ``chunk_size`` points, in file order.

    Parameters
    ----------
    path : str or Path
        ``.npy``, ``.ply``, ``.las`` / ``.laz``, ``.e57``, CSV / XYZ text or ``.stl``.
    chunk_size : int >= 1

    Yields
    ------
    (points (m, 3) float, normals (m, 3) unit float or None)
        Rows are 0-based indices in file order: chunk k starts at the sum of the
        earlier chunks' lengths.  At least one point in all (else an error).

    Raises
    ------
    FileFormatError
        Unknown type, truncated file, a non-finite value or a zero normal (naming the
        row, 0-based for binary formats, the line for text), no points.
    """
    for P, N, _ in iter_scan_attrs(path, chunk_size):
        yield P, N


def iter_scan_attrs(path, chunk_size: int = DEFAULT_CHUNK):
    """:func:`iter_scan` with each chunk's per-point attributes: yields ``(points,
    normals or None, attributes)``, ``attributes`` a dict of (m,) arrays
    (``intensity``, ``red``, ``green``, ``blue`` from LAS / LAZ / E57 files that have
    them; empty for the other formats), the same columns in every chunk."""
    p = check_path(path)
    chunk = int(chunk_size)
    if chunk < 1:
        raise FileFormatError(f"chunk size must be >= 1, got {chunk}")
    ext = p.suffix.lower()
    if ext in TEXT_FORMATS or ext == "":
        count = 0
        for P, N in iter_text(p, chunk):
            count += P.shape[0]
            yield P, N, {}
        if count == 0:
            raise FileFormatError(f"{p}: no points (empty point set)")
        return
    if ext == ".stl":
        V = mesh_vertices(p)
        for a in range(0, len(V), chunk):
            yield V[a:a + chunk], None, {}
        return
    if ext == ".npy":
        it, what = _plain(_iter_npy(p, chunk)), "row"
    elif ext == ".ply":
        it, what = _plain(_iter_ply(p, chunk)), "vertex"
    elif ext in (".las", ".laz"):
        it, what = iter_las(p, chunk), "point"
    elif ext == ".e57":
        it, what = iter_e57(p, chunk), "point"
    else:
        raise FileFormatError(f"{p}: unknown scan file type {p.suffix!r}; use one of "
                              f"{', '.join(STREAM_FORMATS + ('.stl',))}")
    for a, A, attrs in it:
        _check_chunk(p, a, A, what)
        N = _normals(p, a, A, what) if A.shape[1] == 6 else None
        yield np.ascontiguousarray(A[:, :3]), N, attrs


def _plain(it):
    for a, A in it:
        yield a, A, {}


def is_scan_file(path) -> bool:
    """A file :func:`iter_scan` reads (by extension)."""
    ext = Path(path).suffix.lower()
    return ext in STREAM_FORMATS or ext == ".stl"

