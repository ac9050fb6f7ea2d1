"""Plane sections of NURBS surfaces: exact points, chained curves, fit and export.

Method (Paper 2, "plane / free-form surface intersection by quad parameter
subdivision", extended):

1. Each rational Bézier patch is subdivided recursively.  Paper 2 classifies quads
   into seven states a-g from the corner signs of the plane function; here a sub-patch
   is *pruned* only when the signed distances of all its control points have one
   strict sign (convex hull: no crossing, no hidden small loop), and it becomes a
   *leaf* when the plane function is monotone along u or v over its control net (the
   curve is then a graph, with at most one crossing per edge).  Sub-patches smaller
   than the tolerance that are neither (tangent points, singular crossings) become
   unresolved leaves, searched for contact points by Newton on the critical-point
   system ``n.S_u = n.S_v = 0``.
2. Leaf edge crossings are bracketed roots (to 1e-15 in the edge parameter); they are
   linked through the leaves into chains; exact midpoints (bracketed roots on the
   graph line of the leaf, else Newton along the gradient) are inserted until the
   chord deviation is <= ``tol``.
3. Chains are clipped by trims (a chain along a trim that lies in the plane is kept
   up to the trim's corners, and across stretches where an approximate trim winds
   round it within ``tol``), cut at poles, kept once where the plane runs along a
   shared edge or a seam, and joined across seams and surfaces where their ends
   coincide within ``tol`` (or the model's gap), and closed loops are flagged
   (:mod:`geomkit.section.joins`).  Curves whose whole extent is within ``tol`` are
   isolated contact points.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass, field

import numpy as np

from geomkit.section.export import fit_curves, plot, to_csv, to_dxf, to_json
from geomkit.section.clip import clip_trims
from geomkit.section.joins import (drop_shared_edges,
                                   join_across_edges, join_ends, merge_point_curves,
                                   split_at_poles)
from geomkit.section.trace import _Eval, trace_surface
from geomkit.validate import as_float_array
from geomkit.errors import FaceFailedWarning, InvalidInputError
from geomkit.nurbs.trimming import OUTSIDE
from geomkit.nurbs.surface import as_surfaces

__all__ = ["plane_section", "Section", "as_plane"]

BOUNDS_MARGIN = 1e-9
"""A surface whose control points all lie on one side of the plane, farther than its
zero band plus ``BOUNDS_MARGIN`` times the model scale (``|D| + max |P|``), is not
sectioned at all: its Bézier patches' control points are convex combinations of
them (in homogeneous coordinates, weights > 0), so every patch would be pruned
(``stats``: 0 sub-patches).  The margin covers the round-off of the extraction."""


@dataclass(eq=False)
class Section:
    """The intersection of surfaces with a plane.

    Attributes
    ----------
    curves : list of (k, 3) float, ordered points along each curve; a closed curve
        does not repeat its first point.
    closed : list of bool, one per curve.
    uv : list of (k, 2) float, the parameters of each curve point.
    surface_index : list of (k,) int, the surface of each curve point.
    points : (m, 3) float, isolated contact points (tangent plane, curves shorter than
        ``tol``).
    points_uv : (m, 2) float; points_surface : (m,) int.
    plane : (4,) float, the plane ``(A, B, C, D)`` with unit normal.
    tol : float, the chord tolerance the curves were built for.
    max_residual : float, largest ``|A x + B y + C z + D|`` over all output points.
    max_chord_error : float, largest measured distance of a curve midpoint (exact) from
        its chord; <= ``tol`` unless a refinement limit was hit (then reported as is).
    coplanar : list of int, surfaces lying in the plane (not sectioned).
    gap : float, the model gap the section was built with (``plane_section``'s ``gap``);
    max_gap_bridged : float, the largest distance between curve ends that were joined
        (across faces or to close a loop): above ``tol`` only where a CAD model's faces
        do not meet exactly.
    approx_error : float, the largest ``Surface.approx_error`` of the surfaces cut: the
        section points lie on the NURBS; the surfaces they stand for are within this.
    stats : dict, counts (sub-patches, leaves, crossings) per surface; 0 sub-patches:
        the surface's control net misses the plane (not sectioned, see
        :data:`BOUNDS_MARGIN`).
    failed : dict, surface index -> why it could not be sectioned (left out, with a
        :class:`~geomkit.errors.FaceFailedWarning`; the other surfaces are unaffected).
    """

    curves: list
    closed: list
    uv: list
    surface_index: list
    points: np.ndarray
    points_uv: np.ndarray
    points_surface: np.ndarray
    plane: np.ndarray
    tol: float
    max_residual: float
    max_chord_error: float
    coplanar: list = field(default_factory=list)
    stats: dict = field(default_factory=dict)
    gap: float = 0.0
    max_gap_bridged: float = 0.0
    approx_error: float = 0.0
    failed: dict = field(default_factory=dict)
    surfaces: list = field(default_factory=list, repr=False)

    def __len__(self) -> int:
        return len(self.curves)

    def __repr__(self) -> str:
        return (f"<Section {len(self.curves)} curve(s) ({sum(self.closed)} closed), "
                f"{len(self.points)} point(s), max residual {self.max_residual:.2g}, "
                f"max chord error {self.max_chord_error:.2g} (tol {self.tol:.2g})>")

    def fit(self, tol: float | None = None):
        """B-spline curves through each section curve within ``tol`` (default: the
        section's tol); see :func:`geomkit.section.export.fit_curves`."""
        return fit_curves(self, self.tol if tol is None else tol)

    def to_csv(self, path, overwrite: bool = False):
        """Write ``curve, index, x, y, z, u, v, surface`` rows (isolated points have
        curve -1); never overwrites unless ``overwrite=True``."""
        return to_csv(self, path, overwrite)

    def to_dxf(self, path, fit_tol: float | None = None, overwrite: bool = False):
        """Write 3-D POLYLINE entities (and SPLINE entities of :meth:`fit` when
        ``fit_tol`` is given) and POINT entities for isolated points."""
        return to_dxf(self, path, fit_tol, overwrite)

    def to_json(self, path, fit_tol: float | None = None, overwrite: bool = False):
        """Write the curves in geomdl's curve JSON format (``shape.type = "curve"``):
        degree-1 polylines, or the fitted B-splines when ``fit_tol`` is given."""
        return to_json(self, path, fit_tol, overwrite)

    def plot(self, ax=None, **kwargs):
        """Draw the curves and points on a matplotlib 3-D axis; returns the axis."""
        return plot(self, ax, **kwargs)


def as_plane(plane) -> np.ndarray:
    """Normalise a plane given as ``(A, B, C, D)`` or ``(point, normal)`` to a unit-normal
    ``(A, B, C, D)``.

    >>> as_plane(([0, 0, 6], [0, 0, 2])).tolist()
    [0.0, 0.0, 1.0, -6.0]
    """
    if isinstance(plane, (list, tuple)) and len(plane) == 2:
        pn = as_float_array([np.ravel(plane[0]), np.ravel(plane[1])], "plane",
                            shape=(2, 3))
        n = pn[1]
        abcd = np.array([n[0], n[1], n[2], -float(n @ pn[0])])
    else:
        abcd = as_float_array(plane, "plane", shape=(4,))
    ln = float(np.linalg.norm(abcd[:3]))
    if not ln > 0:
        raise InvalidInputError("the plane normal (A, B, C) must not be zero", "plane")
    return abcd / ln


def plane_section(surfaces, plane, tol: float = 1e-6, gap: float = 0.0) -> Section:
    """Intersect one or several surfaces with a plane.

    Parameters
    ----------
    surfaces : Surface or sequence of Surface
    plane : (4,) ``(A, B, C, D)`` for ``A x + B y + C z + D = 0``, or ``(point, normal)``
        with two 3-vectors.
    tol : float > 0
        Chord tolerance: consecutive curve points are close enough that the exact
        curve between them deviates from their chord by at most ``tol`` (measured at
        the exact curve midpoint and reported as ``max_chord_error``); curve ends of
        different surfaces (or across a seam) closer than ``tol`` are joined.
    gap : float >= 0
        The model's edge gap (a CAD file's faces meet within it, not exactly; see
        :func:`geomkit.cad.gaps.model_gap`): curve ends closer than ``max(tol, gap)``
        are joined and loops closed, nearest pair first; ends left open where the
        plane crosses a shared edge obliquely (up to ``gap / sin(angle)`` apart) are
        joined across it when mutual nearest and each within ``gap`` of the other
        face's boundary (see :data:`geomkit.section.joins.EDGE_REACH`); the largest distance bridged is
        reported (``max_gap_bridged``).

    Returns
    -------
    Section
        Every output point is ``S(u, v)`` evaluated at parameters refined onto the
        plane (bracketed roots / Newton): its plane residual is reported
        (``max_residual``, typically < 1e-12 times the model size) and it lies on
        the surface up to evaluation round-off.  A plane that misses gives an
        empty Section.

    Raises
    ------
    InvalidInputError
        Naming ``surfaces``, ``plane`` or ``tol``.
    """
    surfs = as_surfaces(surfaces)
    abcd = as_plane(plane)
    try:
        tol = float(tol)
    except (TypeError, ValueError):
        raise InvalidInputError(f"must be a number, got {type(tol).__name__}", "tol") from None
    if not (np.isfinite(tol) and tol > 0):
        raise InvalidInputError(f"must be a finite number > 0, got {tol!r}", "tol")
    try:
        gap = float(gap)
    except (TypeError, ValueError):
        raise InvalidInputError(f"must be a number, got {type(gap).__name__}", "gap") from None
    if not (np.isfinite(gap) and gap >= 0):
        raise InvalidInputError(f"must be a finite number >= 0, got {gap!r}", "gap")
    curves, contacts, coplanar, stats, failed = [], [], [], {}, {}
    for k, s in enumerate(surfs):
        P, pmax = _net(s)
        scale = float(np.abs(abcd[3]) + pmax)
        zsnap = 64 * np.finfo(float).eps * scale
        h = P @ abcd[:3] + abcd[3]
        hmax = float(np.abs(h).max())
        if hmax <= zsnap:
            coplanar.append(k)
            continue
        reach = zsnap + BOUNDS_MARGIN * scale
        if h.min() > reach or h.max() < -reach:   # the net misses: so does the face
            stats[k] = {"subpatches": 0, "leaves": 0, "unresolved": 0}
            continue
        min_diam = max(0.25 * tol, 1e-13 * scale)
        try:
            chains, cuv, st = trace_surface(s, abcd, tol, zsnap, min_diam)
            clipped = clip_trims(s, abcd, chains, zsnap, tol)
            if len(cuv) and s.is_trimmed:
                cuv = cuv[s.classify_uv(cuv) != OUTSIDE]
        except Exception as exc:  # noqa: BLE001 - reported: a warning and Section.failed
            # one face never sinks the section: left out, named
            failed[k] = f"{type(exc).__name__}: {exc}"
            name = f"surface {k}" + (f" ({s.name})" if s.name else "")
            warnings.warn(f"{name} left out of the section: {failed[k]}",
                          FaceFailedWarning, stacklevel=2)
            continue
        stats[k] = st
        for c in clipped:
            curves.append({"uv": c["uv"], "sid": np.full(len(c["uv"]), k), "closed": c["closed"],
                           "chord": c["chord"]})
        for q in cuv:
            contacts.append((k, q))
    ev = {k: _Eval(s, abcd) for k, s in enumerate(surfs)}
    _curve_points(ev, curves)
    bridged = [0.0]
    curves = split_at_poles(curves, surfs)
    curves = drop_shared_edges(curves, gap + 2 * tol)
    curves = merge_point_curves(curves, tol)
    curves = join_ends(curves, max(tol, gap), bridged, exact=tol)
    if gap > 0:
        curves = join_across_edges(curves, surfs, gap, bridged)
    # curves within tol of a point are contact points
    keep = []
    for c in curves:
        X = c["X"]
        if len(X) and np.linalg.norm(X.max(axis=0) - X.min(axis=0)) <= tol:
            i = int(np.argmin(np.abs(X @ abcd[:3] + abcd[3])))
            contacts.append((int(c["sid"][i]), c["uv"][i]))
        else:
            keep.append(c)
    curves = keep
    pts, puv, psid = _contact_points(ev, contacts, curves, abcd, tol)
    allX = [c["X"] for c in curves] + [pts]
    allX = np.concatenate(allX) if allX else np.empty((0, 3))
    resid = float(np.abs(allX @ abcd[:3] + abcd[3]).max()) if len(allX) else 0.0
    chord = max([c["chord"] for c in curves], default=0.0)
    return Section(curves=[c["X"] for c in curves], closed=[bool(c["closed"]) for c in curves],
                   uv=[c["uv"] for c in curves], surface_index=[c["sid"] for c in curves],
                   points=pts, points_uv=puv, points_surface=psid, plane=abcd, tol=tol,
                   max_residual=resid, max_chord_error=chord, coplanar=coplanar, stats=stats,
                   surfaces=surfs, gap=gap, max_gap_bridged=bridged[0], failed=failed,
                   approx_error=max((getattr(s, "approx_error", 0.0) for s in surfs),
                                    default=0.0))


def _net(s):
    """The control points of ``s`` (m, 3) and their largest absolute coordinate, kept
    on the surface (a part is sectioned at many planes)."""
    net = s._cache.get("section_net")
    if net is None:
        P = s.control_points.reshape(-1, 3)
        net = s._cache["section_net"] = (P, np.abs(P).max())
    return net


def _points(ev, uv, sid):
    """``S_sid(uv)`` (n, 3): the points of the surfaces ``sid`` (n,) at ``uv`` (n, 2),
    one kernel call per surface (each point evaluated alone: the same bits however
    they are grouped)."""
    X = np.empty((len(uv), 3))
    if not len(uv):
        return X
    order = np.argsort(sid, kind="stable")
    s = sid[order]
    cut = np.flatnonzero(s[1:] != s[:-1]) + 1
    for a, b in zip(np.r_[0, cut].tolist(), np.r_[cut, len(s)].tolist()):
        rows = order[a:b]
        X[rows] = ev[int(s[a])].points(uv[rows])
    return X


def _curve_points(ev, curves):
    """``c["X"]``, the points of each curve's ``uv`` on its surfaces ``sid``, for all
    the curves at once (:func:`_points`)."""
    if not curves:
        return
    n = [len(c["uv"]) for c in curves]
    X = _points(ev, np.concatenate([c["uv"] for c in curves]),
                np.concatenate([c["sid"] for c in curves]))
    for c, a, b in zip(curves, np.cumsum([0] + n[:-1]).tolist(), np.cumsum(n).tolist()):
        c["X"] = X[a:b].copy()


CONTACT_BLOCK = 64
""":func:`_contact_points` measures a candidate's distance to the curve points of the
blocks of this many (consecutive) whose box grown by ``tol`` holds it."""


def _contact_points(ev, contacts, curves, plane, tol):
    """Cluster contact candidates within ``tol``; drop those on a curve (within ``tol``
    of one of its points, see :data:`CONTACT_BLOCK`)."""
    if not contacts:
        return np.empty((0, 3)), np.empty((0, 2)), np.empty(0, np.int64)
    sid = np.array([k for k, _ in contacts])
    uv = np.array([q for _, q in contacts])
    X = _points(ev, uv, sid)
    f = np.abs(X @ plane[:3] + plane[3])
    order = np.argsort(f, kind="stable")
    # the curve points in blocks of CONTACT_BLOCK, each block's box grown by tol (and a
    # hair): a candidate outside it is farther than tol from every point of the block
    allX = np.concatenate([c["X"] for c in curves]) if curves else np.empty((0, 3))
    if len(allX):
        starts = np.arange(0, len(allX), CONTACT_BLOCK)
        grow = tol * (1 + 1e-9)
        lo = np.minimum.reduceat(allX, starts) - grow
        hi = np.maximum.reduceat(allX, starts) + grow
    keep = []
    for i in order:
        if any(np.linalg.norm(X[i] - X[j]) <= tol for j in keep):
            continue
        if len(allX):
            blocks = np.flatnonzero((lo <= X[i]).all(axis=1) & (X[i] <= hi).all(axis=1))
            if len(blocks):
                rows = (starts[blocks][:, None] + np.arange(CONTACT_BLOCK)).ravel()
                rows = rows[rows < len(allX)]
                if np.min(np.linalg.norm(allX[rows] - X[i], axis=1)) <= tol:
                    continue
        keep.append(i)
    keep = np.array(keep, dtype=np.int64)
    return X[keep], uv[keep], sid[keep]
