"""One PMI tolerance evaluated on measured points (private to
:mod:`geomkit.jobs.inspect`).

:func:`evaluate` turns a :class:`geomkit.cad.steppmi_types.Tolerance` into calls of
:mod:`geomkit.gdt`: the tolerance's faces become features
(:mod:`geomkit.jobs.features`), each feature is evaluated on the points assigned to
its faces, and the characteristic is the worst feature.  What cannot be evaluated
raises :class:`NotEvaluated` with the reason.
"""

from __future__ import annotations

import math

import numpy as np

from geomkit import gdt
from geomkit.errors import GeomkitError
from geomkit.jobs.features import group_features

__all__ = ["NotEvaluated", "evaluate", "LOWER_SEGMENT", "NEED"]

#: Least points a feature of each kind needs.
NEED = {"plane": 3, "cylinder": 8, "sphere": 6, "cone": 8, "freeform": 3, "width": 6}
LOWER_SEGMENT = "lower"

_MATERIAL = {"maximum_material_requirement": "MMC", "least_material_requirement": "LMC"}
_UNSUPPORTED_MODIFIERS = {
    "free_state": "free state (F)",
    "tangent_plane": "a tangent plane (T)",
    "common_zone": "a common zone (CZ)",
}


class NotEvaluated(Exception):
    """The characteristic cannot be evaluated; ``str(exc)`` says why."""


def _points(ctx, feat, what):
    idx = ctx.indices(feat.faces)
    need = NEED[feat.kind]
    if idx.size < need:
        raise NotEvaluated(f"{what} needs at least {need} points on face(s) "
                           f"{_faces(feat.faces)}, got {idx.size}")
    return idx


def _faces(faces):
    return ", ".join(str(f) for f in faces)


def _widths(feats):
    """Pairs of parallel planes of opposed outward normals (a slot or a tab) as one
    ``width`` feature each; other features unchanged."""
    planes = [f for f in feats if f.kind == "plane"]
    rest = [f for f in feats if f.kind != "plane"]
    used, out = set(), []
    for i, a in enumerate(planes):
        if i in used:
            continue
        for j in range(i + 1, len(planes)):
            b = planes[j]
            if j not in used and float(a.direction @ b.direction) < -1 + 1e-9:
                used |= {i, j}
                out.append(("width", a, b))
                break
        else:
            out.append(("single", a, None))
    return out, rest


def _width_center(Pa, Pb, a, b, ctx, frames):
    """Position of a width feature's centre plane along the fixed nominal normal:
    each side's contact (the point farthest along its outward normal, the
    orientation-constrained mating envelope) and their mean, against the nominal
    centre plane.  Returns (offset, deciding local indices, width)."""
    n = ctx.to_part_dir(a.direction, frames)
    half = 0.5 * float((b.point - a.point) @ a.direction)
    center_nom = ctx.to_part_point(a.point + half * a.direction, frames)
    ta = (Pa - center_nom) @ n
    tb = (Pb - center_nom) @ (-n)
    ia, ib = int(np.argmax(ta)), int(np.argmax(tb))
    side_a, side_b = float(ta[ia]), -float(tb[ib])
    return 0.5 * (side_a + side_b), (ia, ib), abs(side_a - side_b)


def _result(per):
    """Combine per-feature results (dicts with measured, limit, passed, deciding)."""
    worst = max(per, key=lambda r: r["measured"] / r["limit"] if r["limit"] else math.inf)
    return {"measured": worst["measured"], "limit": worst["limit"],
            "passed": all(r["passed"] for r in per), "features": per,
            "deciding": np.unique(np.concatenate([r["deciding"] for r in per]))}


def _from_char(ch, idx, faces, limit=None, extra=None):
    m = ch.measured if not isinstance(ch.measured, tuple) else max(ch.measured)
    lim = limit if limit is not None else ch.tolerance.get("total", ch.tolerance["zone"])
    if isinstance(lim, tuple):
        lim = min(lim)
    out = {"faces": list(faces), "measured": float(m), "limit": float(lim),
           "passed": bool(ch.passed), "deciding": idx[np.asarray(ch.deciding, int)],
           "n_points": int(ch.n_points)}
    out.update(extra or {})
    return out


# ------------------------------------------------------------------ per type

