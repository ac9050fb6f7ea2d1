"""Probe safety: certified clearance of a CMM stylus moved along a path past NURBS parts.

A stylus is a tip sphere, a shaft, and optionally an extension and a probe body, all
on one axis (:class:`Stylus`).  Each piece is modelled as a *capsule* — the set of
points within ``radius`` of an axis segment (the tip: a segment of length 0).  For a
shaft, extension or body the capsule contains the cylinder, so a clearance computed
with it can only be *smaller* than the cylinder's (safe side); it is the cylinder's
exactly wherever the closest point is not in a rounded end, and the rounded ends of a
shaft are inside the tip ball and the extension when those are at least as thick.

Between consecutive poses the stylus moves by a rigid motion about a fixed axis: a pure
translation (straight moves) or a rotation about a fixed line (probe-head indexing).
The set swept by a capsule's axis segment is then an exact NURBS surface — a bilinear
parallelogram for a translation, a rational (2, 1) ruled surface of circular arcs for a
rotation — and the clearance of the moving capsule over the segment is exactly

    clearance = distance(swept axis surface, part) - radius

computed by :func:`geomkit.surface_distance` on the exact surfaces with a certified
interval (Bézier hull branch and bound + Newton), not on a tessellation.  The first
contact parameter of a colliding segment is found by bisection on the sweep of the
prefix [0, s] (its clearance decreases with s), each step decided by certified bounds.
"""

from __future__ import annotations

import dataclasses
import json
import math
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from scipy.spatial.transform import Rotation

from geomkit.tolerances import SCREW_REL
from geomkit.validate import as_float_array
from geomkit.query.distance import surface_distance
from geomkit.errors import InvalidInputError
from geomkit.nurbs.surface import Surface, as_surfaces

__all__ = ["Stylus", "Clearance", "probe_clearance", "read_path", "STYLUS_KEYS"]

STYLUS_KEYS = ("tip_radius", "shaft_radius", "shaft_length", "extension_radius",
                "extension_length", "body_radius", "body_length")
MAX_BISECTIONS = 60


@dataclass(frozen=True)
class Stylus:
    """A CMM stylus in its own frame: tip centre at the origin, axis along +z toward the
    probe head.  Lengths and radii in model units.

    tip_radius : ball radius (> 0).
    shaft_radius, shaft_length : shaft from the tip centre up (> 0 both).
    extension_radius, extension_length : optional extension above the shaft (0 = none).
    body_radius, body_length : optional probe body above the extension (0 = none).
    """

    tip_radius: float
    shaft_radius: float
    shaft_length: float
    extension_radius: float = 0.0
    extension_length: float = 0.0
    body_radius: float = 0.0
    body_length: float = 0.0

    def __post_init__(self):
        for k in STYLUS_KEYS:
            v = getattr(self, k)
            try:
                v = float(v)
            except (TypeError, ValueError):
                raise InvalidInputError(f"expected a number, got {v!r}", f"stylus.{k}") from None
            if not math.isfinite(v) or v < 0:
                raise InvalidInputError(f"expected a finite number >= 0, got {v!r}",
                                        f"stylus.{k}")
            object.__setattr__(self, k, v)
        for k in ("tip_radius", "shaft_radius", "shaft_length"):
            if getattr(self, k) <= 0:
                raise InvalidInputError("must be > 0", f"stylus.{k}")
        for part in ("extension", "body"):
            r, h = getattr(self, f"{part}_radius"), getattr(self, f"{part}_length")
            if (r > 0) != (h > 0):
                raise InvalidInputError(f"give both {part}_radius and {part}_length > 0, "
                                        f"or neither (got {r:g}, {h:g})", f"stylus.{part}")

    @classmethod
    def from_dict(cls, d: dict) -> "Stylus":
        if not isinstance(d, dict):
            raise InvalidInputError(f"expected an object, got {type(d).__name__}", "stylus")
        unknown = sorted(set(d) - set(STYLUS_KEYS))
        if unknown:
            raise InvalidInputError(f"unknown key(s) {unknown}; allowed: "
                                    f"{', '.join(STYLUS_KEYS)}", "stylus")
        missing = [k for k in STYLUS_KEYS[:3] if k not in d]
        if missing:
            raise InvalidInputError(f"missing key(s) {missing}", "stylus")
        return cls(**d)

    @classmethod
    def from_json(cls, path) -> "Stylus":
        try:
            d = json.loads(Path(path).read_text(encoding="utf-8"))
        except json.JSONDecodeError as exc:
            raise InvalidInputError(f"not valid JSON ({exc.msg}, line {exc.lineno})",
                                    str(path)) from None
        return cls.from_dict(d)

    def to_dict(self) -> dict:
        return {k: getattr(self, k) for k in STYLUS_KEYS}

    @property
    def length(self) -> float:
        return self.shaft_length + self.extension_length + self.body_length

    def components(self) -> list[tuple[str, np.ndarray, np.ndarray, float]]:
        """``(name, start, end, radius)`` of each capsule, in the stylus frame."""
        z = np.array([0.0, 0.0, 1.0])
        out = [("tip", np.zeros(3), np.zeros(3), self.tip_radius),
               ("shaft", np.zeros(3), self.shaft_length * z, self.shaft_radius)]
        top = self.shaft_length
        for part in ("extension", "body"):
            r, h = getattr(self, f"{part}_radius"), getattr(self, f"{part}_length")
            if h > 0:
                out.append((part, top * z, (top + h) * z, r))
                top += h
        return out


