"""Scans read through other libraries, chunk by chunk, with the per-point attributes
they carry: LAS / LAZ through laspy, E57 (ASTM E2807) through pye57 (both in the
``scale`` extra).

Each reader yields ``(offset, coordinates (m, 3) float64, attributes)`` where
``attributes`` maps a column name to an (m,) array: ``intensity`` and ``red``,
``green``, ``blue`` where the file has them (LAS: its point format's fields; E57: the
fields every scan of the file has).  A library's exception on a damaged file becomes a
:class:`~geomkit.FileFormatError` naming the file and the point.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from geomkit.errors import FileFormatError, MissingDependencyError

__all__ = ["iter_las", "iter_e57", "las_length", "e57_length"]

_E57_ATTRS = {"intensity": "intensity", "colorRed": "red", "colorGreen": "green",
              "colorBlue": "blue"}
_CARTESIAN = ("cartesianX", "cartesianY", "cartesianZ")
_SPHERICAL = ("sphericalRange", "sphericalAzimuth", "sphericalElevation")


# ------------------------------------------------------------------ LAS / LAZ
def _laspy():
    try:
        import laspy
    except ImportError:
        raise MissingDependencyError("reading LAS/LAZ needs laspy: pip install "
                                     "geomkit[scale]") from None
    return laspy


def _check_las_header(p: Path) -> tuple[int, bool]:
    """The LAS public header block's sizes, checked against the file before laspy
    reads it: a damaged count (of variable-length records, of points) would have laspy
    allocate or loop for as many as it says.  Returns (point count, compressed)."""
    import struct

    size = p.stat().st_size
    with open(p, "rb") as fh:
        head = fh.read(227)
    if len(head) < 227 or head[:4] != b"LASF":
        raise FileFormatError(f"{p}: not a LAS/LAZ file (no 'LASF' header of 227 bytes)")
    hsize, offset, nvlr = struct.unpack_from("<HII", head, 94)
    fmt, rlen, count = head[104] & 0x3F, struct.unpack_from("<H", head, 105)[0], \
        struct.unpack_from("<I", head, 107)[0]
    if head[24] == 1 and head[25] >= 4 and hsize >= 375 and size >= 255:
        with open(p, "rb") as fh:
            fh.seek(247)
            count = max(count, struct.unpack("<Q", fh.read(8))[0])
    if not 227 <= hsize <= offset <= size:
        raise FileFormatError(f"{p}: LAS header: header size {hsize} and point data "
                              f"offset {offset} do not fit in the file ({size} bytes)")
    if nvlr * 54 > offset - hsize:
        raise FileFormatError(f"{p}: LAS header: {nvlr} variable-length records cannot fit "
                              f"in the {offset - hsize} bytes before the points")
    if fmt > 10 or rlen == 0:
        raise FileFormatError(f"{p}: LAS header: point format {fmt} with records of "
                              f"{rlen} bytes")
    compressed = bool(head[104] & 0x80)
    if not compressed and count * rlen > size - offset:
        raise FileFormatError(f"{p}: truncated LAS file: the header declares {count} "
                              f"points of {rlen} bytes, the file holds "
                              f"{(size - offset) // rlen}")
    return int(count), compressed


def las_length(p: Path) -> int:
    count, compressed = _check_las_header(p)
    if compressed:  # the count from the header: no decompressor in this process
        return count
    try:
        with _laspy().open(str(p)) as fh:
            return int(fh.header.point_count)
    except MissingDependencyError:
        raise
    except Exception as exc:  # laspy raises its own and OS errors
        raise FileFormatError(f"{p}: cannot read as LAS/LAZ ({exc})") from None


def iter_las(p: Path, chunk: int):
    laspy = _laspy()
    if _check_las_header(p)[1]:
        yield from _iter_laz(p, chunk)
        return
    try:
        fh = laspy.open(str(p))
    except Exception as exc:  # laspy raises its own and OS errors
        raise FileFormatError(f"{p}: cannot read as LAS/LAZ ({exc})") from None
    with fh:
        n = int(fh.header.point_count)
        if n == 0:
            raise FileFormatError(f"{p}: no points (the LAS header declares 0 points)")
        dims = set(fh.header.point_format.dimension_names)
        names = [d for d in ("intensity", "red", "green", "blue") if d in dims]
        a = 0
        try:
            for pts in fh.chunk_iterator(chunk):
                P = np.column_stack([np.asarray(pts.x, dtype=np.float64),
                                     np.asarray(pts.y, dtype=np.float64),
                                     np.asarray(pts.z, dtype=np.float64)])
                attrs = {d: np.array(pts[d]) for d in names}
                yield a, P, attrs
                a += P.shape[0]
        except FileFormatError:
            raise
        except Exception as exc:
            raise FileFormatError(f"{p}: cannot read point {a} onwards ({exc})") from None
        if a < n:
            raise FileFormatError(f"{p}: truncated LAS file: the header declares {n} points, "
                                  f"read {a}")


def _iter_laz(p: Path, chunk: int):
    """A compressed file, decompressed in a child process
    (:mod:`geomkit.exchange.lazchild`): a decompressor that aborts ends the child."""
    import json
    import os
    import subprocess
    import sys

    proc = subprocess.Popen([sys.executable, "-m", "geomkit.exchange.lazchild", str(p),
                             str(chunk)], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            env={**os.environ, "RUST_BACKTRACE": "0"})
    a = 0
    try:
        head = json.loads(proc.stdout.readline() or b"{}")
        if "error" in head or "fields" not in head:
            raise FileFormatError(f"{p}: cannot read as LAS/LAZ "
                                  f"({head.get('error', 'the decompressor stopped')})")
        n = head["n"]
        if n == 0:
            raise FileFormatError(f"{p}: no points (the LAS header declares 0 points)")
        dt = np.dtype([tuple(f) for f in head["fields"]])
        names = [f[0] for f in head["fields"][3:]]
        while True:
            raw = proc.stdout.read(8)
            if len(raw) < 8:
                break
            m = int.from_bytes(raw, "little")
            body = proc.stdout.read(m * dt.itemsize)
            if len(body) < m * dt.itemsize:
                break
            rec = np.frombuffer(body, dt)
            yield a, np.column_stack([rec["x"], rec["y"], rec["z"]]), \
                {d: rec[d].copy() for d in names}
            a += m
        code = proc.wait()
        if code != 0:
            why = [ln for ln in proc.stderr.read().decode("utf-8", "replace").splitlines()
                   if ln.strip() and not ln.startswith("note:")]
            raise FileFormatError(f"{p}: the LAZ decompressor failed at point {a} "
                                  f"(exit {code}{': ' + why[-1][:200] if why else ''}): "
                                  "the file is corrupt")
        if a < n:
            raise FileFormatError(f"{p}: truncated LAZ file: the header declares {n} "
                                  f"points, read {a}")
    finally:
        if proc.poll() is None:
            proc.kill()
        proc.wait()
        proc.stdout.close()
        proc.stderr.close()


# ------------------------------------------------------------------ E57
def _pye57():
    try:
        import pye57
    except ImportError:
        raise MissingDependencyError("reading E57 needs pye57: pip install "
                                     "geomkit[scale]") from None
    return pye57


def _open_e57(p: Path):
    pye57 = _pye57()
    try:
        f = pye57.E57(str(p))
        n = f.scan_count
    except Exception as exc:  # libe57's exceptions (and OS errors) on a damaged file
        raise FileFormatError(f"{p}: cannot read as E57 ({_short(exc)})") from None
    if n == 0:
        f.close()
        raise FileFormatError(f"{p}: no scans (the E57 file's data3D is empty)")
    return f, n


def _short(exc) -> str:
    """libe57's message without its debug dump."""
    text = " ".join(str(exc).split("****")[0].split())
    return text[:200] or type(exc).__name__