def _form(tol, T, feats, ctx):
    kinds = {"flatness": ("plane",), "cylindricity": ("cylinder",),
             "sphericity": ("sphere",), "roundness": ("cylinder", "cone", "sphere")}
    per = []
    for f in feats:
        if f.kind not in kinds[tol.type]:
            raise NotEvaluated(f"{tol.type} of a {f.kind} face ({_faces(f.faces)}) is "
                               "not supported")
        idx = _points(ctx, f, tol.type)
        P = ctx.P[idx]
        if tol.type == "flatness":
            ch = gdt.flatness(P, T)
        elif tol.type == "cylindricity":
            ch = gdt.cylindricity(P, T)
        elif tol.type == "sphericity":
            ch = gdt.sphericity(P, T)
        else:
            ch, idx = _roundness(P, idx, T, f, ctx)
        per.append(_from_char(ch, idx, f.faces))
    return per


def _roundness(P, idx, T, f, ctx):
    """Circularity in the cross-sections the points form (clusters of the axial
    coordinate); the worst section."""
    if f.kind == "sphere":
        raise NotEvaluated("roundness of a sphere needs its section planes")
    a = f.direction
    s = P @ a
    order = np.argsort(s)
    gap = 1e-3 * max(float(s.max() - s.min()), 1e-12)
    cuts = np.nonzero(np.diff(s[order]) > gap)[0] + 1
    best = None
    for g in np.split(order, cuts):
        if g.size < 6:
            continue
        ch = gdt.circularity(P[g], T, normal=a)
        if best is None or ch.measured > best[0].measured:
            best = (ch, idx[g])
    if best is None:
        raise NotEvaluated("roundness needs points in cross-sections (6 or more points "
                           "at one axial position)")
    return best


def _orientation(tol, T, feats, ctx, frames):
    meas_f, nom_f = frames
    label = tol.datums[0].label
    dn = nom_f.datum(label)
    per = []
    for f in feats:
        if f.kind not in ("plane", "cylinder"):
            raise NotEvaluated(f"{tol.type} of a {f.kind} feature is not supported")
        idx = _points(ctx, f, tol.type)
        P = ctx.P[idx]
        feature = "plane" if f.kind == "plane" else "axis"
        kw = {}
        if feature == "axis":
            kw["diameter"] = bool(tol.diameter) or None
        if tol.type == "angularity":
            c = abs(float(f.direction @ dn.direction))
            same = (feature == "plane") == (dn.element == "plane")
            ang = math.degrees(math.acos(min(c, 1.0)) if same else math.asin(min(c, 1.0)))
            ch = gdt.angularity(P, T, meas_f, ang, datum=label, feature=feature, **kw)
        else:
            fn = gdt.parallelism if tol.type == "parallelism" else gdt.perpendicularity
            ch = fn(P, T, meas_f, datum=label, feature=feature, **kw)
        r = _from_char(ch, idx, f.faces)
        proj = _projected(tol, ctx)
        if proj is not None:
            if feature != "axis":
                raise NotEvaluated("a projected zone (P) on a plane is not supported")
            e1, e2 = ch.details["axis_ends"]
            u = (e2 - e1) / max(float(np.linalg.norm(e2 - e1)), 1e-300)
            z = ch.details["zone"]
            if z["shape"] == "cylinder":
                v = z["axis"]
                r["measured"] = proj * float(np.linalg.norm(u - (u @ v) * v))
            else:
                r["measured"] = proj * abs(float(z["normal"] @ u))
            r["passed"] = bool(r["measured"] <= r["limit"])
            r["note"] = f"projected zone: the axis direction over {proj:.6g}"
        per.append(r)
    return per


def _size_limits(tol, f, ctx):
    """(smallest, largest) diameter of the feature from a size dimension on its
    faces, model units; None when the file gives none."""
    for d in ctx.pmi.dimensions:
        if d.kind != "size" or not set(d.faces) & set(f.faces):
            continue
        if d.limits is not None:
            lo, hi = d.limits
        elif d.value is not None and d.lower is not None and d.upper is not None:
            lo, hi = d.value + d.lower, d.value + d.upper
        else:
            continue
        scale = ctx.length_scale(d.unit)
        if scale is None:
            continue
        if d.name and "radius" in d.name:
            lo, hi = 2 * lo, 2 * hi
        return (lo * scale, hi * scale)
    return None