@dataclass
class Clearance:
    """Result of :func:`probe_clearance`, one row per path segment.

    Attributes
    ----------
    clearance : (m,) float, the smallest gap between the stylus and the part over the
        segment (0 when they touch or overlap): the gap of a real pair of points, so an
        upper bound of the exact value.
    lower_bound : (m,) float, certified lower bound of the exact gap
        (``clearance - lower_bound <= tol`` when ``certified``).
    component : (m,) int, which stylus piece (index into ``component_names``) is closest.
    parameter : (m,) float in [0, 1], where on the segment the smallest gap occurs.
    point_part, point_stylus : (m, 3) float, the closest points (world).
    surface : (m,) int, the part surface holding ``point_part``.
    first_contact : (m,) float in [0, 1], the segment parameter at which the stylus
        first touches the part (NaN for a clear segment); within ``contact_tol``.
    contact : (m,) bool, contact is certain (the gap's upper bound is 0).
    passed : (m,) bool, the certified gap is >= ``margin`` and there is no contact.
    certified : (m,) bool, every distance of the segment reached ``tol``.
    per_component : (m, c) float, each piece's clearance.
    component_names : tuple of str.
    margin, tol : float; motion : (m,) str, "translation", "rotation" or "rest".
    """

    clearance: np.ndarray
    lower_bound: np.ndarray
    component: np.ndarray
    parameter: np.ndarray
    point_part: np.ndarray = field(repr=False)
    point_stylus: np.ndarray = field(repr=False)
    surface: np.ndarray = field(repr=False)
    first_contact: np.ndarray
    contact: np.ndarray
    passed: np.ndarray
    certified: np.ndarray = field(repr=False)
    per_component: np.ndarray = field(repr=False)
    component_names: tuple
    margin: float
    tol: float
    motion: tuple = field(repr=False, default=())
    stats: dict = field(repr=False, default_factory=dict)

    def __len__(self) -> int:
        return len(self.clearance)

    @property
    def ok(self) -> bool:
        """Every segment passes."""
        return bool(np.all(self.passed))

    @property
    def worst(self) -> int:
        """Index of the segment with the smallest certified clearance."""
        return int(np.argmin(self.lower_bound))

    def summary(self) -> dict:
        w = self.worst
        fc = np.flatnonzero(np.isfinite(self.first_contact))
        return {"segments": len(self), "passed": self.ok,
                "failed_segments": np.flatnonzero(~self.passed).tolist(),
                "min_clearance": float(self.clearance[w]),
                "min_clearance_lower_bound": float(self.lower_bound[w]),
                "worst_segment": w, "worst_component": self.component_names[self.component[w]],
                "worst_parameter": float(self.parameter[w]),
                "worst_point_part": self.point_part[w].tolist(),
                "first_contact": None if fc.size == 0 else
                {"segment": int(fc[0]), "parameter": float(self.first_contact[fc[0]])},
                "margin": self.margin, "tol": self.tol,
                "certified": bool(np.all(self.certified)),
                "seconds": self.stats.get("seconds")}


