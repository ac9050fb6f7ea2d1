"""The IGES file itself: global section (separators, units, resolution) and the
parameter records of the P section, every value kept as written."""

from __future__ import annotations

from pathlib import Path

from geomkit.errors import FileFormatError

def real(x: str) -> float:
    """An IGES real as written (``1.5D2``, ``1.5E2`` or empty for 0)."""
    return float(x.replace("D", "E").replace("d", "e")) if x else 0.0


def integer(x: str) -> int:
    """An IGES integer as written (``3``, ``3.`` or empty for 0)."""
    return int(float(x)) if x else 0


UNIT_FLAGS = {1: "in", 2: "mm", 4: "ft", 5: "mi", 6: "m", 7: "km", 8: "mil", 9: "um",
              10: "cm", 11: "uin"}
"""IGES global parameter 14 (unit flag) to a unit name."""
_UNIT_NAMES = {"IN": "in", "INCH": "in", "MM": "mm", "FT": "ft", "MI": "mi", "M": "m",
               "KM": "km", "MIL": "mil", "UM": "um", "MICRON": "um", "CM": "cm",
               "UIN": "uin"}


def _global_fields(glob: str, psep: str, rsep: str) -> list:
    """The global section's fields, Hollerith strings (``3HABC``) decoded."""
    out, k, n = [], 0, len(glob)
    while k < n:
        j = k
        while j < n and glob[j] in "0123456789":
            j += 1
        if j < n and j > k and glob[j] == "H":
            m = int(glob[k:j])
            out.append(glob[j + 1: j + 1 + m])
            k = j + 1 + m
        else:
            e = k
            while e < n and glob[e] not in (psep, rsep):
                e += 1
            out.append(glob[k:e].strip())
            k = e
        if k < n and glob[k] == rsep:
            break
        k += 1
    return out


class Entry:
    """One directory entry: ``d`` holds the fields the reader uses
    (``entity_type_number``, ``transform``, ``status_number``, ``form_number``)."""

    __slots__ = ("sequence_number", "d")

    def __init__(self, seq: int, d: dict):
        self.sequence_number, self.d = seq, d

    def __repr__(self) -> str:
        return f"Entry({self.d['entity_type_number']}@{self.sequence_number})"


def directory(path: Path, lines: list | None = None) -> dict:
    """``{DE sequence number: Entry}`` from the D section (two 80-column lines per
    entity; fields of 8 columns)."""
    if lines is None:
        lines = path.read_text(encoding="latin-1").splitlines()
    dl = [ln for ln in lines if len(ln) >= 73 and ln[72] == "D"]
    if len(dl) % 2:
        raise FileFormatError(f"{path}: directory section has an odd number of lines "
                              f"({len(dl)}); each entity takes two")
    out = {}
    for a, b in zip(dl[::2], dl[1::2]):
        try:
            seq = int(a[73:80])
            typ = int(a[0:8])
            tr = a[48:56].strip()
            st = a[64:72].replace(" ", "0")
            form = b[32:40].strip()
            d = {"entity_type_number": typ, "transform": int(tr) if tr else None,
                 "status_number": int(st) if st.strip("0") else 0,
                 "form_number": int(form) if form else 0}
        except ValueError:
            raise FileFormatError(f"{path}: bad directory entry {a.strip()[:40]!r}") \
                from None
        out[seq] = Entry(seq, d)
    return out


def param_records(path: Path) -> tuple[dict, list]:
    """``({DE pointer: [fields]}, global fields)`` from the P and G sections."""
    text = path.read_text(encoding="latin-1")
    lines = text.splitlines()
    glob = "".join(ln[:72] for ln in lines if len(ln) >= 73 and ln[72] == "G")
    psep, rsep = ",", ";"
    if glob.startswith("1H"):
        psep = glob[2]
        rest = glob[3:]
        if rest.startswith("1H"):
            rsep = rest[2]
    elif glob.startswith(","):
        if glob[1:3] == "1H":
            rsep = glob[3]
    chunks: dict = {}
    for ln in lines:
        if len(ln) >= 73 and ln[72] == "P":
            try:
                de = int(ln[64:72])
            except ValueError:
                raise FileFormatError(f"{path}: bad parameter line {ln.strip()[:40]!r}") \
                    from None
            chunks.setdefault(de, []).append(ln[:64])
    recs = {}
    for de, parts in chunks.items():
        s = "".join(parts).strip()
        if rsep in s:
            s = s[: s.index(rsep)]
        recs[de] = [f.strip() for f in s.split(psep)]
    return recs, _global_fields(glob, psep, rsep)


def units(gf: list):
    """``(units, resolution)`` from global parameters 14, 15 and 19 (1-based)."""
    units = res = None
    if len(gf) >= 15:
        name = gf[14].strip().upper().replace(".", "")
        units = _UNIT_NAMES.get(name)
        if units is None and gf[13]:
            try:
                units = UNIT_FLAGS.get(int(float(gf[13])))
            except ValueError:
                units = None
    if len(gf) >= 19 and gf[18]:
        try:
            res = real(gf[18])
        except ValueError:
            res = None
    return units, res