def _projected(tol, ctx):
    """The projected length (model units) of a projected zone (P), else None."""
    if "projected" not in tol.modifiers:
        return None
    v = tol.extra.get("projected_length")
    if v is None:
        raise NotEvaluated("a projected zone (P) without its projected length")
    scale = ctx.length_scale(v[1] if isinstance(v, (list, tuple)) else tol.unit)
    if scale is None:
        raise NotEvaluated("a projected length in a unit geomkit does not know")
    return float(v[0] if isinstance(v, (list, tuple)) else v) * scale


def _extend(ends, length):
    """A feature's axis ends and the ends of its axis extended ``length`` beyond each
    end (the projected zone: the file does not say on which side the mating part
    sits, so both sides are checked and the worse counts)."""
    e1, e2 = ends
    u = (e2 - e1) / max(float(np.linalg.norm(e2 - e1)), 1e-300)
    return np.array([e1 - length * u, e1, e2, e2 + length * u])


def _position(tol, T, feats, ctx, frames, lower=False):
    meas_f, nom_f = frames
    material = next((_MATERIAL[m] for m in tol.modifiers if m in _MATERIAL), None)
    proj = _projected(tol, ctx)
    planes_paired, rest = _widths(feats)
    if lower and (planes_paired or any(f.kind != "cylinder" for f in rest)):
        raise NotEvaluated("the lower segment of a composite position is evaluated for "
                           "holes and shafts only")
    per, axes = [], []
    for kind, a, b in planes_paired:
        if kind != "width":
            raise NotEvaluated(f"position of a single plane (face {_faces(a.faces)}) "
                               "is not supported")
        ia, ib = _points(ctx, a, "a width feature"), _points(ctx, b, "a width feature")
        off, (ja, jb), width = _width_center(ctx.P[ia], ctx.P[ib], a, b, ctx, frames)
        measured = 2.0 * abs(off)
        per.append({"faces": a.faces + b.faces, "measured": measured, "limit": T,
                    "passed": measured <= T, "deciding": np.array([ia[ja], ib[jb]]),
                    "n_points": int(ia.size + ib.size), "width": width,
                    "note": "centre plane of the width (material modifier not applied)"
                    if material else "centre plane of the width"})
    for f in rest:
        if f.kind not in ("cylinder", "sphere"):
            raise NotEvaluated(f"position of a {f.kind} feature is not supported")
        idx = _points(ctx, f, "position")
        P = ctx.P[idx]
        nominal = nom_f.to_datum(f.point[None, :])[0]
        if f.kind == "sphere":
            ch = gdt.position(P, T, meas_f, nominal, feature="sphere")
            per.append(_from_char(ch, idx, f.faces))
            continue
        feature = "hole" if f.internal else "shaft"
        axis = nom_f.axes @ f.direction
        limits = _size_limits(tol, f, ctx) if material else None
        note = None
        if material and limits is None:
            note = f"{material} bonus not applied: no size limits for the feature"
        ch = gdt.position(P, T, meas_f, nominal, feature=feature, axis=axis,
                          material=material if limits else None, size_limits=limits)
        extra = {"diameter": ch.details.get("diameter")}
        if note:
            extra["note"] = note
        if "bonus" in ch.tolerance:
            extra["bonus"] = ch.tolerance["bonus"]
        r = _from_char(ch, idx, f.faces, extra=extra)
        ends = np.asarray(ch.details["axis_ends"])
        if proj is not None:
            ends = _extend(ends, proj)
            r["measured"] = 2.0 * float(np.linalg.norm(
                (ends - nominal) - np.outer((ends - nominal) @ axis, axis), axis=1).max())
            r["passed"] = bool(r["measured"] <= r["limit"]
                               and ch.details.get("size_ok", True))
            r["note"] = (f"projected zone: the axis extended {proj:.6g} beyond both ends, "
                         "the worse side")
        per.append(r)
        axes.append((ends, nominal, axis, ch.details.get("size_ok", True)))
    if lower:
        free = tuple(sorted(set(nom_f.free) | {"tx", "ty", "tz"}))
        got, motion = gdt.float_pattern([a[0] for a in axes], [a[1] for a in axes],
                                        [a[2] for a in axes], [r["limit"] for r in per],
                                        free)
        for r, m, a in zip(per, got, axes):
            r["measured"] = float(m)
            r["passed"] = bool(m <= r["limit"] and a[3])
            r["note"] = ("lower segment: the pattern's zones moved together in "
                         f"{', '.join(free)} (orientation to the datums kept)")
    return per