def _as_poses(path, axis) -> np.ndarray:
    """(k, 4, 4) stylus -> world poses from points (tip centres) or poses."""
    P = as_float_array(path, "path")
    if P.ndim == 2 and P.shape[1] == 3:
        if P.shape[0] < 2:
            raise InvalidInputError(f"need at least 2 points, got {P.shape[0]}", "path")
        a = as_float_array(axis, "axis", shape=(3,))
        n = np.linalg.norm(a)
        if not np.isfinite(n) or n == 0:
            raise InvalidInputError(f"expected a non-zero direction, got {a.tolist()}", "axis")
        R = _frame_with_z(a / n)
        T = np.tile(np.eye(4), (P.shape[0], 1, 1))
        T[:, :3, :3] = R
        T[:, :3, 3] = P
        return T
    if P.ndim == 3 and P.shape[1:] == (4, 4):
        if P.shape[0] < 2:
            raise InvalidInputError(f"need at least 2 poses, got {P.shape[0]}", "path")
        for i, T in enumerate(P):
            R = T[:3, :3]
            if (np.abs(T[3] - [0, 0, 0, 1]).max() > 1e-12
                    or np.abs(R @ R.T - np.eye(3)).max() > 1e-9 or np.linalg.det(R) < 0):
                raise InvalidInputError("not a rigid pose (rotation must be orthonormal with "
                                        "det +1, last row 0 0 0 1)", f"path[{i}]")
        return P.copy()
    raise InvalidInputError(f"expected (k, 3) tip-centre points or (k, 4, 4) poses, got "
                            f"shape {P.shape}", "path")


def _frame_with_z(z) -> np.ndarray:
    """A rotation whose third column is the unit vector ``z``."""
    h = np.array([1.0, 0, 0]) if abs(z[0]) < 0.9 else np.array([0, 1.0, 0])
    x = np.cross(h, z)
    x /= np.linalg.norm(x)
    return np.column_stack([x, np.cross(z, x), z])


class _Motion:
    """The rigid motion of one segment: world point x at s = 0 -> its place at s."""

    def __init__(self, T0, T1, scale, index):
        M = T1 @ np.linalg.inv(T0)
        self.R = M[:3, :3]
        self.t = M[:3, 3]
        rv = Rotation.from_matrix(self.R).as_rotvec()    # angle in [0, pi]
        ang = float(np.linalg.norm(rv))
        k = rv / ang if ang >= 1e-14 else np.array([0.0, 0.0, 1.0])
        self.axis, self.angle = k, ang
        if ang < 1e-12:
            self.kind = "rest" if np.linalg.norm(self.t) <= 1e-15 * scale else "translation"
            return
        along = float(k @ self.t)
        if abs(along) > SCREW_REL * scale:
            raise InvalidInputError(
                f"the motion from pose {index} to {index + 1} rotates {math.degrees(ang):.6g} "
                f"deg and translates {along:.6g} along the rotation axis (a screw); split it "
                "into a translation and a rotation", "path")
        # a point c on the axis: (I - R) c = t restricted to the plane normal to k
        A = np.eye(3) - self.R + np.outer(k, k)
        self.centre = np.linalg.solve(A, self.t - along * k)
        self.kind = "rotation"

    def sweep(self, a, b, s_end=1.0) -> Surface:
        """The surface swept by segment a-b (world, at s = 0) for s in [0, s_end]:
        u = motion parameter / s_end, v = along a-b."""
        if self.kind in ("translation", "rest"):
            d = s_end * self.t
            P = np.array([[a, b], [a + d, b + d]], float)
            return Surface(1, 1, [0, 0, 1, 1], [0, 0, 1, 1], P)
        total = s_end * self.angle
        n = max(1, int(math.ceil(total / (math.pi / 2) - 1e-12)))
        dphi = total / n
        w1 = math.cos(dphi / 2)
        pts, wts = [], []
        for x in (a, b):
            row, rw = [], []
            for j in range(n):
                p0 = self._rotate(x, j * dphi)
                p2 = self._rotate(x, (j + 1) * dphi)
                o = self.centre + self.axis * (self.axis @ (x - self.centre))
                mid = o + (0.5 * (p0 + p2) - o) / (w1 * w1)  # tangent intersection
                if j == 0:
                    row.append(p0)
                    rw.append(1.0)
                row += [mid, p2]
                rw += [w1, 1.0]
            pts.append(row)
            wts.append(rw)
        P = np.array(pts).transpose(1, 0, 2)  # (2n+1, 2, 3): u along the arc
        W = np.array(wts).T
        knots = [0.0, 0.0, 0.0] + [j / n for j in range(1, n) for _ in (0, 1)] + [1.0] * 3
        return Surface(2, 1, knots, [0, 0, 1, 1], P, W)

    def _rotate(self, x, phi):
        k, r = self.axis, x - self.centre
        return (self.centre + r * math.cos(phi) + np.cross(k, r) * math.sin(phi)
                + k * (k @ r) * (1 - math.cos(phi)))

    def parameter_of(self, a, b, point, s_end=1.0) -> float:
        """The motion parameter at which the swept segment passes ``point``."""
        if self.kind == "rest":
            return 0.0
        if self.kind == "translation":
            d = self.t
            # point = a + v (b - a) + s d: least squares in (v, s)
            A = np.column_stack([b - a, d]) if np.linalg.norm(b - a) > 0 else d[:, None]
            sol = np.linalg.lstsq(A, point - a, rcond=None)[0]
            return float(np.clip(sol[-1], 0.0, s_end))
        k = self.axis
        x = a if np.linalg.norm(np.cross(k, a - self.centre)) >= np.linalg.norm(
            np.cross(k, b - self.centre)) else b
        r0 = x - self.centre
        r0 -= k * (k @ r0)
        rp = point - self.centre
        rp -= k * (k @ rp)
        if np.linalg.norm(r0) == 0 or np.linalg.norm(rp) == 0:
            return 0.0
        phi = math.atan2(float(k @ np.cross(r0, rp)), float(r0 @ rp)) % (2 * math.pi)
        if phi > self.angle * s_end + 1e-9:  # just below 0 by rounding
            phi = 0.0 if phi > math.pi else self.angle * s_end
        return float(phi / self.angle)


