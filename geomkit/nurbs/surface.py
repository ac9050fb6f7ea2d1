"""geomkit's data types: exact NURBS surfaces with trims, and their Bézier patches.

Types hold validated, C-contiguous, read-only float64 arrays and no algorithms; the
methods hand off to the domain modules (:mod:`geomkit.nurbs.evaluation`,
:mod:`geomkit.nurbs.trimming`, :mod:`geomkit.nurbs.bezier`, :mod:`geomkit.exchange.cases`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from geomkit import tolerances as tols
from geomkit._kernels.bezier import insert_knot
from geomkit.validate import as_float_array, as_int, check_knots
from geomkit.errors import InvalidSurfaceError, InvalidTrimError

__all__ = ["Surface", "TrimCurve", "TrimLoop", "BezierPatches"]


def _readonly(a: np.ndarray) -> np.ndarray:
    a = np.ascontiguousarray(a, dtype=np.float64)
    a.setflags(write=False)
    return a


def _clamp(Pw: np.ndarray, p: int, U: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Clamp an unclamped knot vector by knot insertion; the curve is unchanged.

    ``Pw`` (n, dim) homogeneous rows.  Inserts the domain ends ``U[p]`` and ``U[n]``
    until they have multiplicity ``p`` and drops the parts outside the domain.
    """
    n = Pw.shape[0]
    a, b = U[p], U[n]
    if np.all(U[: p + 1] == a) and np.all(U[n:] == b):
        return Pw, U
    for end in (a, b):
        s = int(np.count_nonzero(U == end))
        if s < p:
            Pw, U = insert_knot(np.ascontiguousarray(Pw), p, U, end, p - s)
    first_a = int(np.nonzero(U == a)[0][0])
    start = first_a + int(np.count_nonzero(U == a)) - 1 - p  # span of a, minus p
    first_b = int(np.nonzero(U == b)[0][0])
    newU = U[start: first_b + p + 1].copy()
    newU[: p + 1] = a
    newU[-(p + 1):] = b
    return np.ascontiguousarray(Pw[start: first_b]), newU


@dataclass(frozen=True, eq=False)
class TrimCurve:
    """A 2-D NURBS curve in a surface's parameter plane (one piece of a trim loop).

    Attributes
    ----------
    degree : int
    knots : (n + degree + 1,) float, clamped.
    control_points : (n, 2) float, in (u, v).
    weights : (n,) float, all 1 for a polyline or plain B-spline.
    """

    degree: int
    knots: np.ndarray
    control_points: np.ndarray
    weights: np.ndarray

    @classmethod
    def create(cls, degree, knots, control_points, weights=None, field="trim") -> "TrimCurve":
        """Validate and build a trim curve (unclamped knot vectors are clamped)."""
        p = as_int(degree, f"{field}.degree", minimum=1, error=InvalidTrimError)
        P = as_float_array(control_points, f"{field}.control_points", shape=(None, 2),
                           error=InvalidTrimError)
        n = P.shape[0]
        if n < p + 1:
            raise InvalidTrimError(f"{n} control points but degree {p} needs at least {p + 1}",
                                   f"{field}.control_points")
        U = check_knots(knots, p, n, f"{field}.knots", InvalidTrimError)
        if weights is None:
            w = np.ones(n)
        else:
            w = as_float_array(weights, f"{field}.weights", shape=(n,), error=InvalidTrimError)
            if np.any(w <= 0):
                i = int(np.argmin(w))
                raise InvalidTrimError(f"weights must be > 0, weight[{i}] = {float(w[i])!r}",
                                       f"{field}.weights")
        Pw = np.empty((n, 3))
        Pw[:, :2] = P * w[:, None]
        Pw[:, 2] = w
        Pw, U = _clamp(Pw, p, U)
        w = Pw[:, 2].copy()
        return cls(p, _readonly(U), _readonly(Pw[:, :2] / w[:, None]), _readonly(w))

    @classmethod
    def polyline(cls, points, field="trim") -> "TrimCurve":
        """A polyline (k, 2) as a degree-1 curve with one knot per vertex (chord length)."""
        P = as_float_array(points, field, shape=(None, 2), error=InvalidTrimError)
        if P.shape[0] < 2:
            raise InvalidTrimError(f"a polyline needs at least 2 points, got {P.shape[0]}", field)
        seg = np.hypot(*np.diff(P, axis=0).T)
        keep = np.concatenate([[True], seg > 0])  # drop repeated vertices
        P = P[keep]
        if P.shape[0] < 2:
            raise InvalidTrimError("degenerate polyline: all points coincide", field)
        t = np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(P, axis=0).T))])
        t /= t[-1]
        U = np.concatenate([[0.0], t, [1.0]])
        return cls(1, _readonly(U), _readonly(P), _readonly(np.ones(P.shape[0])))

    @property
    def is_polyline(self) -> bool:
        return self.degree == 1 and bool(np.all(self.weights == 1.0))

    @property
    def start(self) -> np.ndarray:
        return self.control_points[0]

    @property
    def end(self) -> np.ndarray:
        return self.control_points[-1]

    @property
    def homogeneous(self) -> np.ndarray:
        """(n, 3) homogeneous control points ``(w u, w v, w)``."""
        Pw = np.empty((self.control_points.shape[0], 3))
        Pw[:, :2] = self.control_points * self.weights[:, None]
        Pw[:, 2] = self.weights
        return Pw

    def to_dict(self) -> dict:
        """The ``geomkit-case/1`` form of this piece."""
        if self.is_polyline:
            return {"degree": 1, "knots": self.knots.tolist(),
                    "control_points": self.control_points.tolist()}
        return {"degree": self.degree, "knots": self.knots.tolist(),
                "control_points": self.control_points.tolist(),
                "weights": self.weights.tolist()}


