"""Text point files: CSV / XYZ (x, y, z with optional i, j, k), read in chunks.

Text files (``.csv``, ``.xyz``, ``.txt``, ``.asc``, ``.pts``) hold one point a line,
3 columns ``x y z`` or 6 columns ``x y z i j k`` (a measured normal or probe
direction), separated by commas, semicolons, tabs or spaces, and ``#`` comment lines.

* A header line names the columns: ``x, y, z`` are required, ``i, j, k`` or ``nx, ny,
  nz`` are the normals, any other column (``id``, ``name``, ...) is ignored, in any
  order (``id,x,y,z``, ``name x y z``, ``x;y;z;nx;ny;nz``).
* Decimal commas (European CMM exports) are read as decimal commas when the columns
  are separated by semicolons, tabs or blanks: ``50,5 0,0 50,0`` and ``50,5;0,0;50,0``
  are the point (50.5, 0, 50).  A row that would be ambiguous -- commas as both
  separator and decimal mark, ``50,5,0,0,50,0`` -- is read with comma separators (six
  columns); a decimal point in a file read with decimal commas is an error.

A row with a missing, non-numeric or non-finite value is an error naming its line:
measured data are never silently dropped.  Files are only read, never modified.
"""

from __future__ import annotations

import math
import re
from pathlib import Path

import numpy as np

from geomkit.errors import FileFormatError

__all__ = ["TEXT_FORMATS", "check_path", "iter_text", "read_int_column"]

TEXT_FORMATS = (".csv", ".xyz", ".txt", ".asc", ".pts")
_SPLIT = re.compile(r"[,;\s]+")


def check_path(path) -> Path:
    """``path`` as a Path; FileFormatError if it is missing or a directory."""
    p = Path(path)
    if not p.exists():
        raise FileFormatError(f"{p}: no such file")
    if p.is_dir():
        raise FileFormatError(f"{p}: is a directory, expected a point file")
    return p


class _TextLayout:
    """How the rows of a text point file are split and which columns are used."""

    def __init__(self, split, decimal_comma, ncol, cols, has_normals):
        self.split = split              # callable: line -> list of fields
        self.decimal_comma = decimal_comma
        self.ncol = ncol                # fields per row
        self.cols = cols                # indices of x, y, z[, i, j, k]
        self.has_normals = has_normals


_WS = re.compile(r"\s+")
_NOT_COMMA = re.compile(r"[;\s]+")
_DC_NUMBER = re.compile(r"^[+-]?(\d+,\d*|,\d+|\d+)([eE][+-]?\d+)?$")


def _fields(pattern):
    if pattern is None:
        return lambda line: _WS.split(line.strip())
    return lambda line: [f.strip() for f in pattern.split(line)]


def _is_number(f: str) -> bool:
    try:
        float(f)
    except ValueError:
        return False
    return True


def _header_layout(p, lineno, line) -> _TextLayout:
    """Columns named by a header line: x, y, z required, i, j, k or nx, ny, nz
    optional, any other column (id, name, ...) ignored."""
    if ";" in line:
        pat = re.compile(";")
    elif "," in line:
        pat = re.compile(",")
    elif "\t" in line:
        pat = re.compile("\t")
    else:
        pat = None
    names = [f.strip().strip('"').strip("'").strip().lower() for f in _fields(pat)(line)]
    idx = {}
    for k, n in enumerate(names):
        if n in idx:
            raise FileFormatError(f"{p}: line {lineno}: header names column {n!r} twice")
        idx[n] = k
    if not {"x", "y", "z"} <= idx.keys():
        raise FileFormatError(
            f"{p}: line {lineno}: header {line!r} not understood; expected columns "
            "named x, y, z (and optionally i, j, k or nx, ny, nz; other columns such as "
            "id or name are ignored)")
    cols = [idx["x"], idx["y"], idx["z"]]
    has_n = False
    for group in (("i", "j", "k"), ("nx", "ny", "nz")):
        if all(g in idx for g in group):
            cols += [idx[g] for g in group]
            has_n = True
            break
    # with ; tab or blank separators a comma can only be a decimal comma
    dc = "auto" if pat is None or pat.pattern != "," else False
    return _TextLayout(_fields(pat), dc, len(names), tuple(cols), has_n)


def _data_layout(p, lineno, line) -> _TextLayout:
    """Layout from the first data row (no header): 3 or 6 numeric columns.

    Decimal commas: when the row splits on semicolons / blanks (not commas) into 3 or 6
    fields that are all numbers written with a decimal comma (``50,5 0,0 50,0`` or
    ``50,5;0,0;50,0``), the file is read with decimal commas."""
    f = [x for x in _NOT_COMMA.split(line.strip()) if x]
    if len(f) in (3, 6) and any("," in x for x in f) and \
            all(_DC_NUMBER.match(x) for x in f):
        return _TextLayout(lambda s: [x for x in _NOT_COMMA.split(s.strip()) if x], True,
                           len(f), tuple(range(len(f))), len(f) == 6)
    fields = [x for x in _SPLIT.split(line) if x]
    if len(fields) not in (3, 6):
        raise FileFormatError(f"{p}: line {lineno}: expected 3 (x y z) or 6 "
                              f"(x y z i j k) columns, got {len(fields)}")
    return _TextLayout(lambda s: [x for x in _SPLIT.split(s) if x], False, len(fields),
                       tuple(range(len(fields))), len(fields) == 6)


