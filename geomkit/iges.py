"""Reading IGES files: B-spline surfaces (entity 128) and trimmed surfaces (144).

pyiges lists the entities (directory section); the parameter records are read here
from the file's P section, so every value is taken exactly as written.

* 128 (rational B-spline surface): ``K1, K2, M1, M2, PROP1..5``, knots ``S`` (K1+M1+2)
  and ``T`` (K2+M2+2), weights and control points with the *first* index (u)
  varying fastest, then ``U0, U1, V0, V1``.  Unclamped (e.g. periodic) knot vectors are
  clamped by :class:`~geomkit.Surface` (the surface is unchanged).  PROP3 = 1
  (polynomial) drops the weights.  A transformation matrix (124) is applied to the
  control points (exact for NURBS).
* 144 (trimmed surface): ``PTS, N1, N2, PTO, PTI(1..N2)``; each boundary is a 142
  (curve on surface) whose parameter-space curve ``BPTR`` (126 B-spline curve, 110
  line, or a 102 composite of those) becomes a trim loop, outer first.  ``N1 = 0``
  means the outer boundary is the domain boundary.
* Gaps between the pieces of a boundary (CAD files carry 1e-5..1e-3 of the domain)
  are bridged by straight UV segments and counted (``gaps_closed``, ``max_gap``).
* Faces that cannot be read exactly — a surface that is not a 128 (e.g. 120 surface
  of revolution), a boundary without a parameter-space curve, a 100 arc in parameter
  space — are skipped and listed in :attr:`IgesResult.skipped` (never guessed).
* 128 surfaces used by no 144 are returned untrimmed.

Each surface is validated; an invalid one raises :class:`InvalidSurfaceError` naming
its entity (directory sequence number), or is skipped with ``skip_invalid=True``.
"""

from __future__ import annotations

import contextlib
import io
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .errors import (FileFormatError, InvalidInputError, InvalidSurfaceError,
                     MissingDependencyError)
from .types import Surface, TrimCurve

__all__ = ["read_iges", "IgesResult"]


@dataclass(eq=False)
class IgesResult:
    """Surfaces read from an IGES file.

    Attributes
    ----------
    surfaces : list of Surface, named ``"<type>@<DE>"`` (entity type and directory
        sequence number of the face or surface).
    entities : list of int, the directory sequence number of each surface's entity.
    skipped : list of str, one line per face not read and why.
    counts : dict, entities per type in the file.
    gaps_closed : int, trim-piece gaps bridged by UV segments (see ``GAP_TOL``); max_gap : their largest
        size in UV.
    """

    surfaces: list
    entities: list
    skipped: list = field(default_factory=list)
    counts: dict = field(default_factory=dict)
    gaps_closed: int = 0
    max_gap: float = 0.0


def _import_pyiges():
    try:
        import pyiges
    except ImportError:
        raise MissingDependencyError("reading IGES needs pyiges: pip install pyiges") from None
    return pyiges


def _param_records(path: Path) -> tuple[dict, str]:
    """``{DE pointer: [fields]}`` from the P section (fields as strings)."""
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
    return recs, psep


def _f(x: str) -> float:
    return float(x.replace("D", "E").replace("d", "e")) if x else 0.0


def _i(x: str) -> int:
    return int(float(x)) if x else 0


