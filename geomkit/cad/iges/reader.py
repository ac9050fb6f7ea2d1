"""Reading IGES files: every face as an exact NURBS :class:`~geomkit.Surface`.

The directory (D) and parameter (P) sections are read here
(:mod:`geomkit.cad.iges.file`), so every value is taken exactly as written.

* Surfaces (see :mod:`geomkit.cad.iges.entities`): 128 (rational B-spline), 114
  (parametric spline, bicubic patches), 120 (surface of revolution about a 110 axis,
  generatrix 110 / 100 / 104 / 126 / 112), 122 (tabulated cylinder), 118 (ruled, between
  curves of equal degree whose parameters map alike to their NURBS), each with
  its 124 transformation chain.  Revolutions are built exactly (The NURBS Book A7.1 /
  A8.1); their angle parameter becomes a rational one, and the face's pcurves are
  carried through that map (:mod:`geomkit.cad.uvmap`: exact for iso-parametric
  segments, else a cubic interpolant within ``PCURVE_TOL`` x the domain).
* Analytic surfaces 108 (plane), 190 (plane), 192 / 194 / 196 / 198 (cylinder, cone,
  sphere, torus) as exact bilinear patches and revolutions over each face's boundary,
  which is read from the model-space edges (:mod:`geomkit.cad.brep`).
* B-rep faces: every 510 (under 514 shells / 186 solids) on an analytic surface bounded
  by its 508 loops' 504 edges, or on 128 / 120 / 122 / 118 / 114 by the loops' pcurves;
  a loop without pcurves has its 3-D edges projected onto the surface within the
  model resolution (:mod:`geomkit.cad.edgeproj`, ``edge_fit_error``).
* 143 (bounded surface) with 141 boundaries: model-space curves on analytic surfaces,
  parameter-space curves on the others.
* 144 (trimmed surface): ``PTS, N1, N2, PTO, PTI(1..N2)``; each boundary is a 142
  (curve on surface) whose parameter-space curve ``BPTR`` (126 B-spline curve, 110
  line, 100 arc, 104 conic (:mod:`geomkit.cad.conic`), or a 102 composite of those)
  becomes a trim loop, outer first.  ``N1 = 0``
  means the outer boundary is the domain boundary.
* Gaps between the pieces of a boundary (CAD files carry 1e-5..1e-3 of the domain)
  are bridged by straight UV segments and counted (``gaps_closed``, ``max_gap``).
* Faces that cannot be read exactly are never guessed: by default the read fails
  listing every one and why; with ``skip_unsupported=True`` they are left out and
  listed in :attr:`IgesResult.skipped` as ``(id, reason)`` pairs.
* Units (global parameters 14 / 15) and the model resolution (parameter 19) are read
  into :attr:`IgesResult.units` / :attr:`IgesResult.resolution`.
* Surfaces used by no 144 are returned untrimmed (unless physically dependent).

Each surface is validated; an invalid one raises :class:`InvalidSurfaceError` naming
its entity (directory sequence number), or is skipped with ``skip_invalid=True``.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import NamedTuple

import numpy as np

from geomkit.tolerances import EDGE_TOL, PCURVE_TOL, SAME_POINT_TOL, TRIM_CLIP_TOL
from geomkit.cad.iges.entities import Unsupported as _Skip
from geomkit.cad.iges.file import integer as _i
from geomkit.cad.iges.file import real as _f
from geomkit.cad.iges.entities import bspline126, curve3d, restrict
from geomkit.cad.iges.entities import surface as _surface_entity
from geomkit.cad.brep import ANALYTIC, curve_loop_141, curve_loop_142, edge_loop_508, face_surface
from geomkit.cad.loops import clip_to_domain, close_gaps
from geomkit.cad.iges.file import UNIT_FLAGS  # noqa: F401 (re-exported)
from geomkit.cad.iges.file import directory as _directory
from geomkit.cad.iges.file import param_records as _param_records
from geomkit.cad.iges.file import units as _units
from geomkit.cad.uvmap import map_pcurve
from geomkit.cad.edgeproj import edge_uv
from geomkit.cad.loops import reverse
from geomkit.nurbs.evaluation import evaluate
from geomkit.errors import FileFormatError, InvalidInputError, InvalidSurfaceError
from geomkit.nurbs.surface import Surface, TrimCurve

__all__ = ["read_iges", "IgesResult", "Skipped"]

class Skipped(NamedTuple):
    """One face or entity left out of a read: its id (``"<type>@<DE>"`` or
    ``"face<k>"``) and why."""

    id: str
    reason: str

    def __str__(self) -> str:
        return f"{self.id}: {self.reason}"


@dataclass(eq=False)
class IgesResult:
    """Surfaces read from an IGES (or STEP) file.

    Attributes
    ----------
    surfaces : list of Surface, named ``"<type>@<DE>"`` (entity type and directory
        sequence number of the face or surface; ``"face<k>"`` for STEP).
    entities : list of int, the directory sequence number (STEP: face index) of each.
    skipped : list of :class:`Skipped` ``(id, reason)``, faces left out (only with
        ``skip_unsupported`` / ``skip_invalid``).
    counts : dict, entities per type in the file (STEP: ``{"faces": n}``).
    gaps_closed : int, trim-piece gaps bridged by UV segments; max_gap : their largest
        size in UV.
    units : str or None, the file's length unit (``"mm"``, ``"in"``, ``"m"``, ...).
    resolution : float or None, the file's model resolution / uncertainty in ``units``.
    pcurve_error : float, largest UV error of the pcurves carried through a
        reparametrisation (0 when every one was mapped exactly).
    edge_fit_error : float, largest model-space distance between a 510 face's edges
        that carry no pcurves and their projected UV polylines (within the model
        resolution; 0 when no edge was projected).
    edge_gap : float or None, the model's gap measured on the edges its faces share
        (STEP: :func:`geomkit.cad.step.edge_gaps`); None when the file gives no
        topology to measure it on.
    edge_tolerance : float or None, the largest edge tolerance the file states (STEP,
        as Open CASCADE keeps it).
    loose : list of int, positions in ``surfaces`` of the faces outside the file's
        solids (STEP: an open shell of a surface model beside a closed shell).
    duplicates : dict, loose face position -> positions of the solid faces it lies on
        within the file's tolerance (:mod:`geomkit.cad.loose`).
    """

    surfaces: list
    entities: list
    skipped: list = field(default_factory=list)
    counts: dict = field(default_factory=dict)
    gaps_closed: int = 0
    max_gap: float = 0.0
    units: str | None = None
    resolution: float | None = None
    pcurve_error: float = 0.0
    edge_fit_error: float = 0.0
    edge_gap: float | None = None
    edge_tolerance: float | None = None
    loose: list = field(default_factory=list)
    duplicates: dict = field(default_factory=dict)


class _Reader:
    def __init__(self, path: Path, iges=None):
        """``iges`` is ignored (kept for callers that pass a pyiges model): the
        directory and parameter sections are read here."""
        self.path = path
        self.recs, self.glob = _param_records(path)
        self.dir = _directory(path)
        self.gaps = []
        self.pcurve_error = 0.0
        self.clipped = 0
        self.approx = {}  # DE -> achieved error of an approximated (offset) surface
        self.edge_fit_error = 0.0  # model-space error of edges projected to UV

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
    def surface128_args(self, de: int):
        """Entity 128 as :class:`~geomkit.Surface` arguments ``(p, q, U, V, P, W)``."""
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
        return M1, M2, S, T, P, weights

    def make_surface(self, de: int, args, trim=None, name=None) -> Surface:
        try:
            return Surface(*args, trim, name=name, approx_error=self.approx.get(de, 0.0))
        except InvalidInputError as exc:
            if trim is not None:
                raise
            raise InvalidSurfaceError(f"entity {self.type_of(de)} at DE {de}: {exc}") \
                from None

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
        if t in (100, 104):  # arcs and conics in the (u, v) plane: exact rational
            (p, U, Pw), _, _ = curve3d(self, de)
            w = Pw[:, 3]
            return [TrimCurve.create(p, U, Pw[:, :2] / w[:, None],
                                     None if np.all(w == w[0]) else w,
                                     f"{where}.{t}@{de}")]
        if t == 110:
            p0 = [_f(r[1]), _f(r[2])]
            p1 = [_f(r[4]), _f(r[5])]
            return [TrimCurve.polyline([p0, p1], f"{where}.line@{de}")]
        if t == 126:
            M, knots, W, P, (v0, v1) = bspline126(r)
            w = W if np.any(W != W[0]) else np.ones(len(W))
            U, Pw = restrict(M, knots, np.column_stack([P[:, :2] * w[:, None], w]), v0, v1)
            w = Pw[:, 2]
            return [TrimCurve.create(M, U, Pw[:, :2] / w[:, None],
                                     None if np.all(w == w[0]) else w, f"{where}.curve@{de}")]
        raise _Skip(f"parameter-space curve DE {de} is entity {t} (only 126, 110, 100, "
                    "104 and 102 are read exactly)")

    def loop142(self, de: int, where: str, domain=None, fu=None, fv=None, base=None):
        if self.type_of(de) != 142:
            raise _Skip(f"boundary DE {de} is entity {self.type_of(de)}, expected 142")
        r = self.rec(de)
        bptr = _i(r[3])
        if bptr == 0:
            raise _Skip(f"boundary 142 at DE {de} has no parameter-space curve")
        return self.uv_loop(self.pcurve_pieces(bptr, where), f"boundary 142 at DE {de}",
                            domain, fu, fv, base)

    def loop508(self, de: int, where: str, domain=None, fu=None, fv=None, base=None):
        """A 508 loop from its edges' pcurves (each reversed where the loop runs
        against its edge; vertex entries dropped: poles are bridged)."""

        r = self.rec(de)
        n, a, pieces = _i(r[1]), 2, []
        for _ in range(n):
            typ, of, k = _i(r[a]), _i(r[a + 3]), _i(r[a + 4])
            ptr = _i(r[a + 6]) if k >= 1 else 0
            a += 5 + 2 * k
            if typ == 1:
                continue
            if not ptr:  # model-space edges only: project them (cad.edgeproj)
                return self.projected508(de, where, domain, base)
            ps = self.pcurve_pieces(ptr, where)
            pieces += ps if of == 1 else [reverse(c) for c in ps[::-1]]
        return self.uv_loop(pieces, f"loop 508 at DE {de}", domain, fu, fv, base)

    def projected508(self, de: int, where: str, domain, base):
        """A 508 loop whose edges have no pcurves: its 3-D edges projected onto
        ``base`` within the model resolution (:func:`geomkit.cad.edgeproj.edge_uv`)."""

        if base is None:
            raise _Skip(f"loop 508 at DE {de}: an edge has no parameter-space curve")
        res = _units(self.glob)[1]
        P = base.control_points.reshape(-1, 3)
        size = float(np.linalg.norm(np.ptp(P, axis=0)))
        tol = max(res or 0.0, EDGE_TOL * size)
        pieces, err = edge_uv(base, edge_loop_508(self, de), tol, f"loop 508 at DE {de}")
        self.edge_fit_error = max(self.edge_fit_error, err)
        return self.uv_loop(pieces, f"loop 508 at DE {de}", domain, None, None, base)

    def loop141(self, de: int, where: str, domain=None, fu=None, fv=None, base=None):
        """A 141 boundary from its parameter-space curves (``SENSE = 2``: reversed)."""

        if self.type_of(de) != 141:
            raise _Skip(f"boundary DE {de} is entity {self.type_of(de)}, expected 141")
        r = self.rec(de)
        n, a, pieces = _i(r[4]), 5, []
        for _ in range(n):
            sense, k = _i(r[a + 1]), _i(r[a + 2])
            if k < 1:
                raise _Skip(f"boundary 141 at DE {de} has no parameter-space curve")
            ps = self.pcurve_pieces(_i(r[a + 3]), where)
            pieces += ps if sense != 2 else [reverse(c) for c in ps[::-1]]
            a += 3 + k
        return self.uv_loop(pieces, f"boundary 141 at DE {de}", domain, fu, fv, base)

    def uv_loop(self, pieces, what, domain, fu, fv, base):
        """Pcurve pieces carried through ``fu, fv``, clipped, gaps closed."""
        if (fu is not None or fv is not None) and pieces:
            (u0, u1), (v0, v1) = domain
            tol = PCURVE_TOL * max(u1 - u0, v1 - v0)
            mapped = []
            for c in pieces:
                m, err = map_pcurve(c, fu, fv, tol)
                self.pcurve_error = max(self.pcurve_error, err)
                mapped.append(m)
            pieces = mapped
        if not pieces:
            raise _Skip(f"{what} has an empty parameter-space curve")
        return self._close_gaps(self._clip(pieces, domain), what, domain, base)

    def analytic_face(self, srf: int, edges, where: str) -> Surface:
        """A face on an analytic surface bounded by model-space edge loops
        (:func:`geomkit.cad.brep.face_surface`)."""
        args, uv_loops, dom = face_surface(self, srf, edges, PCURVE_TOL)
        loops = [self._close_gaps(self._clip(lp, dom), f"face on surface DE {srf}", dom)
                 for lp in uv_loops]
        return Surface(*args, loops, name=where)

    def _clip(self, pieces, domain):
        """Snap control points within ``TRIM_CLIP_TOL`` outside the domain onto it."""
        if domain is None:
            return pieces
        out, moves = clip_to_domain(pieces, domain, TRIM_CLIP_TOL)
        self.clipped += len(moves)
        return out

    def _close_gaps(self, pieces, what, domain, base=None):
        """Bridge rounding gaps between consecutive pieces (:func:`close_gaps`); on
        ``base``, also gaps whose ends are one model point (poles)."""
        if domain is None:
            return pieces
        same = None
        if base is not None:
            P = base.control_points.reshape(-1, 3)
            eps = SAME_POINT_TOL * float(np.ptp(P, axis=0).max())
            (u0, u1), (v0, v1) = domain

            def same(a, b):
                uv = np.clip(np.array([a, b]), [u0, v0], [u1, v1])
                X = evaluate(base, uv)
                return float(np.linalg.norm(X[0] - X[1])) <= eps
        out, gaps = close_gaps(pieces, domain, what, same)
        self.gaps += gaps
        return out




def read_iges(path, skip_invalid: bool = False,
              skip_unsupported: bool = False) -> IgesResult:
    """Read every face of an IGES file as an exact NURBS surface.

    Parameters
    ----------
    path : str or Path
    skip_invalid : bool
        Skip (and list in ``skipped``) surfaces that fail validation instead of
        raising.
    skip_unsupported : bool
        Leave out (and list in ``skipped``) faces whose entities are not read, instead
        of raising.  Never silent: the result's ``skipped`` says which and why.

    Returns
    -------
    IgesResult

    Raises
    ------
    InvalidInputError
        An empty file.
    FileFormatError
        Missing or unreadable file, no surface entity, or faces that cannot be read
        (listed, each with its reason) without ``skip_unsupported``.
    InvalidSurfaceError
        A surface or trim that fails validation, naming its entity.
    """
    p = Path(path)
    if not p.exists():
        raise FileFormatError(f"{p}: no such file")
    if p.is_dir():
        raise FileFormatError(f"{p}: is a directory, expected an IGES file")
    if not p.read_bytes().strip():
        raise InvalidInputError(f"{p}: empty file, expected an IGES file")
    rd = _Reader(p)
    if not rd.dir:
        raise FileFormatError(f"{p}: not a readable IGES file (no directory section: "
                              "no line with 'D' in column 73)")
    counts: dict = {}
    for e in rd.dir.values():
        t = int(e.d["entity_type_number"])
        counts[t] = counts.get(t, 0) + 1
    surfaces, entities, skipped = [], [], []
    used = set()

    def take(de, where, what, build):
        """One face: ``build()`` gives its Surface or raises _Skip (not read: listed)
        or InvalidInputError (an error unless ``skip_invalid``)."""
        try:
            s = build()
        except _Skip as why:
            skipped.append(Skipped(where, str(why)))
            return
        except (IndexError, ValueError, TypeError, KeyError) as exc:
            if isinstance(exc, InvalidInputError):  # a ValueError too: validation
                if not skip_invalid:
                    raise InvalidSurfaceError(f"{p}: {what} at DE {de}: {exc}") from None
                skipped.append(Skipped(where, f"invalid: {exc}"))
                return
            # parameters missing or not numbers where the entity needs them
            raise FileFormatError(f"{p}: {what} at DE {de}: malformed parameters "
                                  f"({type(exc).__name__}: {exc})") from None
        except InvalidInputError as exc:
            if not skip_invalid:
                raise InvalidSurfaceError(f"{p}: {what} at DE {de}: {exc}") from None
            skipped.append(Skipped(where, f"invalid: {exc}"))
            return
        surfaces.append(s)
        entities.append(de)

    def of_type(t):
        return [(de, e) for de, e in sorted(rd.dir.items())
                if int(e.d["entity_type_number"]) == t]

    for de, e in of_type(144):
        r = rd.rec(de)
        pts, n1, n2, pto = _i(r[1]), _i(r[2]), _i(r[3]), _i(r[4])
        pti = [_i(x) for x in r[5: 5 + n2]]
        used.add(pts)
        where = f"144@{de}"

        def trimmed_144():
            if rd.transform(de) is not None:
                raise _Skip("transformation matrix on the trimmed surface itself")
            if rd.type_of(pts) in ANALYTIC:
                if not (n1 == 1 and pto):
                    raise _Skip(f"analytic surface DE {pts} is unbounded (144 without an "
                                "outer boundary)")
                edges = [curve_loop_142(rd, k) for k in [pto] + pti]
                return rd.analytic_face(pts, edges, where)
            args, fu, fv = _surface_entity(rd, pts)
            base = rd.make_surface(pts, args, name=where)
            loops = []
            if n1 == 1 and pto:
                loops.append(rd.loop142(pto, where, base.domain, fu, fv, base))
            elif n2:
                (u0, u1), (v0, v1) = base.domain
                loops.append([[u0, v0], [u1, v0], [u1, v1], [u0, v1], [u0, v0]])
            for k in pti:
                loops.append(rd.loop142(k, where, base.domain, fu, fv, base))
            return rd.make_surface(pts, args, trim=loops or None, name=where)

        take(de, where, "trimmed surface 144", trimmed_144)
    for de, e in of_type(143):
        r = rd.rec(de)
        srf, nb = _i(r[2]), _i(r[3])
        bd = [_i(x) for x in r[4: 4 + nb]]
        used.add(srf)
        where = f"143@{de}"

        def bounded_143():
            if not bd:
                raise _Skip("bounded surface 143 without boundaries")
            if rd.type_of(srf) in ANALYTIC:
                return rd.analytic_face(srf, [curve_loop_141(rd, k) for k in bd], where)
            args, fu, fv = _surface_entity(rd, srf)
            base = rd.make_surface(srf, args, name=where)
            loops = [rd.loop141(k, where, base.domain, fu, fv, base) for k in bd]
            return rd.make_surface(srf, args, trim=loops, name=where)

        take(de, where, "bounded surface 143", bounded_143)
    for de, e in of_type(510):
        r = rd.rec(de)
        srf, nl = _i(r[1]), _i(r[2])
        used.add(srf)
        where = f"510@{de}"

        def face_510():
            if rd.type_of(srf) in ANALYTIC or (rd.type_of(srf) == 140 and rd.type_of(
                    _i(rd.rec(srf)[5])) in ANALYTIC):
                edges = [edge_loop_508(rd, _i(x)) for x in r[4: 4 + nl]]
                return rd.analytic_face(srf, edges, where)
            args, fu, fv = _surface_entity(rd, srf)
            base = rd.make_surface(srf, args, name=where)
            loops = [rd.loop508(_i(x), where, base.domain, fu, fv, base)
                     for x in r[4: 4 + nl]]
            return rd.make_surface(srf, args, trim=loops, name=where)

        take(de, where, "face 510", face_510)
    for de, e in sorted(rd.dir.items()):
        t = int(e.d["entity_type_number"])
        if t not in (128, 114, 120, 122, 118, 140) or de in used:
            continue
        sub = (e.d.get("status_number") or 0) // 10000 % 100
        if sub == 1:  # physically dependent: part of another entity
            continue

        def untrimmed(de=de, t=t):
            args, _, _ = _surface_entity(rd, de)
            return rd.make_surface(de, args, name=f"{t}@{de}")

        take(de, f"{t}@{de}", f"surface {t}", untrimmed)
    for de, e in sorted(rd.dir.items()):
        t = int(e.d["entity_type_number"])
        sub = (e.d.get("status_number") or 0) // 10000 % 100
        if t in UNREAD_SURFACES and de not in used and sub != 1:
            skipped.append(Skipped(f"{t}@{de}", f"entity {t} ({UNREAD_SURFACES[t]}) is "
                                   "not read"))
    unsupported = [k for k in skipped if not k.reason.startswith("invalid:")]
    if unsupported and not skip_unsupported:
        lines = "; ".join(str(k) for k in unsupported[:5])
        more = f" (and {len(unsupported) - 5} more)" if len(unsupported) > 5 else ""
        raise FileFormatError(f"{p}: {len(unsupported)} face(s) cannot be read: {lines}"
                              f"{more}; pass skip_unsupported=True (--skip-unsupported) "
                              "to go on without them")
    if not surfaces:
        kinds = ", ".join(f"{n} x {t}" for t, n in sorted(counts.items()))
        raise FileFormatError(f"{p}: no readable surface (entities 128, 114, 120, 122, "
                              f"118, 144); the file holds {kinds or 'no entities'}"
                              + (f"; first skipped: {skipped[0]}" if skipped else ""))
    units, res = _units(rd.glob)
    return IgesResult(surfaces, entities, skipped, counts, len(rd.gaps),
                      max(rd.gaps, default=0.0), units, res, rd.pcurve_error,
                      rd.edge_fit_error)


UNREAD_SURFACES = {108: "plane",
                   190: "plane surface", 192: "right circular cylindrical surface",
                   194: "right circular conical surface", 196: "spherical surface",
                   198: "toroidal surface"}
"""Surface entities listed as skipped when they are not under a 144 that was read."""