def _scan_layout(p, f, k):
    """(header, coordinate fields, invalid-state field or None) of scan ``k``."""
    try:
        h = f.get_header(k)
        fields = set(h.point_fields)
    except Exception as exc:
        raise FileFormatError(f"{p}: scan {k}: cannot read its header ({_short(exc)})") \
            from None
    if set(_CARTESIAN) <= fields:
        coords, state = _CARTESIAN, "cartesianInvalidState"
    elif set(_SPHERICAL) <= fields:
        coords, state = _SPHERICAL, "sphericalInvalidState"
    else:
        raise FileFormatError(f"{p}: scan {k}: no cartesian or spherical coordinates "
                              f"(fields: {', '.join(sorted(fields)) or 'none'})")
    return h, coords, state if state in fields else None, fields


def e57_length(p: Path) -> int:
    """Points stored in every scan of the file (points flagged invalid included)."""
    f, n = _open_e57(p)
    try:
        return sum(int(_scan_layout(p, f, k)[0].point_count) for k in range(n))
    except FileFormatError:
        raise
    except Exception as exc:
        raise FileFormatError(f"{p}: cannot read as E57 ({_short(exc)})") from None
    finally:
        f.close()


def _pose(h):
    """(R, t) of a scan's pose (identity when it has none)."""
    if not h.has_pose():
        return None, None
    R = np.asarray(h.rotation_matrix, dtype=np.float64)
    t = np.asarray(h.translation, dtype=np.float64)
    return R, t