def _sniff(p, lineno, line) -> _TextLayout:
    fields = [f for f in _SPLIT.split(line) if f]
    if all(_is_number(f) for f in fields):
        return _data_layout(p, lineno, line)
    dc = [x for x in _NOT_COMMA.split(line.strip()) if x]
    if all(_DC_NUMBER.match(x) for x in dc):
        return _data_layout(p, lineno, line)
    return _header_layout(p, lineno, line)


def _parse_row(p, lineno, line, lay: _TextLayout):
    fields = lay.split(line)
    if len(fields) != lay.ncol:
        raise FileFormatError(f"{p}: line {lineno}: expected {lay.ncol} columns, got "
                              f"{len(fields)}")
    picked = [fields[c] for c in lay.cols]
    if lay.decimal_comma == "auto":
        picked = [f.replace(",", ".") if "." not in f else f for f in picked]
    elif lay.decimal_comma:
        if any("." in f for f in picked):
            raise FileFormatError(f"{p}: line {lineno}: decimal point in a file read "
                                  f"with decimal commas: {line!r}")
        picked = [f.replace(",", ".") for f in picked]
    try:
        vals = [float(f) for f in picked]
    except ValueError:
        raise FileFormatError(f"{p}: line {lineno}: not a number in {line!r}") from None
    if not all(math.isfinite(v) for v in vals):
        raise FileFormatError(f"{p}: line {lineno}: non-finite value (NaN or inf) in "
                              f"{line!r}")
    return vals


def _finish_rows(p, rows, lines, has_normals):
    a = np.array(rows, dtype=np.float64).reshape(len(rows), 6 if has_normals else 3)
    normals = None
    if has_normals:
        n = a[:, 3:]
        ln = np.linalg.norm(n, axis=1)
        if np.any(ln == 0):
            i = int(np.argmin(ln))
            raise FileFormatError(f"{p}: line {lines[i]}: zero normal vector (i, j, k)")
        normals = np.ascontiguousarray(n / ln[:, None])
    return np.ascontiguousarray(a[:, :3]), normals


def iter_text(path, chunk_size: int = 1 << 16):
    """Read a text point file in chunks of at most ``chunk_size`` rows.

    Yields
    ------
    (points (m, 3), normals (m, 3) or None)
        Rows in file order; a malformed row raises :class:`FileFormatError` naming
        its line (the rows before it have been yielded).
    """
    p = check_path(path)
    try:
        fh = open(p, encoding="utf-8-sig", newline=None)
    except OSError as exc:
        raise FileFormatError(f"{p}: cannot read ({exc.strerror or exc})") from None
    lay = None
    rows, lines = [], []
    with fh:
        lineno = 0
        while True:
            try:
                raw = fh.readline()
            except UnicodeDecodeError:
                raise FileFormatError(f"{p}: line {lineno + 1}: not text (expected "
                                      "x, y, z rows)") from None
            if not raw:
                break
            lineno += 1
            line = raw.split("#", 1)[0].strip()
            if not line:
                continue
            if lay is None:
                lay = _sniff(p, lineno, line)
                if not _is_data(line, lay):
                    continue
            rows.append(_parse_row(p, lineno, line, lay))
            lines.append(lineno)
            if len(rows) >= chunk_size:
                yield _finish_rows(p, rows, lines, lay.has_normals)
                rows, lines = [], []
    if rows:
        yield _finish_rows(p, rows, lines, lay.has_normals)


def _is_data(line, lay) -> bool:
    """The line the layout was sniffed from is a data row (not a header)."""
    return lay.decimal_comma is True or all(_is_number(f) for f in _SPLIT.split(line) if f)


def read_int_column(path, name: str):
    """The integer column ``name`` of a text point file with a header (e.g. the
    ``face`` column of ``geomkit sample``), one value per data row in file order;
    None when the file has no header naming it.  A value that is not an integer is
    a :class:`FileFormatError` naming its line."""
    p = check_path(path)
    if p.suffix.lower() not in TEXT_FORMATS and p.suffix:
        return None
    want = name.lower()
    out, col, lay = [], None, None
    try:
        fh = open(p, encoding="utf-8-sig", newline=None)
    except OSError as exc:
        raise FileFormatError(f"{p}: cannot read ({exc.strerror or exc})") from None
    with fh:
        for lineno, raw in enumerate(fh, 1):
            line = raw.split("#", 1)[0].strip()
            if not line:
                continue
            if lay is None:
                lay = _sniff(p, lineno, line)
                if _is_data(line, lay):
                    return None                       # no header: no named columns
                names = [f.strip().strip('"').strip("'").strip().lower()
                         for f in lay.split(line)]
                if want not in names:
                    return None
                col = names.index(want)
                continue
            fields = lay.split(line)
            try:
                v = fields[col]
                iv = int(v)
            except (IndexError, ValueError):
                raise FileFormatError(f"{p}: line {lineno}: column {name!r} is not an "
                                      f"integer in {line!r}") from None
            out.append(iv)
    return None if col is None else np.asarray(out, dtype=np.int64)
