"""Inspect a part against its own drawing: every geometric tolerance of the STEP
file's AP242 PMI evaluated on measured points (:func:`inspect_part`).

1. **Faces.**  Each point belongs to a face of :func:`geomkit.read_step`: given (a
   ``face`` column), or the face of its exact foot (:func:`project_points`, after a
   best fit of the points to the whole part when ``align`` is ``"bestfit"``); points
   farther than ``max_distance`` from every face are left out.
2. **Datum reference frames.**  For each datum system of the PMI (``A|B|C``, in the
   file's order), the datum features' points give the measured frame
   (:func:`geomkit.gdt.datum_frame`, default associations) and the nominal faces'
   exact samples the nominal one; a datum on one plane is a tangent plane, on a
   bore or shaft the maximum inscribed / minimum circumscribed cylinder or sphere,
   on two opposed parallel planes (a width) their least-squares median plane.
3. **Characteristics.**  Each tolerance's faces become features
   (:mod:`geomkit.jobs.features`) evaluated by :mod:`geomkit.gdt` in the measured
   frame (``align="datums"``), or in the nominal frame after a best fit
   (``"bestfit"``) or as given (``"none"``, points already in CAD coordinates).
   A tolerance on several features (a pattern) is the worst of them.

A characteristic that cannot be evaluated (too few points, a datum defined by
targets, an unsupported type or modifier) is reported with its reason and makes the
verdict ``"incomplete"``, never ``"pass"``.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np

from geomkit import gdt
from geomkit.cad.steppmi_types import MM_PER_UNIT
from geomkit.errors import GeomkitError, InvalidInputError
from geomkit.gdt._common import jsonable
from geomkit.jobs.deviation import align_rigid
from geomkit.jobs.features import face_shapes, group_features
from geomkit.jobs.inspect_eval import NEED, NotEvaluated, evaluate
from geomkit.jobs.sample import sample_faces
from geomkit.query.projection_part import project_points
from geomkit.query.results import BEYOND, FAILED

__all__ = ["inspect_part", "Inspection", "CharacteristicRow", "ALIGN_MODES",
           "assign_faces"]

ALIGN_MODES = ("datums", "bestfit", "none")
#: Default largest distance of a point from its face, x the part size.
REL_MAX_DISTANCE = 0.02
#: Exact samples per face the PMI names (recognition, the nominal datum frames).
NOMINAL_SAMPLES = 200


@dataclass
class CharacteristicRow:
    """One characteristic of the drawing, evaluated (or not, with ``reason``)."""

    id: str
    type: str
    faces: list
    tolerance: dict
    datums: list
    status: str                         # "pass", "fail", "not evaluated"
    measured: float | None = None
    limit: float | None = None
    n_points: int = 0
    reason: str | None = None
    surfaces: list = field(default_factory=list)      # positions in part.surfaces
    features: list = field(default_factory=list, repr=False)
    deciding: np.ndarray = field(default_factory=lambda: np.zeros(0, np.int64),
                                 repr=False)

    @property
    def passed(self):
        return None if self.status == "not evaluated" else self.status == "pass"

    def to_dict(self) -> dict:
        feats = []
        for f in self.features:
            feats.append({k: jsonable(v) for k, v in f.items()
                          if k not in ("deviation", "deviation_points")})
        return {"id": self.id, "type": self.type, "faces": list(self.faces),
                "surfaces": list(self.surfaces),
                "tolerance": jsonable(self.tolerance), "datums": list(self.datums),
                "measured": self.measured, "limit": self.limit,
                "pass": self.passed, "status": self.status, "points": self.n_points,
                "reason": self.reason, "deciding": jsonable(self.deciding),
                "features": feats}


@dataclass
class Inspection:
    """Result of :func:`inspect_part`.

    ``characteristics`` in the file's order; ``verdict`` ``"pass"`` (every
    characteristic evaluated and passed), ``"fail"`` (one failed) or
    ``"incomplete"`` (none failed, one or more not evaluated); ``face`` the face of
    each point (-1: left out); ``points`` as evaluated (after the best fit with
    ``align="bestfit"``); ``frames`` the datum systems built (label string ->
    measured frame dict, or the reason it could not be built); ``units`` the model's
    length unit; ``deviation`` each point's signed distance to its own face (NaN when
    left out) with the points placed by the datum system ``shown_in`` (the first
    that fixes every degree of freedom; None: as evaluated), for the colour maps."""

    characteristics: list
    verdict: str
    face: np.ndarray = field(repr=False)
    points: np.ndarray = field(repr=False)
    frames: dict = field(default_factory=dict, repr=False)
    units: str | None = None
    align: str = "datums"
    assignment: dict = field(default_factory=dict)
    source: str = ""
    deviation: np.ndarray = field(default=None, repr=False)
    shown_in: str | None = None
    shown_points: np.ndarray = field(default=None, repr=False)

    def counts(self) -> dict:
        out = {"pass": 0, "fail": 0, "not evaluated": 0}
        for c in self.characteristics:
            out[c.status] += 1
        return out

    def to_dict(self) -> dict:
        return {"characteristics": [c.to_dict() for c in self.characteristics],
                "verdict": self.verdict, "counts": self.counts(), "units": self.units,
                "align": self.align, "assignment": jsonable(self.assignment),
                "frames": jsonable(self.frames), "source": self.source}


def assign_faces(surfaces, points, max_distance, exclude=()):
    """Face of each point's exact foot (-1 beyond ``max_distance`` or not found) and
    its signed distance; the faces ``exclude`` (loose faces duplicating a solid's
    face) take no points."""
    keep = [i for i in range(len(surfaces)) if i not in set(exclude)] or \
        list(range(len(surfaces)))
    pr = project_points([surfaces[i] for i in keep], points, max_distance)
    face = np.asarray(keep, np.int64)[np.maximum(np.asarray(pr.surface, np.int64), 0)]
    bad = (pr.status == BEYOND) | (pr.status == FAILED) | ~np.isfinite(pr.signed_distance)
    face[bad] = -1
    return face, np.where(bad, np.nan, pr.signed_distance)


class _Context:
    """What the evaluators share: points by face, face shapes, frames, units."""

    def __init__(self, part, surfaces, pmi, P, face, units, align, tolerances):
        self.surfaces, self.pmi, self.P, self.face = surfaces, pmi, P, face
        self.units, self.align = units, align
        self.size = max(s.size for s in surfaces)
        self.all_faces = sorted(int(f) for f in np.unique(face[face >= 0]))
        # the faces of the tolerances evaluated and of the datums they refer to
        labels = {r.label for t in tolerances for r in t.datums}
        need = {int(f) for t in tolerances for f in t.faces}
        need |= {int(f) for d in pmi.datums if d.label in labels for f in d.faces}
        need = sorted(f for f in need if 0 <= f < len(surfaces))
        self._shapes = {}
        self.flipped = set()      # faces whose S_u x S_v points into the material
        if need:       # one exact sample of every face the PMI names (one ray vote)
            # the part itself (not only its surfaces): its duplicate loose faces
            # stay out of the ray vote
            src = part if hasattr(part, "surfaces") else surfaces
            smp = sample_faces(src, NOMINAL_SAMPLES, faces=need, seed=1)
            self._shapes = face_shapes(surfaces, need, sampled=smp)
            self.flipped = {int(f) for f, v in smp.orientation.items() if v == "flipped"}
        self._frames = {}
        self._by_face = {}
        for f in self.all_faces:
            self._by_face[f] = np.nonzero(face == f)[0]

    # ---- units
    def length_scale(self, unit):
        """Model units per ``unit`` (None: unknown)."""
        mu = MM_PER_UNIT.get(self.units or "mm")
        if unit not in MM_PER_UNIT or mu is None:
            return None
        return MM_PER_UNIT[unit] / mu

    def tolerance_value(self, tol):
        s = self.length_scale(tol.unit)
        if s is None:
            raise NotEvaluated(f"the tolerance's unit {tol.unit!r} is not known")
        return float(tol.value) * s

    # ---- points and faces
    def indices(self, faces):
        parts = [self._by_face.get(int(f), np.zeros(0, np.int64)) for f in faces]
        return np.concatenate(parts) if parts else np.zeros(0, np.int64)

    def shapes(self, faces):
        todo = [f for f in faces if f not in self._shapes]
        if todo:
            self._shapes.update(face_shapes(self.surfaces, todo))
        return {f: self._shapes[f] for f in faces}

    # ---- frames
    def to_part_dir(self, d, frames):
        meas_f, nom_f = frames
        return meas_f.axes.T @ (nom_f.axes @ d)

    def to_part_point(self, p, frames):
        meas_f, nom_f = frames
        return meas_f.to_part(nom_f.to_datum(np.asarray(p)[None, :]))[0]

    def _datum(self, label, measured):
        d = next((d for d in self.pmi.datums if d.label == label), None)
        if d is None:
            raise NotEvaluated(f"datum {label} is referenced but not defined in the PMI")
        unread = [-1 - f for f in d.faces if f < 0]
        if unread:
            raise NotEvaluated(f"datum {label}: face(s) {', '.join(map(str, unread))} "
                               "of the file were left out of the read")
        if not d.faces:
            what = "datum targets" if d.targets else "no face"
            raise NotEvaluated(f"datum {label} is defined by {what} (not supported)")
        feats = group_features(self.shapes(d.faces), d.faces, self.size)
        if len(feats) == 2 and all(f.kind == "plane" for f in feats) and \
                float(feats[0].direction @ feats[1].direction) < -1 + 1e-9:
            return self._width_datum(label, feats, measured)
        if len(feats) != 1:
            raise NotEvaluated(f"datum {label} on {len(feats)} features (faces "
                               f"{', '.join(map(str, d.faces))}) is not supported")
        f = feats[0]
        kind = {"plane": "plane", "cylinder": "cylinder", "sphere": "sphere"}.get(f.kind)
        if kind is None:
            raise NotEvaluated(f"datum {label} on a {f.kind} face is not supported")
        P = self._datum_points(label, f, measured)
        feature = None if f.internal is None else ("internal" if f.internal else
                                                   "external")
        return gdt.Datum(label, kind, P, feature=feature,
                         normal=f.direction if kind == "plane" else None,
                         axis=f.direction if kind == "cylinder" else None)

    def _datum_points(self, label, f, measured):
        if not measured:
            return f.points
        idx = self.indices(f.faces)
        if idx.size < NEED[f.kind]:
            raise NotEvaluated(f"datum {label}: {idx.size} point(s) on its face(s) "
                               f"{', '.join(map(str, f.faces))}, needs at least "
                               f"{NEED[f.kind]}")
        return self.P[idx]

    def _width_datum(self, label, feats, measured):
        """A width datum (two opposed parallel planes): each side moved half the
        nominal width toward the median plane, one least-squares plane."""
        a, b = feats
        half = 0.5 * float((b.point - a.point) @ a.direction)
        parts = []
        for f, sgn in ((a, 1.0), (b, -1.0)):
            P = self._datum_points(label, f, measured)
            parts.append(P + (sgn * half) * a.direction)
        return gdt.Datum(label, "plane", np.vstack(parts), method="lsq",
                         normal=a.direction)

    def frames(self, tol):
        labels = tuple(r.label for r in tol.datums)
        if len(labels) > 3:
            raise NotEvaluated(f"{len(labels)} datums: at most 3 are supported")
        for r in tol.datums:
            if "-" in r.label or len(r.datums) != 1:
                raise NotEvaluated(f"common datum {r.label} is not supported")
            if r.modifiers:
                raise NotEvaluated(f"datum modifier {r.modifiers[0]} on {r.label} is "
                                   "not supported")
        key = "|".join(labels)
        if key not in self._frames:
            try:
                nom = gdt.datum_frame(*[self._datum(lb, False) for lb in labels])
                if self.align == "datums":
                    meas = _pin_free(gdt.datum_frame(
                        *[self._datum(lb, True) for lb in labels]), nom)
                else:
                    meas = nom
                self._frames[key] = (meas, nom)
            except NotEvaluated as exc:
                self._frames[key] = str(exc)
            except GeomkitError as exc:
                self._frames[key] = f"datum frame {key}: {exc}"
        got = self._frames[key]
        if isinstance(got, str):
            raise NotEvaluated(got)
        return got


def _remap(pmi, entities, n):
    """The PMI with its face indices (``read_step``'s face order) turned into
    positions in ``surfaces``: they differ when faces were left out of the read
    (``skip_unsupported`` / ``skip_invalid``); a face that was not read maps to
    ``-1 - index`` (its characteristic is then not evaluated, naming it)."""
    if entities is None or list(entities) == list(range(n)):
        return pmi
    pos = {int(e): i for i, e in enumerate(entities)}

    def faces(fs):
        return [pos.get(int(f), -1 - int(f)) for f in fs]

    return replace(
        pmi,
        tolerances=[replace(t, faces=faces(t.faces)) for t in pmi.tolerances],
        datums=[replace(d, faces=faces(d.faces)) for d in pmi.datums],
        dimensions=[replace(d, faces=faces(d.faces)) for d in pmi.dimensions])


def _pin_free(meas, nom):
    """The measured frame with its free translations placed as the nominal frame's
    (the datums leave them to the association's starting point; the zone floats in
    them anyway, and the characteristics start from the nominal placement)."""
    o = meas.origin.copy()
    for name in meas.free:
        if name[0] == "t":
            a = meas.axes["xyz".index(name[1])]
            o = o + float((nom.origin - o) @ a) * a
    T = meas.transform.copy()
    T[:3, 3] = -meas.axes @ o
    return replace(meas, origin=o, transform=T)


def _tol_dict(t, T, units):
    d = {"value": T, "unit": units, "file_value": t.value, "file_unit": t.unit,
         "zone": t.zone, "diameter": t.diameter, "modifiers": list(t.modifiers)}
    if t.extra:
        d["extra"] = jsonable(t.extra)
    return d


def _check_align(align):
    if align not in ALIGN_MODES:
        raise InvalidInputError(f"expected one of {', '.join(ALIGN_MODES)}, got "
                                f"{align!r}", "align")
    return align


def inspect_part(part, pmi, points, face=None, *, align: str = "datums",
                 max_distance: float | None = None, tolerances=None) -> Inspection:
    """Evaluate every geometric tolerance of a part's PMI on measured points.

    Parameters
    ----------
    part : IgesResult (``read_step``) or list of Surface
        The nominal; its face order is the PMI's.
    pmi : Pmi
        :func:`geomkit.read_pmi` of the same file.
    points : (n, 3) float
        Measured points (roughly in CAD coordinates: nominal normals say on which
        side the material is).
    face : (n,) int, optional
        The face of each point (e.g. the ``face`` column of ``geomkit sample``);
        default: the face of its exact foot.
    align : {"datums", "bestfit", "none"}
        ``datums``: each characteristic in its measured datum reference frame
        (module doc); ``bestfit``: the points best-fitted to the whole part first,
        characteristics then in the nominal frames; ``none``: the points taken as
        CAD coordinates.
    max_distance : float, optional
        Points farther from every face are left out when faces are found by
        projection (default 2 % of the part size).
    tolerances : list of Tolerance, optional
        A subset of ``pmi.tolerances`` to evaluate.

    Returns
    -------
    Inspection
    """
    _check_align(align)
    surfaces = list(getattr(part, "surfaces", part))
    units = getattr(part, "units", None)
    if not surfaces:
        raise InvalidInputError("the part has no faces", "part")
    P = np.asarray(points, dtype=np.float64)
    if P.ndim != 2 or P.shape[1] != 3 or P.shape[0] == 0:
        raise InvalidInputError(f"expected (n, 3) points, got shape {P.shape}", "points")
    if not np.isfinite(P).all():
        raise InvalidInputError("non-finite point coordinates", "points")
    size = max(s.size for s in surfaces)
    md = REL_MAX_DISTANCE * size if max_distance is None else float(max_distance)
    info = {"given": face is not None}
    if align == "bestfit":
        al = align_rigid(surfaces, P, max_distance=md)
        T = al["transform"]
        P = P @ T[:3, :3].T + T[:3, 3]
        info["bestfit"] = {k: al[k] for k in ("rms_before", "rms_after", "iterations",
                                              "converged")}
    if face is None:
        F, _ = assign_faces(surfaces, P, md, getattr(part, "duplicates", None) or {})
    else:
        F = np.asarray(face)
        if F.shape != (P.shape[0],) or not np.issubdtype(F.dtype, np.integer):
            raise InvalidInputError(f"expected {P.shape[0]} integer face ids, got shape "
                                    f"{F.shape} of {F.dtype}", "face")
        bad = np.nonzero((F < -1) | (F >= len(surfaces)))[0]
        if bad.size:
            raise InvalidInputError(f"point {int(bad[0])}: face {int(F[bad[0]])} is out "
                                    f"of range (the part has {len(surfaces)} faces)",
                                    "face")
        F = F.astype(np.int64)
    info.update(points=int(P.shape[0]), assigned=int((F >= 0).sum()),
                left_out=int((F < 0).sum()), max_distance=md)
    file_faces = {t.id: list(t.faces) for t in pmi.tolerances}
    pmi = _remap(pmi, getattr(part, "entities", None), len(surfaces))
    tols = pmi.tolerances if tolerances is None else \
        [t for t in pmi.tolerances if t.id in {u.id for u in tolerances}]
    ctx = _Context(part, surfaces, pmi, P, F, units, align, tols)
    lower = {o for t in pmi.tolerances for k, o in t.related if k == "composite"}
    rows = []
    for t in tols:
        T = None
        try:
            T = ctx.tolerance_value(t) if t.value is not None else None
        except NotEvaluated:
            pass
        where = ctx.all_faces if t.whole_part else [f for f in t.faces if f >= 0]
        ent = getattr(part, "entities", None)
        base = dict(id=f"#{t.id}", type=t.type, surfaces=where,
                    faces=([int(ent[i]) for i in where] if ent is not None else where)
                    if t.whole_part else file_faces[t.id],
                    tolerance=_tol_dict(t, T, units), datums=t.datum_labels)
        try:
            r = evaluate(t, ctx, lower=t.id in lower)
        except NotEvaluated as exc:
            rows.append(CharacteristicRow(**base, status="not evaluated",
                                          n_points=int(ctx.indices(where).size),
                                          reason=str(exc)))
            continue
        rows.append(CharacteristicRow(
            **base, status="pass" if r["passed"] else "fail",
            measured=float(r["measured"]), limit=float(r["limit"]),
            n_points=int(sum(f["n_points"] for f in r["features"])),
            features=r["features"], deciding=r["deciding"]))
    if any(r.status == "fail" for r in rows):
        verdict = "fail"
    elif any(r.status == "not evaluated" for r in rows) or not rows:
        verdict = "incomplete"
    else:
        verdict = "pass"
    frames, shown, X = {}, None, P
    for k, v in ctx._frames.items():
        frames[k] = v if isinstance(v, str) else v[0].to_dict()
        if shown is None and not isinstance(v, str) and not v[1].free:
            shown, X = k, gdt.align_to_cad(P, *v)
    return Inspection(rows, verdict, F, P, frames, units, align, info,
                      getattr(pmi, "source", ""),
                      _own_face_deviation(surfaces, X, F, ctx.flipped), shown, X)


def _own_face_deviation(surfaces, X, F, flipped):
    """Signed distance of each point to its own face, outward positive on the faces
    whose orientation is known (NaN: no face, no foot)."""
    d = np.full(X.shape[0], np.nan)
    for f in np.unique(F[F >= 0]):
        m = F == f
        pr = project_points([surfaces[int(f)]], X[m])
        ok = (pr.status != BEYOND) & (pr.status != FAILED)
        d[np.nonzero(m)[0][ok]] = pr.signed_distance[ok] * (-1.0 if int(f) in flipped
                                                             else 1.0)
    return d