def iter_e57(p: Path, chunk: int):
    """Every scan of an E57 file in order, each placed by its pose into the file's
    frame; spherical coordinates converted; points whose invalid state is set (no
    coordinates measured) skipped.  Attributes: those every scan has."""
    f, nscans = _open_e57(p)
    try:
        layouts = [_scan_layout(p, f, k) for k in range(nscans)]
        common = set.intersection(*(L[3] for L in layouts))
        attrs = [a for a in _E57_ATTRS if a in common]
        a = 0
        for k, (h, coords, state, _) in enumerate(layouts):
            wanted = list(coords) + ([state] if state else []) + attrs
            R, t = _pose(h)
            try:
                data, bufs = f.make_buffers(wanted, chunk)
                reader = h.points.reader(bufs)
            except Exception as exc:
                raise FileFormatError(f"{p}: scan {k}: cannot read its points "
                                      f"({_short(exc)})") from None
            try:
                while True:
                    try:
                        m = int(reader.read())
                    except Exception as exc:
                        raise FileFormatError(f"{p}: scan {k}: cannot read point {a} "
                                              f"onwards ({_short(exc)})") from None
                    if m == 0:
                        break
                    X = np.column_stack([np.array(data[c][:m], dtype=np.float64)
                                         for c in coords])
                    if coords is _SPHERICAL:
                        r, az, el = X[:, 0], X[:, 1], X[:, 2]
                        X = np.column_stack([r * np.cos(el) * np.cos(az),
                                             r * np.cos(el) * np.sin(az), r * np.sin(el)])
                    keep = None if state is None else data[state][:m] == 0
                    if R is not None:
                        X = X @ R.T + t
                    A = {_E57_ATTRS[c]: np.array(data[c][:m]) for c in attrs}
                    if keep is not None and not keep.all():
                        X = X[keep]
                        A = {c: v[keep] for c, v in A.items()}
                    if X.shape[0]:
                        yield a, X, A
                        a += X.shape[0]
            finally:
                try:
                    reader.close()
                except Exception:  # noqa: BLE001 - a damaged file's reader
                    pass
        if a == 0:
            raise FileFormatError(f"{p}: no points (no valid point in its {nscans} scan(s))")
    finally:
        f.close()