@dataclass(frozen=True, eq=False)
class TrimLoop:
    """A closed chain of trim curves, in order; the end of each piece meets the next."""

    pieces: tuple

    @property
    def is_polyline(self) -> bool:
        return all(c.is_polyline for c in self.pieces)

    def to_case(self):
        """The ``geomkit-case/1`` form: a point list for a single polyline piece,
        a curve dict for a single NURBS piece, else a list of curve dicts."""
        if len(self.pieces) == 1:
            c = self.pieces[0]
            return c.control_points.tolist() if c.is_polyline else c.to_dict()
        return [c.to_dict() for c in self.pieces]


def _parse_loop(loop, field) -> TrimLoop:
    if isinstance(loop, TrimLoop):
        return loop
    if isinstance(loop, (TrimCurve, dict)):
        raw = [loop]
    elif isinstance(loop, (list, tuple)) and loop and isinstance(loop[0], (TrimCurve, dict)):
        raw = list(loop)
    else:
        raw = [("polyline", loop)]
    pieces = []
    for k, item in enumerate(raw):
        f = field if len(raw) == 1 else f"{field}[{k}]"
        if isinstance(item, TrimCurve):
            pieces.append(item)
        elif isinstance(item, tuple) and item[0] == "polyline":
            pieces.append(TrimCurve.polyline(item[1], f))
        elif isinstance(item, dict):
            missing = [key for key in ("degree", "knots", "control_points") if key not in item]
            if missing:
                raise InvalidTrimError(f"trim curve is missing {', '.join(missing)}", f)
            pieces.append(TrimCurve.create(item["degree"], item["knots"], item["control_points"],
                                           item.get("weights"), f))
        else:
            raise InvalidTrimError(f"expected a polyline or a NURBS curve dict, got "
                                   f"{type(item).__name__}", f)
    return TrimLoop(tuple(pieces))


def _first_point_outside(curve: TrimCurve, box: np.ndarray, tol: float):
    """A point of ``curve`` outside ``box`` (u0, u1, v0, v1), or None if it stays in.

    Exact up to ``tol``: Bézier pieces whose control points lie in the box are inside
    (convex hull property); others are split until a piece end point is found
    outside or the piece is smaller than ``tol``.
    """
    from geomkit._kernels.bezier import de_casteljau_split, decompose

    xy = curve.control_points  # the curve lies in their convex hull (weights > 0)
    if ((xy[:, 0] >= box[0]) & (xy[:, 0] <= box[1]) & (xy[:, 1] >= box[2])
            & (xy[:, 1] <= box[3])).all():
        return None
    Q, _ = decompose(curve.homogeneous, curve.degree, curve.knots)
    stack = list(Q)
    while stack:
        piece = stack.pop()
        xy = piece[:, :2] / piece[:, 2:3]
        if ((xy[:, 0] >= box[0]) & (xy[:, 0] <= box[1]) & (xy[:, 1] >= box[2])
                & (xy[:, 1] <= box[3])).all():
            continue
        for end in (xy[0], xy[-1]):
            if not (box[0] <= end[0] <= box[1] and box[2] <= end[1] <= box[3]):
                return end
        if np.ptp(xy, axis=0).max() <= tol:
            continue
        left = np.empty_like(piece)
        right = np.empty_like(piece)
        de_casteljau_split(piece, 0.5, left, right)
        stack += [left, right]
    return None