def probe_clearance(part, stylus: Stylus, path, *, axis=(0.0, 0.0, 1.0), margin=0.0,
                    tol=None, max_pairs=50_000, contact_tol=1e-9,
                    progress=None) -> Clearance:
    """Certified clearance of ``stylus`` moved along ``path`` past the NURBS ``part``.

    Parameters
    ----------
    part : Surface, list of Surfaces, or a Case (e.g. from :func:`geomkit.load`).
    stylus : Stylus.
    path : (k, 3) float tip-centre points (the stylus axis points along ``axis``), or
        (k, 4, 4) float stylus -> world poses; k >= 2.  Between consecutive poses the
        motion is a translation or a rotation about a fixed line (screws are refused).
    axis : (3,) direction from the tip toward the probe head, for point paths.
    margin : float >= 0, required clearance: a segment passes when its certified
        clearance is >= margin and there is no contact.
    tol : float > 0, width of each certified distance interval (default 1e-6 of the
        part's bounding-box diagonal).
    max_pairs : work cap of each :func:`surface_distance` call.
    contact_tol : first-contact parameter accuracy (segment parameter units).
    progress : callable ``progress(done, total)`` called after each move, or None.

    Returns
    -------
    Clearance
    """
    t_start = time.perf_counter()
    surfaces = as_surfaces(part, "part")
    if not isinstance(stylus, Stylus):
        raise InvalidInputError(f"expected a geomkit.Stylus, got {type(stylus).__name__}",
                                "stylus")
    poses = _as_poses(path, axis)
    lo = np.min([s.bounds[0] for s in surfaces], axis=0)
    hi = np.max([s.bounds[1] for s in surfaces], axis=0)
    diag = float(np.linalg.norm(hi - lo))
    if tol is None:
        tol = 1e-6 * max(diag, 1e-300)
    for name, v in (("margin", margin), ("tol", tol), ("contact_tol", contact_tol)):
        if not (isinstance(v, (int, float)) and math.isfinite(v) and v >= 0):
            raise InvalidInputError(f"expected a finite number >= 0, got {v!r}", name)
    if tol <= 0 or contact_tol <= 0:
        raise InvalidInputError("must be > 0", "tol" if tol <= 0 else "contact_tol")
    scale = max(diag, float(np.abs(poses[:, :3, 3]).max()), stylus.length, 1e-300)
    comps = stylus.components()
    part_boxes = np.array([s.bounds for s in surfaces])  # control-net boxes (n, 2, 3)
    m, c = len(poses) - 1, len(comps)
    gap = np.full((m, c), np.nan)
    glo = np.full((m, c), np.nan)
    best = [None] * m
    motions, motion_objs, calls = [], [], 0
    first = np.full(m, np.nan)
    contact_at = [None] * m  # (component, part point) of the first contact
    for i in range(m):
        mo = _Motion(poses[i], poses[i + 1], scale, i)
        motion_objs.append(mo)
        motions.append(mo.kind)
        R, p = poses[i][:3, :3], poses[i][:3, 3]
        first_i = np.inf
        for j, (name, a, b, r) in enumerate(comps):
            A, B = R @ a + p, R @ b + p
            res = _distance(mo.sweep(A, B), part_boxes, surfaces, tol, max_pairs)
            calls += 1
            gap[i, j] = max(res.upper - r, 0.0)
            glo[i, j] = max(res.lower - r, 0.0)
            if best[i] is None or gap[i, j] < gap[i, best[i][0]]:
                best[i] = (j, res, A, B, r)
            if res.lower - r <= 0.0:  # contact possible: find when it starts
                s, q, n = _first_contact(mo, A, B, r, part_boxes, surfaces,
                                         min(tol, 1e-10 * scale),
                                         max_pairs, contact_tol, min(first_i, 1.0))
                calls += n
                if s < first_i or (s == first_i and contact_at[i] is None):
                    first_i, contact_at[i] = s, (j, q)
        first[i] = first_i if np.isfinite(first_i) else np.nan
        if progress is not None:
            progress(i + 1, m)
    clearance = np.array([gap[i, best[i][0]] for i in range(m)])
    lower = glo.min(axis=1)
    comp = np.array([b[0] for b in best], dtype=np.int64)
    point_part = np.array([b[1].point_b for b in best])
    surface = np.array([b[1].surface_b for b in best], dtype=np.int64)
    point_axis = np.array([b[1].point_a for b in best])
    radius = np.array([b[4] for b in best])
    dirn = point_part - point_axis
    ln = np.linalg.norm(dirn, axis=1)
    safe = np.where(ln > 0, ln, 1.0)
    point_stylus = point_axis + (np.minimum(radius, ln) / safe)[:, None] * dirn
    param = np.array([mo.parameter_of(bi[2], bi[3], bi[1].point_a)
                      for mo, bi in zip(motion_objs, best)])
    for i, ca in enumerate(contact_at):  # a colliding segment: report the first contact
        if ca is None or ca[1] is None:
            continue
        comp[i], point_part[i], param[i] = ca[0], ca[1], first[i]
        _, a, b, r_ = comps[ca[0]]
        R, p = poses[i][:3, :3], poses[i][:3, 3]
        A0, B0 = R @ a + p, R @ b + p
        if first[i] > 0.0:  # the piece's axis at the contact pose
            A0, B0 = _end_segment(motion_objs[i].sweep(A0, B0, first[i]))
        axis_pt = _closest_on_segment(A0, B0, ca[1])
        dv = ca[1] - axis_pt
        ln_ = float(np.linalg.norm(dv))
        point_stylus[i] = axis_pt + (min(r_, ln_) / ln_ if ln_ > 0 else 0.0) * dv
    contact = np.isfinite(first) & (clearance <= 0.0)
    passed = (lower >= margin) & np.isnan(first)  # a possible contact fails the move
    certified = (clearance - lower) <= tol * (1 + 1e-9)
    return Clearance(clearance=clearance, lower_bound=lower, component=comp,
                     parameter=param, point_part=point_part, point_stylus=point_stylus,
                     surface=surface, first_contact=first, contact=contact, passed=passed,
                     certified=certified, per_component=gap,
                     component_names=tuple(cc[0] for cc in comps), margin=float(margin),
                     tol=float(tol), motion=tuple(motions),
                     stats={"distance_calls": calls, "seconds": time.perf_counter() - t_start})