class _Reader:
    def __init__(self, path: Path, iges):
        self.path = path
        self.recs, _ = _param_records(path)
        self.dir = {}
        self.gaps = []
        self.clipped = 0
        for e in iges.items:
            self.dir[e.sequence_number] = e

    def rec(self, de: int) -> list:
        if de not in self.recs:
            raise FileFormatError(f"{self.path}: entity DE {de}: no parameter data")
        return self.recs[de]

    def type_of(self, de: int) -> int:
        e = self.dir.get(de)
        if e is None:
            raise FileFormatError(f"{self.path}: pointer to missing entity DE {de}")
        return int(e.d["entity_type_number"])

    def transform(self, de: int):
        """4x4 matrix of the entity's transformation chain (None for identity)."""
        e = self.dir[de]
        T = None
        ptr = e.d.get("transform")
        seen = set()
        while ptr:
            if ptr in seen:
                raise FileFormatError(f"{self.path}: DE {de}: cyclic transformation chain")
            seen.add(ptr)
            r = self.rec(ptr)
            v = [_f(x) for x in r[1:13]]
            M = np.eye(4)
            M[:3, :3] = np.array([v[0:3], v[4:7], v[8:11]])
            M[:3, 3] = [v[3], v[7], v[11]]
            T = M if T is None else M @ T
            ptr = self.dir[ptr].d.get("transform")
        return T

    # ----------------------------------------------------------------- 128
    def surface128(self, de: int, trim=None, name=None) -> Surface:
        r = self.rec(de)
        K1, K2, M1, M2 = (_i(x) for x in r[1:5])
        prop3 = _i(r[7])
        n1, n2 = K1 + 1, K2 + 1
        a = 10
        S = [_f(x) for x in r[a: a + K1 + M1 + 2]]
        a += K1 + M1 + 2
        T = [_f(x) for x in r[a: a + K2 + M2 + 2]]
        a += K2 + M2 + 2
        W = np.array([_f(x) for x in r[a: a + n1 * n2]])
        a += n1 * n2
        P = np.array([_f(x) for x in r[a: a + 3 * n1 * n2]])
        if P.size != 3 * n1 * n2 or W.size != n1 * n2:
            raise FileFormatError(f"{self.path}: entity 128 DE {de}: truncated parameter "
                                  "data")
        # first index (u) varies fastest: [j][i] -> transpose to [i][j]
        P = P.reshape(n2, n1, 3).transpose(1, 0, 2)
        W = W.reshape(n2, n1).T
        Tm = self.transform(de)
        if Tm is not None:
            P = P @ Tm[:3, :3].T + Tm[:3, 3]
        weights = None if prop3 == 1 or np.all(W == W.flat[0]) else W
        try:
            return Surface(M1, M2, S, T, P, weights, trim, name=name or f"128@{de}")
        except InvalidInputError as exc:
            raise InvalidSurfaceError(f"entity 128 at DE {de}: {exc}") from None

    # ------------------------------------------------------------ curves
    def pcurve_pieces(self, de: int, where: str) -> list:
        t = self.type_of(de)
        r = self.rec(de)
        if t == 102:
            n = _i(r[1])
            out = []
            for k in range(n):
                out += self.pcurve_pieces(_i(r[2 + k]), where)
            return out
        if t == 110:
            p0 = [_f(r[1]), _f(r[2])]
            p1 = [_f(r[4]), _f(r[5])]
            return [TrimCurve.polyline([p0, p1], f"{where}.line@{de}")]
        if t == 126:
            K, M = _i(r[1]), _i(r[2])
            prop3 = _i(r[5])
            N = 1 + K - M
            A = N + 2 * M
            a = 7
            knots = np.array([_f(x) for x in r[a: a + A + 1]])
            a += A + 1
            W = np.array([_f(x) for x in r[a: a + K + 1]])
            a += K + 1
            P = np.array([_f(x) for x in r[a: a + 3 * (K + 1)]]).reshape(K + 1, 3)
            a += 3 * (K + 1)
            v0, v1 = _f(r[a]), _f(r[a + 1])
            w = None if prop3 == 1 or np.all(W == W[0]) else W
            return [_restricted_curve(M, knots, P[:, :2], w, v0, v1, f"{where}.curve@{de}")]
        raise _Skip(f"parameter-space curve DE {de} is entity {t} (only 126, 110 and 102 "
                    "are read exactly)")

    def loop142(self, de: int, where: str, domain=None):
        if self.type_of(de) != 142:
            raise _Skip(f"boundary DE {de} is entity {self.type_of(de)}, expected 142")
        r = self.rec(de)
        bptr = _i(r[3])
        if bptr == 0:
            raise _Skip(f"boundary 142 at DE {de} has no parameter-space curve")
        pieces = self.pcurve_pieces(bptr, where)
        if not pieces:
            raise _Skip(f"boundary 142 at DE {de} has an empty parameter-space curve")
        return self._close_gaps(self._clip(pieces, domain), de, domain)

    def _clip(self, pieces, domain):
        """Move control points that lie at most CLIP_TOL x the domain size outside the
        parameter domain onto its edge (files round the domain ends: 0.011739075 vs
        0.0117390748871053); the curve moves by at most that much.  Points farther out
        are kept, and validation reports them."""
        if domain is None:
            return pieces
        (u0, u1), (v0, v1) = domain
        eps = CLIP_TOL * max(u1 - u0, v1 - v0)
        out = []
        for c in pieces:
            P = np.array(c.control_points)
            Q = np.column_stack([np.clip(P[:, 0], u0, u1), np.clip(P[:, 1], v0, v1)])
            moved = np.abs(Q - P).max()
            if moved == 0 or moved > eps:
                out.append(c)
                continue
            self.clipped += 1
            out.append(TrimCurve.create(c.degree, c.knots, Q,
                                        None if np.all(c.weights == 1) else c.weights))
        return out

    def _close_gaps(self, pieces, de, domain):
        """Bridge gaps between consecutive pieces (CAD files carry gaps of 1e-5 to 1e-3
        of the domain in UV) with straight UV segments: the exact pieces are kept as
        they are.  Gaps above GAP_TOL x the domain size skip the face."""
        if domain is None:
            return pieces
        (u0, u1), (v0, v1) = domain
        size = max(u1 - u0, v1 - v0)
        out = []
        for k, a in enumerate(pieces):
            out.append(a)
            b = pieces[(k + 1) % len(pieces)]
            gap = float(np.hypot(*(a.end - b.start)))
            if gap <= 1e-9 * size:
                continue
            if gap > GAP_TOL * size:
                raise _Skip(f"boundary 142 at DE {de}: pieces {k} and "
                            f"{(k + 1) % len(pieces)} are {gap:.3g} apart in UV (more than "
                            f"{GAP_TOL:g} of the domain)")
            self.gaps.append(gap)
            out.append(TrimCurve.polyline([a.end, b.start]))
        return out