def _loop_samples(loop: TrimLoop, per_segment: int = 24) -> np.ndarray:
    """Points along a loop (for validation only: area, domain containment)."""
    from geomkit._kernels.bezier import curve_points  # local: keeps import graph one-way

    out = []
    for c in loop.pieces:
        if c.is_polyline:
            out.append(c.control_points)
            continue
        t = np.unique(np.concatenate([
            np.linspace(a, b, per_segment, endpoint=False)
            for a, b in zip(c.knots[c.degree:-c.degree - 1], c.knots[c.degree + 1:-c.degree])
            if b > a] + [c.knots[-1:]]))
        res = np.empty((t.shape[0], 1, 2))
        curve_points(c.homogeneous, c.degree, c.knots, t, 0, res)
        out.append(res[:, 0, :])
    return np.concatenate(out)


class Surface:
    """A B-spline or NURBS surface, optionally trimmed.

    Parameters
    ----------
    degree_u, degree_v : int >= 1
    knots_u : (nu + degree_u + 1,) float, non-decreasing, interior multiplicity <=
        degree_u.  Unclamped vectors are accepted and clamped by knot insertion (the
        surface is unchanged on its domain ``[knots_u[p], knots_u[nu]]``).
    knots_v : (nv + degree_v + 1,) float, likewise.
    control_points : (nu, nv, 3) float.
    weights : (nu, nv) float > 0, optional (a non-rational B-spline when omitted).
    trim : list of loops in UV, outer first, optional.  A loop is a closed polyline
        ``[[u, v], ...]`` (first point repeated at the end), a 2-D NURBS curve
        ``{"degree", "knots", "control_points", "weights"}`` (closed: it ends where it
        starts), a list of such curves chained end to start, or a :class:`TrimLoop`.
        A UV point is in the trimmed face when an odd number of loops wind around it
        (outer loop minus holes).
    name : str, optional, carried through I/O.
    approx_error : float >= 0, optional
        Largest distance between this NURBS and the surface it stands for, when it is
        an approximation (e.g. a CAD offset surface); 0 for an exact surface.  Results
        computed on it widen their error bounds by it; carried through I/O.

    Raises
    ------
    InvalidSurfaceError, InvalidTrimError
        Naming the field: wrong knot-vector length, decreasing knots, interior
        multiplicity > degree, non-finite values, weights <= 0, open or degenerate
        trim loops, trim loops outside the domain.
    """

    __slots__ = ("degree_u", "degree_v", "knots_u", "knots_v", "control_points", "weights",
                 "trim", "name", "approx_error", "_Pw", "_cache")

    def __init__(self, degree_u, degree_v, knots_u, knots_v, control_points, weights=None,
                 trim=None, name: str | None = None, approx_error: float = 0.0):
        E = InvalidSurfaceError
        try:
            err = float(approx_error)
        except (TypeError, ValueError):
            raise E(f"expected a number >= 0, got {approx_error!r}", "approx_error") from None
        if not (np.isfinite(err) and err >= 0):
            raise E(f"must be finite and >= 0, got {err!r}", "approx_error")
        p = as_int(degree_u, "degree_u", minimum=1, error=E)
        q = as_int(degree_v, "degree_v", minimum=1, error=E)
        P = as_float_array(control_points, "control_points", shape=(None, None, 3), error=E)
        nu, nv = P.shape[:2]
        if nu < p + 1:
            raise E(f"{nu} rows of control points but degree_u {p} needs at least {p + 1}",
                    "control_points")
        if nv < q + 1:
            raise E(f"{nv} columns of control points but degree_v {q} needs at least {q + 1}",
                    "control_points")
        U = check_knots(knots_u, p, nu, "knots_u", E)
        V = check_knots(knots_v, q, nv, "knots_v", E)
        rational = weights is not None
        if rational:
            w = as_float_array(weights, "weights", shape=(nu, nv), error=E)
            if np.any(w <= 0):
                i, j = (int(x) for x in np.unravel_index(np.argmin(w), w.shape))
                raise E(f"weights must be > 0, weight[{i}][{j}] = {float(w[i, j])!r}", "weights")
            if np.all(w == 1.0):
                rational = False
        else:
            w = np.ones((nu, nv))
        Pw = np.empty((nu, nv, 4))
        Pw[..., :3] = P * w[..., None]
        Pw[..., 3] = w
        # clamp unclamped knot vectors (u: rows are curves; v: transpose)
        flat, U = _clamp(Pw.reshape(nu, nv * 4), p, U)
        Pw = flat.reshape(-1, nv, 4)
        nu = Pw.shape[0]
        flat, V = _clamp(np.ascontiguousarray(Pw.transpose(1, 0, 2)).reshape(nv, nu * 4), q, V)
        Pw = np.ascontiguousarray(flat.reshape(-1, nu, 4).transpose(1, 0, 2))
        self.degree_u = p
        self.degree_v = q
        self.knots_u = _readonly(U)
        self.knots_v = _readonly(V)
        if Pw.shape[:2] == P.shape[:2]:  # not re-clamped: keep the input exactly
            self.control_points = _readonly(P)
        else:
            self.control_points = _readonly(Pw[..., :3] / Pw[..., 3:4])
        self.weights = _readonly(Pw[..., 3]) if rational else None
        self._Pw = _readonly(Pw)
        self._cache = {}
        self.name = name
        self.approx_error = err
        self.trim = self._parse_trim(trim)

    # ------------------------------------------------------------------ trims
    def _parse_trim(self, trim) -> tuple:
        if trim is None:
            return ()
        if isinstance(trim, (TrimLoop, TrimCurve, dict)):
            trim = [trim]
        if not isinstance(trim, (list, tuple)):
            raise InvalidTrimError(f"expected a list of loops, got {type(trim).__name__}", "trim")
        (u0, u1), (v0, v1) = self.domain
        size = max(u1 - u0, v1 - v0)
        close = tols.CLOSURE_TOL * size
        loops = []
        for k, raw in enumerate(trim):
            field = f"trim[{k}]"
            loop = _parse_loop(raw, field)
            pcs = loop.pieces
            for i, c in enumerate(pcs):
                nxt = pcs[(i + 1) % len(pcs)]
                gap = float(np.hypot(*(c.end - nxt.start)))
                if gap > close:
                    if len(pcs) == 1:
                        what = (f"loop is open: it ends at {c.end.tolist()}, {gap:.3g} away "
                                f"from its start {nxt.start.tolist()}")
                    else:
                        j = (i + 1) % len(pcs)
                        what = (f"pieces do not join: piece {i} ends at {c.end.tolist()} but "
                                f"piece {j} starts at {nxt.start.tolist()}, {gap:.3g} away")
                    raise InvalidTrimError(f"{what} (closure tolerance {close:.3g})", field)
            box = np.array([u0 - close, u1 + close, v0 - close, v1 + close])
            for c in loop.pieces:
                bad = _first_point_outside(c, box, close)
                if bad is not None:
                    raise InvalidTrimError(
                        f"loop leaves the parameter domain [{u0}, {u1}] x [{v0}, {v1}] at "
                        f"({bad[0]:.6g}, {bad[1]:.6g})", field)
            pts = _loop_samples(loop)
            x, y = pts[:, 0], pts[:, 1]
            area = 0.5 * float(np.sum(x * np.roll(y, -1) - np.roll(x, -1) * y))
            if abs(area) <= (close * close) or np.unique(np.round(pts / close), axis=0).shape[0] < 3:
                raise InvalidTrimError(f"degenerate loop: enclosed area {area:.3g} in UV", field)
            loops.append(loop)
        return tuple(loops)

    # ------------------------------------------------------------- properties
    @property
    def domain(self) -> tuple[tuple[float, float], tuple[float, float]]:
        """((u_min, u_max), (v_min, v_max))."""
        p, q = self.degree_u, self.degree_v
        return ((float(self.knots_u[p]), float(self.knots_u[-p - 1])),
                (float(self.knots_v[q]), float(self.knots_v[-q - 1])))

    @property
    def shape(self) -> tuple[int, int]:
        """Control net size (nu, nv)."""
        return self.control_points.shape[:2]

    @property
    def is_rational(self) -> bool:
        return self.weights is not None

    @property
    def is_trimmed(self) -> bool:
        return bool(self.trim)

    @property
    def homogeneous(self) -> np.ndarray:
        """(nu, nv, 4) read-only homogeneous control points ``(w x, w y, w z, w)``."""
        return self._Pw

    @property
    def bounds(self) -> np.ndarray:
        """(2, 3) axis-aligned box of the control net; contains the surface."""
        P = self.control_points.reshape(-1, 3)
        return np.array([P.min(axis=0), P.max(axis=0)])

    @property
    def size(self) -> float:
        """Model size: diagonal of :attr:`bounds` (scale for relative tolerances)."""
        b = self.bounds
        return float(np.linalg.norm(b[1] - b[0]))

    def __repr__(self) -> str:
        kind = "NURBS" if self.is_rational else "B-spline"
        nu, nv = self.shape
        extra = f", {len(self.trim)} trim loop(s)" if self.trim else ""
        name = f" {self.name!r}" if self.name else ""
        return (f"<Surface{name} {kind} degree ({self.degree_u}, {self.degree_v}), "
                f"{nu}x{nv} control points{extra}>")

    # --------------------------------------------------------------- methods
    def evaluate(self, uv) -> np.ndarray:
        """Points S(u, v); see :func:`geomkit.nurbs.evaluation.evaluate`."""
        from geomkit.nurbs.evaluation import evaluate
        return evaluate(self, uv)

    def derivatives(self, uv, order: int = 1) -> np.ndarray:
        """Partial derivatives; see :func:`geomkit.nurbs.evaluation.derivatives`."""
        from geomkit.nurbs.evaluation import derivatives
        return derivatives(self, uv, order)

    def normals(self, uv, return_status: bool = False):
        """Unit normals; see :func:`geomkit.nurbs.evaluation.normals`."""
        from geomkit.nurbs.evaluation import normals
        return normals(self, uv, return_status)

    def classify_uv(self, uv, tol: float | None = None) -> np.ndarray:
        """Inside/outside/boundary codes; see :func:`geomkit.nurbs.trimming.classify_uv`."""
        from geomkit.nurbs.trimming import classify_uv
        return classify_uv(self, uv, tol)

    def bezier_patches(self) -> "BezierPatches":
        """Bézier extraction; see :func:`geomkit.nurbs.bezier.bezier_patches`.  Computed once
        per surface and kept (the patches are read-only): repeated distance queries and
        sections of one surface (a probe path against a part) do not extract again."""
        bp = self._cache.get("bezier_patches")
        if bp is None:
            from geomkit.nurbs.bezier import bezier_patches
            bp = self._cache["bezier_patches"] = bezier_patches(self)
        return bp

    def to_geomdl(self):
        """A ``geomdl`` surface (``BSpline.Surface`` or ``NURBS.Surface``); trims dropped."""
        from geomkit.exchange.cases import to_geomdl
        return to_geomdl(self)

    @classmethod
    def from_geomdl(cls, obj) -> "Surface":
        """Build from a ``geomdl`` B-spline or NURBS surface."""
        from geomkit.exchange.cases import from_geomdl
        return from_geomdl(obj)

    def to_dict(self) -> dict:
        """The ``geomkit-case/1`` form of this surface."""
        from geomkit.exchange.cases import surface_to_dict
        return surface_to_dict(self)