def _first_contact(mo, A, B, r, part_boxes, surfaces, tol, max_pairs, contact_tol, s_hi):
    """Smallest s in [0, s_hi] at which the capsule (A-B, r) touches the part.

    The prefix sweep [0, s] grows with s, so its distance decreases: bisection with
    certified decisions (undecided -> treated as contact: the earliest possible)."""
    calls = 0
    hit = [None]

    def touches(s):
        nonlocal calls
        calls += 1
        sweep = _segment_surface(A, B) if s <= 0.0 else mo.sweep(A, B, s)
        d = _distance(sweep, part_boxes, surfaces, tol, max_pairs)
        if d.lower - r <= 0.0:
            hit[0] = d.point_b
            return True
        return False

    if touches(0.0):
        return 0.0, hit[0], calls
    if mo.kind == "rest" or not touches(s_hi):
        return np.inf, None, calls
    lo, hi = 0.0, s_hi
    for _ in range(MAX_BISECTIONS):
        if hi - lo <= contact_tol:
            break
        mid = 0.5 * (lo + hi)
        if touches(mid):
            hi = mid
        else:
            lo = mid
    touches(hi)  # the contact point at the reported parameter
    return hi, hit[0], calls


FIRST_FACES = 4
"""Faces whose boxes are nearest a sweep, measured first; their distance then bounds
which other faces can still matter."""


