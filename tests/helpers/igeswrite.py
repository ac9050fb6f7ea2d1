"""Write small IGES files by hand for the reader's tests (fixed 80-column format).

``write_iges(path, entities)``: ``entities`` is a list of
``(type, params, form=0, transform=0, status="00000000")`` tuples; entity ``k``
(0-based) gets the directory sequence number ``2 k + 1`` (:func:`de`), which is how
parameters point at each other.  :func:`entity_types` lists the entity types of a
written file.
"""

from __future__ import annotations


def de(k: int) -> int:
    """Directory sequence number of the ``k``-th entity (0-based)."""
    return 2 * k + 1


def _fmt(x) -> str:
    if isinstance(x, str):
        return x
    if isinstance(x, int):
        return str(x)
    return repr(float(x))


def write_iges(path, entities, unit_flag: int = 2, unit: str = "MM",
               resolution: float = 1e-7) -> None:
    glob = (f"1H,,1H;,4Htest,{len(str(path))}H{path},4Htest,4Htest,32,38,6,308,15,"
            f"4Htest,1.,{unit_flag},{len(unit)}H{unit},1,0.01,15H20260101.000000,"
            f"{resolution!r},1000.,4Htest,4Htest,11,0,15H20260101.000000;")
    S = ["hand-written IGES test file".ljust(72) + "S      1"]
    G = [glob[i: i + 72].ljust(72) + f"G{i // 72 + 1:7d}" for i in range(0, len(glob), 72)]
    D, P = [], []
    for k, ent in enumerate(entities):
        typ, params, form, tr, status = (tuple(ent) + (0, 0, "00000000")[len(ent) - 2:])
        text = ",".join([str(typ)] + [_fmt(x) for x in params]) + ";"
        chunks, cur = [], ""
        for f in text.split(","):
            piece = f if not cur else "," + f
            if len(cur) + len(piece) > 63:
                chunks.append(cur + ",")
                cur = f
            else:
                cur += piece
        chunks.append(cur)
        p0 = len(P) + 1
        for c in chunks:
            P.append(c.ljust(64) + f"{de(k):8d}P{len(P) + 1:7d}")
        D.append(f"{typ:8d}{p0:8d}{0:8d}{0:8d}{0:8d}{0:8d}{tr:8d}{0:8d}{status:>8s}"
                 f"D{de(k):7d}")
        D.append(f"{typ:8d}{0:8d}{0:8d}{len(chunks):8d}{form:8d}{'':8s}{'':8s}{'':8s}"
                 f"{0:8d}D{de(k) + 1:7d}")
    T = f"S{len(S):7d}G{len(G):7d}D{len(D):7d}P{len(P):7d}".ljust(72) + "T      1"
    with open(path, "w") as fh:
        fh.write("\n".join(S + G + D + P + [T]) + "\n")


def entity_types(path) -> set:
    """The entity type numbers in an IGES file's directory section (written by this
    module or by Open CASCADE)."""
    lines = [ln for ln in path.read_text().splitlines() if len(ln) >= 73 and ln[72] == "D"]
    return {int(ln[:8]) for ln in lines[::2]}