@dataclass(frozen=True, eq=False)
class BezierPatches:
    """A surface split into rational Bézier patches (knot insertion).

    Attributes
    ----------
    homogeneous : (nsu, nsv, p+1, q+1, 4) float, homogeneous control points of patch
        (i, j); patches share their boundary control points exactly.
    u_breaks : (nsu + 1,) float, the patch boundaries in u.
    v_breaks : (nsv + 1,) float, the patch boundaries in v.
    """

    homogeneous: np.ndarray
    u_breaks: np.ndarray
    v_breaks: np.ndarray

    @property
    def control_points(self) -> np.ndarray:
        """(nsu, nsv, p+1, q+1, 3) Cartesian control points."""
        return self.homogeneous[..., :3] / self.homogeneous[..., 3:4]

    @property
    def weights(self) -> np.ndarray:
        """(nsu, nsv, p+1, q+1) weights."""
        return self.homogeneous[..., 3]

    @property
    def shape(self) -> tuple[int, int]:
        return self.homogeneous.shape[:2]

    def bounds(self) -> np.ndarray:
        """(nsu, nsv, 2, 3) axis-aligned boxes of each patch's control net.

        Each box contains its patch (convex hull property; weights are positive).
        """
        P = self.control_points
        return np.stack([P.min(axis=(2, 3)), P.max(axis=(2, 3))], axis=2)