CLIP_TOL = 1e-7
"""Trim control points this close outside the domain (relative) are moved onto it."""
GAP_TOL = 1e-2
"""Largest gap between the pieces of a trim loop that is bridged, relative to the
parameter domain size."""


class _Skip(Exception):
    pass


def _restricted_curve(p, knots, P, w, t0, t1, field):
    """A 2-D NURBS curve restricted to ``[t0, t1]`` (exact, by knot insertion)."""
    from ._kernels.bezier import insert_knot

    n = P.shape[0]
    if w is None:
        w = np.ones(n)
    Pw = np.column_stack([P * w[:, None], w])
    U = np.asarray(knots, float)
    lo, hi = U[p], U[n]
    t0 = max(t0, lo)
    t1 = min(t1, hi) if t1 > t0 else hi
    if t0 > lo or t1 < hi:
        for t in (t0, t1):
            s = int(np.count_nonzero(U == t))
            if s < p:
                Pw, U = insert_knot(np.ascontiguousarray(Pw), p, U, t, p - s)
        first_a = int(np.nonzero(U == t0)[0][0])
        start = first_a + int(np.count_nonzero(U == t0)) - 1 - p
        first_b = int(np.nonzero(U == t1)[0][0])
        newU = U[start: first_b + p + 1].copy()
        newU[: p + 1] = t0
        newU[-(p + 1):] = t1
        Pw = Pw[start: first_b]
        U = newU
    w = Pw[:, 2]
    return TrimCurve.create(p, U, Pw[:, :2] / w[:, None],
                            None if np.all(w == w[0]) else w, field)