def _distance(sweep: Surface, boxes, surfaces, tol, max_pairs):
    """surface_distance(sweep, surfaces) on only the faces that can hold the minimum.

    A face's control-net box contains it, so the box gap is a lower bound of its
    distance: the nearest few faces by box give an attained distance ``d``; faces whose
    box gap exceeds ``d`` cannot be closer and are never subdivided."""
    b = sweep.bounds
    gap = np.linalg.norm(np.maximum(0.0, np.maximum(boxes[:, 0] - b[1], b[0] - boxes[:, 1])),
                         axis=1)
    n = len(surfaces)
    if n <= FIRST_FACES:
        return surface_distance(sweep, surfaces, tol=tol, max_pairs=max_pairs)
    kth = np.partition(gap, FIRST_FACES - 1)[FIRST_FACES - 1]
    first = np.flatnonzero(gap <= kth)
    res = surface_distance(sweep, [surfaces[i] for i in first], tol=tol, max_pairs=max_pairs)
    cand = np.flatnonzero(gap <= res.upper)
    if np.isin(cand, first).all():
        return dataclasses.replace(res, surface_b=int(first[res.surface_b]))
    res = surface_distance(sweep, [surfaces[i] for i in cand], tol=tol, max_pairs=max_pairs)
    return dataclasses.replace(res, surface_b=int(cand[res.surface_b]))


def _end_segment(sweep: Surface):
    """The axis segment at the end (u = 1) of a sweep."""
    P = sweep.evaluate([[1.0, 0.0], [1.0, 1.0]])
    return P[0], P[1]


def _closest_on_segment(a, b, x):
    d = b - a
    dd = float(d @ d)
    t = 0.0 if dd == 0 else min(1.0, max(0.0, float((x - a) @ d) / dd))
    return a + t * d


def _segment_surface(a, b) -> Surface:
    P = np.array([[a, b], [a, b]], float)
    return Surface(1, 1, [0, 0, 1, 1], [0, 0, 1, 1], P)



def read_path(path) -> np.ndarray:
    """A probe path file: JSON ``{"poses": [4x4, ...]}`` or ``{"points": [[x, y, z], ...]}``
    (or a bare list of either), else CSV/XYZ tip-centre points (x y z per row)."""
    p = Path(path)
    if p.suffix.lower() == ".json":
        try:
            d = json.loads(p.read_text(encoding="utf-8"))
        except json.JSONDecodeError as exc:
            raise InvalidInputError(f"not valid JSON ({exc.msg}, line {exc.lineno})",
                                    str(p)) from None
        if isinstance(d, dict):
            keys = [k for k in ("poses", "points") if k in d]
            if len(keys) != 1:
                raise InvalidInputError('expected exactly one of the keys "poses" or '
                                        '"points"', str(p))
            d = d[keys[0]]
        arr = as_float_array(d, str(p))
        if not np.all(np.isfinite(arr)):
            raise InvalidInputError("contains NaN or infinite values", str(p))
        return arr
    from geomkit.exchange.points import read_points

    return read_points(p).points
