"""The exact NURBS surface, optionally trimmed, and its Bézier patches.

A :class:`Surface` holds validated, C-contiguous, read-only float64 arrays; its
methods (evaluation, derivatives, normals, trim classification, Bézier extraction)
call the numba kernels directly.  The free functions of
:mod:`geomkit.nurbs.evaluation`, :mod:`geomkit.nurbs.trimming` and
:mod:`geomkit.nurbs.bezier` are the documented entry points; they check their
argument and call these methods.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from geomkit import tolerances as tols
from geomkit._kernels import surface as K
from geomkit._kernels.bezier import decompose
from geomkit._kernels.ranges import col_range
from geomkit._kernels.trim import BOUNDARY, INSIDE, OUTSIDE, classify_points
from geomkit.validate import (as_float_array, as_int, as_points, check_knots,
                              clamped_knots_ok)
from geomkit.errors import InvalidInputError, InvalidSurfaceError, InvalidTrimError
from geomkit.nurbs import serial
from geomkit.nurbs.trims import (TrimCurve, TrimLoop, check_loop, clamp_knots, is_clamped,
                                 pack_segments, parse_loop, readonly)

__all__ = ["Surface", "TrimCurve", "TrimLoop", "BezierPatches", "check_uv", "check_surface",
           "as_surfaces",
           "NORMAL_REGULAR", "NORMAL_LIMIT", "NORMAL_NUDGED", "NORMAL_UNDEFINED"]

NORMAL_REGULAR, NORMAL_LIMIT, NORMAL_NUDGED, NORMAL_UNDEFINED = 0, 1, 2, 3
"""Status codes of :meth:`Surface.normals`."""


def check_uv(surface: "Surface", uv, field: str = "uv") -> tuple[np.ndarray, tuple]:
    """Validate parameters: returns (n, 2) float64 clamped to the domain, leading shape.

    Parameters within ``DOMAIN_TOL`` of the domain are clamped onto it; anything further
    out raises :class:`~geomkit.errors.InvalidInputError` naming the first offending row.
    """
    arr, lead = as_points(uv, 2, field)
    (u0, u1), (v0, v1) = surface.domain
    eu = tols.DOMAIN_TOL * (u1 - u0)
    ev = tols.DOMAIN_TOL * (v1 - v0)
    bad = ((arr[:, 0] < u0 - eu) | (arr[:, 0] > u1 + eu)
           | (arr[:, 1] < v0 - ev) | (arr[:, 1] > v1 + ev))
    if bad.any():
        i = int(np.argmax(bad))
        raise InvalidInputError(
            f"row {i} = ({arr[i, 0]!r}, {arr[i, 1]!r}) is outside the parameter domain "
            f"[{u0}, {u1}] x [{v0}, {v1}] ({int(bad.sum())} row(s) outside)", field)
    np.clip(arr[:, 0], u0, u1, out=arr[:, 0])
    np.clip(arr[:, 1], v0, v1, out=arr[:, 1])
    return arr, lead


def check_surface(surface, field: str = "surface") -> "Surface":
    """``surface`` if it is a :class:`Surface`, else InvalidInputError naming ``field``."""
    if not isinstance(surface, Surface):
        raise InvalidInputError(f"expected a geomkit.Surface, got {type(surface).__name__}",
                                field)
    return surface


def as_surfaces(x, field: str = "surfaces") -> list:
    """The surfaces of a query: one :class:`Surface`, a non-empty list or tuple of them,
    or an object holding them in a ``surfaces`` list (a :class:`~geomkit.Case`, a CAD
    read).  Anything else is an InvalidInputError naming ``field`` (or the element)."""
    if isinstance(x, Surface):
        return [x]
    if not isinstance(x, (list, tuple)) and isinstance(getattr(x, "surfaces", None), list):
        x = x.surfaces
    if isinstance(x, (list, tuple)) and x:
        for i, s in enumerate(x):
            check_surface(s, f"{field}[{i}]")
        return list(x)
    raise InvalidInputError("expected a Surface or a non-empty list of Surfaces, got "
                            f"{type(x).__name__}"
                            + (" (empty)" if isinstance(x, (list, tuple)) else ""), field)


def _net(a):
    """Control rows for ``decompose``: C-contiguous and writable (a copy of a read-only
    surface net), as :func:`geomkit.nurbs.trims.pack_segments` passes its curves'; knots
    go read-only (:func:`_knots`).  numba compiles a read-only and a writable array
    argument separately: one argument kind per parameter, one compiled ``decompose``."""
    a = np.ascontiguousarray(a)
    return a if a.flags.writeable else a.copy()


def _knots(a):
    a = np.ascontiguousarray(a)
    if a.flags.writeable:
        a = a.view()
        a.setflags(write=False)
    return a


_NO_WEIGHTS = np.ones((1, 1))
"""What :meth:`Surface.of_arrays` passes as the weights of a non-rational net."""


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
        if not is_clamped(U, p):
            flat, U = clamp_knots(Pw.reshape(nu, nv * 4), p, U)
            Pw = flat.reshape(-1, nv, 4)
            nu = Pw.shape[0]
        if not is_clamped(V, q):
            flat, V = clamp_knots(np.ascontiguousarray(Pw.transpose(1, 0, 2))
                                  .reshape(nv, nu * 4), q, V)
            Pw = np.ascontiguousarray(flat.reshape(-1, nu, 4).transpose(1, 0, 2))
        self.degree_u = p
        self.degree_v = q
        self.knots_u = readonly(U)
        self.knots_v = readonly(V)
        if Pw.shape[:2] == P.shape[:2]:  # not re-clamped: keep the input exactly
            self.control_points = readonly(P)
        else:
            self.control_points = readonly(Pw[..., :3] / Pw[..., 3:4])
        self.weights = readonly(Pw[..., 3]) if rational else None
        self._Pw = readonly(Pw)
        self._cache = {}
        self.name = name
        self.approx_error = err
        self.trim = self._parse_trim(trim)

    @classmethod
    def of_arrays(cls, p: int, q: int, U, V, P, W=None, name: str | None = None):
        """``Surface(p, q, U, V, P, W, name=name)`` of arrays as a reader builds them
        (float64, C-ordered, of matching shapes, finite, weights > 0, clamped knots
        that pass :func:`~geomkit.validate.check_knots`) without the constructor's
        conversions: thousands per part.  The same checks are made, in plain Python
        where numpy's per-call cost would dominate; anything else goes through the
        constructor (an error naming the fault)."""
        if not (type(p) is int and type(q) is int and p >= 1 and q >= 1
                and all(isinstance(a, np.ndarray) and a.dtype == np.float64
                        and a.flags.c_contiguous for a in (U, V, P))
                and P.ndim == 3 and P.shape[2] == 3):
            return cls(p, q, U, V, P, W, name=name)
        nu, nv = P.shape[:2]
        rational = W is not None
        if not (nu >= p + 1 and nv >= q + 1 and clamped_knots_ok(U.tolist(), p, nu)
                and clamped_knots_ok(V.tolist(), q, nv)
                and (not rational or (isinstance(W, np.ndarray) and W.dtype == np.float64
                                      and W.shape == (nu, nv)))):
            return cls(p, q, U, V, P, W, name=name)
        # finite products: finite points and weights (an overflow is left to the
        # constructor, which names it)
        Pw, ok, unit = K.homogeneous_net(P, W if rational else _NO_WEIGHTS, rational)
        if not ok:
            return cls(p, q, U, V, P, W, name=name)
        rational = rational and not unit
        s = object.__new__(cls)
        s.degree_u, s.degree_v = p, q
        s.knots_u, s.knots_v = readonly(np.array(U)), readonly(np.array(V))
        s.control_points = readonly(np.array(P))
        s.weights = readonly(Pw[..., 3]) if rational else None
        s._Pw = readonly(Pw)
        s._cache = {}
        s.name = name
        s.approx_error = 0.0
        s.trim = ()
        return s

    def with_trim(self, trim, name: str | None = None, approx_error: float | None = None):
        """The same surface (its validated arrays shared, not copied) with the trim
        loops ``trim`` (any form the constructor takes, validated as there) and,
        when given, another ``name`` / ``approx_error``."""
        s = object.__new__(Surface)
        for k in ("degree_u", "degree_v", "knots_u", "knots_v", "control_points",
                  "weights", "_Pw"):
            setattr(s, k, getattr(self, k))
        s._cache = {}
        s.name = self.name if name is None else name
        if approx_error is None:
            s.approx_error = self.approx_error
        else:
            err = float(approx_error)
            if not (np.isfinite(err) and err >= 0):
                raise InvalidSurfaceError(f"must be finite and >= 0, got {err!r}",
                                          "approx_error")
            s.approx_error = err
        s.trim = s._parse_trim(trim)
        return s

    def placed(self, matrix=None, name: str | None = None):
        """The surface carried by the affine 4 x 4 ``matrix`` (exact: an affine map
        commutes with the rational basis, so it maps the control points) and, when
        given, renamed ``name``.  Knots, weights and trim loops (in UV, unchanged by
        the map) are shared with this surface, not validated again."""
        s = object.__new__(Surface)
        for k in ("degree_u", "degree_v", "knots_u", "knots_v", "control_points",
                  "weights", "_Pw", "trim", "approx_error"):
            setattr(s, k, getattr(self, k))
        s._cache = {}
        s.name = self.name if name is None else name
        if matrix is not None:
            M = as_float_array(matrix, "matrix", shape=(4, 4), error=InvalidSurfaceError)
            if not np.isfinite(M).all():
                raise InvalidSurfaceError("must be finite", "matrix")
            P = self.control_points @ M[:3, :3].T + M[:3, 3]
            Pw = np.empty_like(self._Pw)
            Pw[..., :3] = P * self._Pw[..., 3:4]
            Pw[..., 3] = self._Pw[..., 3]
            s.control_points = readonly(P)
            s._Pw = readonly(Pw)
        return s

    # ------------------------------------------------------------------ pickling
    def __reduce__(self):
        """Pickled as one float buffer and a list of shapes (a read cache or a Dask
        worker restores a part of 800 faces from ~800 arrays, not ~16,000); the
        restored surface holds the same values bit for bit, unvalidated (it was
        validated when built).  The evaluation cache is not kept."""
        arrays = [self.knots_u, self.knots_v, self.control_points, self._Pw]
        if self.weights is not None:
            arrays.append(self.weights)
        loops = []
        for loop in self.trim:
            loops.append([c.degree for c in loop.pieces])
            for c in loop.pieces:
                arrays += [c.knots, c.control_points, c.weights]
        shapes = [a.shape for a in arrays]
        flat = np.concatenate([a.ravel() for a in arrays]) if arrays else np.zeros(0)
        return (_restore, (self.degree_u, self.degree_v, self.weights is not None, loops,
                           shapes, flat, self.name, self.approx_error))

    # ------------------------------------------------------------------ trims
    def _parse_trim(self, trim) -> tuple:
        if trim is None:
            return ()
        if isinstance(trim, (TrimLoop, TrimCurve, dict)):
            trim = [trim]
        if not isinstance(trim, (list, tuple)):
            raise InvalidTrimError(f"expected a list of loops, got {type(trim).__name__}", "trim")
        (u0, u1), (v0, v1) = self.domain
        close = tols.CLOSURE_TOL * max(u1 - u0, v1 - v0)
        loops = []
        for k, raw in enumerate(trim):
            field = f"trim[{k}]"
            loop = parse_loop(raw, field)
            check_loop(loop, self.domain, close, field)
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
        return np.array(col_range(self.control_points.reshape(-1, 3)))

    @property
    def size(self) -> float:
        """Model size: diagonal of :attr:`bounds` (scale for relative tolerances;
        computed once: the net is read-only)."""
        v = self._cache.get("size")
        if v is None:
            b = self.bounds
            d = b[1] - b[0]
            v = self._cache["size"] = math.sqrt(d.dot(d))  # np.linalg.norm's value
        return v

    def __repr__(self) -> str:
        kind = "NURBS" if self.is_rational else "B-spline"
        nu, nv = self.shape
        extra = f", {len(self.trim)} trim loop(s)" if self.trim else ""
        name = f" {self.name!r}" if self.name else ""
        return (f"<Surface{name} {kind} degree ({self.degree_u}, {self.degree_v}), "
                f"{nu}x{nv} control points{extra}>")

    # --------------------------------------------------------------- methods
    def evaluate(self, uv) -> np.ndarray:
        """Points S(u, v), (..., 3): see :func:`geomkit.evaluate`."""
        arr, lead = check_uv(self, uv)
        out = np.empty((arr.shape[0], 3))
        if arr.shape[0]:
            K.surface_points(self._Pw, self.degree_u, self.degree_v, self.knots_u,
                             self.knots_v, arr, out)
        return out.reshape(lead + (3,))

    def derivatives(self, uv, order: int = 1) -> np.ndarray:
        """Partial derivatives, (..., order+1, order+1, 3): see :func:`geomkit.derivatives`."""
        order = as_int(order, "order", minimum=0)
        if order > 8:
            raise InvalidInputError(f"order must be <= 8, got {order}", "order")
        arr, lead = check_uv(self, uv)
        out = np.empty((arr.shape[0], order + 1, order + 1, 3))
        if arr.shape[0]:
            K.surface_derivatives(self._Pw, self.degree_u, self.degree_v, self.knots_u,
                                  self.knots_v, arr, order, out)
        return out.reshape(lead + (order + 1, order + 1, 3))

    def normals(self, uv, return_status: bool = False):
        """Unit normals (and their status codes): see :func:`geomkit.normals`."""
        arr, lead = check_uv(self, uv)
        out = np.empty((arr.shape[0], 3))
        status = np.zeros(arr.shape[0], dtype=np.int8)
        (u0, u1), (v0, v1) = self.domain
        if arr.shape[0]:
            K.surface_normals(self._Pw, self.degree_u, self.degree_v, self.knots_u,
                              self.knots_v, arr, u0, u1, v0, v1, tols.DEGENERATE_NORMAL,
                              out, status)
        out = out.reshape(lead + (3,))
        if return_status:
            return out, status.reshape(lead)
        return out

    def trim_segments(self) -> tuple:
        """The trim loops packed as rational Bézier segments (computed once and kept):
        see :func:`geomkit.nurbs.trims.pack_segments`."""
        cached = self._cache.get("trim_segments")
        if cached is None:
            cached = self._cache["trim_segments"] = pack_segments(self.trim)
        return cached

    def classify_uv(self, uv, tol: float | None = None) -> np.ndarray:
        """``INSIDE`` / ``OUTSIDE`` / ``ON_BOUNDARY`` codes: see :func:`geomkit.classify_uv`."""
        arr, lead = as_points(uv, 2, "uv")
        (u0, u1), (v0, v1) = self.domain
        if tol is None:
            tol = tols.TRIM_TOL * max(u1 - u0, v1 - v0)
        tol = float(tol)
        if not np.isfinite(tol) or tol < 0:
            raise InvalidInputError(f"must be a finite number >= 0, got {tol!r}", "tol")
        # the domain rectangle
        du = np.minimum(arr[:, 0] - u0, u1 - arr[:, 0])
        dv = np.minimum(arr[:, 1] - v0, v1 - arr[:, 1])
        d = np.minimum(du, dv)
        out = np.where(d < -tol, OUTSIDE, np.where(d <= tol, BOUNDARY, INSIDE)).astype(np.int8)
        if self.trim and arr.shape[0]:
            seg, deg, lp, nloops = self.trim_segments()
            res = np.empty(arr.shape[0], dtype=np.int8)
            classify_points(seg, deg, lp, nloops, arr, tol, res)
            # outside the trim wins; on a trim curve wins over inside
            out = np.where((out == OUTSIDE) | (res == OUTSIDE), OUTSIDE,
                           np.where((res == BOUNDARY) | (out == BOUNDARY), BOUNDARY, INSIDE))
            out = out.astype(np.int8)
        return out.reshape(lead)

    def bezier_patches(self) -> "BezierPatches":
        """Split into rational Bézier patches (knot insertion, The NURBS Book A5.6),
        one per non-empty knot cell.  Computed once per surface and kept (the patches
        are read-only): repeated distance queries and sections of one surface (a probe
        path against a part) do not extract again.

        Returns
        -------
        BezierPatches
            ``homogeneous`` (nsu, nsv, p+1, q+1, 4); patch (i, j) covers
            ``[u_breaks[i], u_breaks[i+1]] x [v_breaks[j], v_breaks[j+1]]`` and
            evaluates exactly like the surface there.  Trims are ignored (patches cover
            the domain).
        """
        bp = self._cache.get("bezier_patches")
        if bp is None:
            bp = self._cache["bezier_patches"] = self._extract_patches()
        return bp

    def _extract_patches(self) -> "BezierPatches":
        p, q = self.degree_u, self.degree_v
        Pw = self._Pw
        nu, nv = Pw.shape[:2]
        # u direction: each row index i is a control point of a curve in R^(nv*4)
        Qu, ub = decompose(_net(Pw.reshape(nu, nv * 4)), p, _knots(self.knots_u))
        nsu = Qu.shape[0]
        rows = Qu.reshape(nsu * (p + 1), nv, 4)
        # v direction: columns become control points of curves in R^(nsu*(p+1)*4)
        cols = np.ascontiguousarray(rows.transpose(1, 0, 2)).reshape(nv, -1)
        Qv, vb = decompose(_net(cols), q, _knots(self.knots_v))
        nsv = Qv.shape[0]
        H = Qv.reshape(nsv, q + 1, nsu, p + 1, 4).transpose(2, 0, 3, 1, 4)
        H = np.ascontiguousarray(H)
        for a in (H, ub, vb):
            a.setflags(write=False)
        return BezierPatches(H, ub, vb)

    # ---------------------------------------------------------- plain data
    def to_geomdl(self):
        """A ``geomdl`` surface (``BSpline.Surface`` or ``NURBS.Surface``); trims dropped."""
        return serial.surface_to_geomdl(self)

    @classmethod
    def from_geomdl(cls, obj) -> "Surface":
        """Build from a ``geomdl`` B-spline or NURBS surface."""
        return cls(**serial.geomdl_kwargs(obj))

    def to_dict(self) -> dict:
        """The ``geomkit-case/1`` form of this surface."""
        return serial.surface_to_dict(self)


def _restore(p, q, rational, loops, shapes, flat, name, approx_error) -> Surface:
    """A :class:`Surface` from :meth:`Surface.__reduce__`'s parts: read-only views of
    one buffer."""
    flat = np.ascontiguousarray(flat, dtype=np.float64)
    flat.setflags(write=False)
    views, o = [], 0
    for shp in shapes:
        n = math.prod(shp)
        views.append(flat[o:o + n].reshape(shp))
        o += n
    s = object.__new__(Surface)
    s.degree_u, s.degree_v = p, q
    s.knots_u, s.knots_v, s.control_points, s._Pw = views[:4]
    k = 4
    s.weights = None
    if rational:
        s.weights, k = views[4], 5
    trim = []
    for degrees in loops:
        pieces = []
        for d in degrees:
            c = object.__new__(TrimCurve)  # a frozen dataclass: filled as __init__ would
            c.__dict__.update(degree=d, knots=views[k], control_points=views[k + 1],
                              weights=views[k + 2])
            pieces.append(c)
            k += 3
        trim.append(TrimLoop(tuple(pieces)))
    s.trim = tuple(trim)
    s.name, s.approx_error = name, approx_error
    s._cache = {}
    return s


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