def _profile(tol, T, faces, ctx, frames, lower):
    idx = ctx.indices(faces)
    if idx.size < 3:
        raise NotEvaluated(f"profile needs at least 3 points on face(s) {_faces(faces)}, "
                           f"got {idx.size}")
    surfs = [ctx.surfaces[f] for f in faces]
    local = {f: k for k, f in enumerate(faces)}
    owner = np.array([local[int(f)] for f in ctx.face[idx]], np.int64)
    U = tol.extra.get("displacement")
    unequal = None
    if U is not None:
        val = U[0] if isinstance(U, (list, tuple)) else U
        scale = ctx.length_scale(U[1] if isinstance(U, (list, tuple)) else tol.unit)
        if scale is None:
            raise NotEvaluated("unequal zone in a unit geomkit does not know")
        unequal = float(val) * scale + T / 2       # AP242 displacement: the UZ offset
    if frames is None:
        ch = gdt.profile_surface(ctx.P[idx], surfs, T, unequal=unequal, surface_of=owner)
    else:
        meas_f, nom_f = frames
        X = gdt.align_to_cad(ctx.P[idx], meas_f, nom_f)
        free = None
        if lower:                                  # orientation only: translations float
            free = tuple(sorted(set(nom_f.free) | {"tx", "ty", "tz"}))
        ch = gdt.profile_surface(X, surfs, T, frame=nom_f, unequal=unequal,
                                 free=free or nom_f.free, surface_of=owner)
    return [_from_char(ch, idx, faces, extra={
        "range": ch.details["range"], "deviation_points": idx,
        "deviation": ch.details["deviation"]})]


def _runout(tol, T, feats, ctx, frames):
    meas_f, _ = frames
    direction = "radial"
    per = []
    for f in feats:
        if f.kind == "plane":
            direction = "axial"
        elif f.kind not in ("cylinder", "cone", "sphere", "freeform"):
            raise NotEvaluated(f"runout of a {f.kind} feature is not supported")
        idx = _points(ctx, f, tol.type)
        if tol.type == "total_runout":
            ch = gdt.total_runout(ctx.P[idx], meas_f, T, direction=direction)
        else:
            L = float(np.ptp(ctx.P[idx] @ meas_f.axes[2])) or 1.0
            ch = gdt.circular_runout(ctx.P[idx], meas_f, T, width=1e-3 * L,
                                     direction=direction)
        per.append(_from_char(ch, idx, f.faces))
    return per


def evaluate(tol, ctx, lower: bool = False) -> dict:
    """Evaluate one tolerance; the combined result (``measured``, ``limit``,
    ``passed``, ``features``, ``deciding``) or :class:`NotEvaluated`."""
    if tol.value is None:
        raise NotEvaluated("the tolerance has no value")
    T = ctx.tolerance_value(tol)
    bad = [v for k, v in _UNSUPPORTED_MODIFIERS.items() if k in tol.modifiers]
    if bad:
        raise NotEvaluated(f"{bad[0]} is not supported")
    faces = ctx.all_faces if tol.whole_part else list(tol.faces)
    unread = [-1 - f for f in faces if f < 0]
    if unread:
        raise NotEvaluated(f"face(s) {_faces(unread)} of the file were left out of the "
                           "read")
    if not faces:
        raise NotEvaluated("applies to no face (edges and curves are not evaluated)"
                           if tol.items else "applies to no face")
    frames = ctx.frames(tol) if tol.datums else None
    if tol.type == "surface_profile":
        return _result(_profile(tol, T, faces, ctx, frames, lower))
    feats = group_features(ctx.shapes(faces), faces, ctx.size)
    try:
        if tol.type in ("flatness", "cylindricity", "sphericity", "roundness"):
            per = _form(tol, T, feats, ctx)
        elif tol.type in ("parallelism", "perpendicularity", "angularity"):
            per = _orientation(tol, T, feats, ctx, frames)
        elif tol.type in ("position", "coaxiality"):
            if frames is None:
                raise NotEvaluated(f"{tol.type} without datums is not supported")
            per = _position(tol, T, feats, ctx, frames, lower)
        elif tol.type in ("circular_runout", "total_runout"):
            per = _runout(tol, T, feats, ctx, frames)
        else:
            raise NotEvaluated(f"{tol.type.replace('_', ' ')} is not supported")
    except GeomkitError as exc:
        raise NotEvaluated(f"{type(exc).__name__}: {exc}") from None
    return _result(per)