def read_iges(path, skip_invalid: bool = False) -> IgesResult:
    """Read the B-spline and trimmed surfaces of an IGES file.

    Parameters
    ----------
    path : str or Path
    skip_invalid : bool
        Skip (and list in ``skipped``) surfaces that fail validation instead of
        raising.

    Returns
    -------
    IgesResult

    Raises
    ------
    FileFormatError
        Missing or unreadable file, or no surface that can be read.
    InvalidSurfaceError
        A surface or trim that fails validation, naming its entity.
    MissingDependencyError
        pyiges is not installed.
    """
    p = Path(path)
    if not p.exists():
        raise FileFormatError(f"{p}: no such file")
    if p.is_dir():
        raise FileFormatError(f"{p}: is a directory, expected an IGES file")
    pyiges = _import_pyiges()
    try:
        with contextlib.redirect_stdout(io.StringIO()):  # pyiges prints warnings
            ig = pyiges.read(str(p))
    except (ValueError, IndexError, KeyError, UnicodeDecodeError) as exc:
        raise FileFormatError(f"{p}: not a readable IGES file ({type(exc).__name__}: "
                              f"{exc})") from None
    rd = _Reader(p, ig)
    counts: dict = {}
    for e in ig.items:
        t = int(e.d["entity_type_number"])
        counts[t] = counts.get(t, 0) + 1
    surfaces, entities, skipped = [], [], []
    used = set()
    for de, e in sorted(rd.dir.items()):
        if int(e.d["entity_type_number"]) != 144:
            continue
        r = rd.rec(de)
        pts, n1, n2, pto = _i(r[1]), _i(r[2]), _i(r[3]), _i(r[4])
        pti = [_i(x) for x in r[5: 5 + n2]]
        used.add(pts)
        where = f"144@{de}"
        try:
            if rd.type_of(pts) != 128:
                raise _Skip(f"surface DE {pts} is entity {rd.type_of(pts)} (only 128 B-spline "
                            "surfaces are read)")
            base = rd.surface128(pts, name=where)
            loops = []
            if n1 == 1 and pto:
                loops.append(rd.loop142(pto, where, base.domain))
            elif n2:
                (u0, u1), (v0, v1) = base.domain
                loops.append([[u0, v0], [u1, v0], [u1, v1], [u0, v1], [u0, v0]])
            for k in pti:
                loops.append(rd.loop142(k, where, base.domain))
            if rd.transform(de) is not None:
                raise _Skip("transformation matrix on the trimmed surface itself")
            s = rd.surface128(pts, trim=loops or None, name=where)
        except _Skip as why:
            skipped.append(f"{where}: {why}")
            continue
        except InvalidInputError as exc:
            if not skip_invalid:
                raise InvalidSurfaceError(f"{p}: trimmed surface 144 at DE {de}: {exc}") \
                    from None
            skipped.append(f"{where}: invalid: {exc}")
            continue
        surfaces.append(s)
        entities.append(de)
    for de, e in sorted(rd.dir.items()):
        if int(e.d["entity_type_number"]) != 128 or de in used:
            continue
        sub = (e.d.get("status_number") or 0) // 10000 % 100
        if sub == 1:  # physically dependent: part of another entity
            continue
        try:
            surfaces.append(rd.surface128(de))
            entities.append(de)
        except InvalidInputError as exc:
            if not skip_invalid:
                raise InvalidSurfaceError(f"{p}: {exc}") from None
            skipped.append(f"128@{de}: invalid: {exc}")
    if not surfaces:
        raise FileFormatError(f"{p}: no readable B-spline surface (entities 128/144); "
                              f"{len(skipped)} face(s) skipped"
                              + (f", first: {skipped[0]}" if skipped else ""))
    return IgesResult(surfaces, entities, skipped, counts, len(rd.gaps),
                      max(rd.gaps, default=0.0))
