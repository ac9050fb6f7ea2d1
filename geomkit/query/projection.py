"""Exact projection of points onto trimmed NURBS surfaces (CMM deviation).

Method (Paper 1's mesh + voxel grid for candidates, the exact surface for the answer):

1. tessellate the surfaces once (:func:`geomkit.tessellate`, chord tolerance
   ``mesh_tol``) and bin the triangles in a :class:`~geomkit.VoxelGrid`;
2. per point, a best-first search over the grid collects every triangle t whose
   surface piece can hold the nearest point: with d_t the point–triangle distance
   and e_t the triangle's deviation bound, every t with
   ``d_t - e_t <= min(d_t' + e_t')``; ``min(d_t - e_t)`` is the reported lower bound;
3. from every candidate whose lower bound is below the best bound so far (the mesh
   upper bound, then the nearest foot inside its face: untrimmed, or classified
   inside the trim loops in the kernel) a
   safeguarded Newton iteration on the exact surface finds the foot
   (:func:`geomkit._kernels.project_newton.foot_newton`: exact Hessian or Gauss–Newton,
   active set on the domain box, backtracking);
4. on trimmed surfaces a foot outside the face is replaced by the nearest point of
   the trim boundary (1-D Newton on the exact trim curve mapped onto the surface),
   so the answer is the nearest point of the *trimmed* face.

The nearest foot wins; points with many feet (the sphere centre) get the exact
distance and one of them.  Work is parallel over points (serial kernels on threads,
``_numba.prun``), in chunks
of ``chunk_size`` points, so memory stays bounded for any number of points
(:meth:`Projector.iter_project` streams).
"""

from __future__ import annotations

import time

import numpy as np

from geomkit.tolerances import DEFAULT_MESH_TOL, TIE_TOL
from geomkit.query import results as R
from geomkit._kernels import project as _pk
from geomkit._kernels import project_finish as _pf
from geomkit._kernels import trim_feet as _tf
from geomkit import tolerances as tols
from geomkit.query.projection_cert import pack_span_bounds
from geomkit.query.projection_trim import _TrimData, _trim_boundary_triangles, cert_boxes
from geomkit.query.projection_base import QueryBase
from geomkit.query.results import Projection
from geomkit.mesh.tessellate import (SAMPLES_PER_EDGE, closed_directions,
                                     tessellate_with_target)
from geomkit.nurbs.trimming import BOUNDARY, INSIDE, OUTSIDE
from geomkit.nurbs.surface import as_surfaces
from geomkit.nurbs.trims import concat_segments
from geomkit.query.voxel import VoxelGrid, sliver_voxel_size

__all__ = ["Projector", "DEFAULT_MESH_TOL", "DEVIATION_SAFETY"]

DEVIATION_SAFETY = 2.0
"""The triangles' measured deviations are multiplied by this in the candidate search
(they are measured at samples, not proven)."""
PROJ_TRIM_TARGET = 0.05
"""The candidate mesh's trim polylines are refined to a 3-D chord error of this times
the mesh tolerance (tessellate's own target is :data:`geomkit.mesh.tessellate.TRIM_TARGET`);
triangles along a trim curve carry it in their bound, so a finer polyline means fewer
near-tie candidates on parts whose triangles mostly border a trim curve."""
MAX_STARTS = 16
"""Newton runs per point in the first pass (a point left with an untried candidate
that could hold a nearer point is run again with :data:`RERUN_STARTS`)."""
MAX_STARTS_TRIMMED = 16
"""The same with trimmed faces (their feet prune no candidate: a foot may lie
outside its face)."""
RERUN_STARTS = 64
"""Newton runs per point at least in the second pass, for the points whose first pass
hit the start cap with a candidate left that could hold a nearer point: the pass
allows as many starts as the most candidates of its points, at least this many and at
most :data:`RERUN_STARTS_MAX` (the candidate buffer grows, no candidate is dropped)."""
RERUN_STARTS_MAX = 256
"""The second pass's start cap.  The few points with more candidates than that whose
untried candidates could still hold a nearer point get a last pass with every
candidate (in batches of :data:`RERUN_BUDGET` point-starts); a point left open after
trying every candidate is counted in ``stats["not_proven"]``."""
RERUN_BUDGET = 1 << 20
"""Points x starts per batch of the last pass (bounds its working memory)."""


def _morton_order(P, origin, h):
    """Order of the points along a Z curve over cells of 4 voxels (21 bits/axis)."""
    c = np.floor((P - origin) / (4.0 * h))
    c = np.clip(c, 0, (1 << 21) - 1).astype(np.uint64)
    key = np.zeros(P.shape[0], dtype=np.uint64)
    for b in range(21):
        for a in range(3):
            key |= ((c[:, a] >> np.uint64(b)) & np.uint64(1)) << np.uint64(3 * b + a)
    return np.argsort(key, kind="stable")


def _groups(keys, mask):
    """``(key, indices)`` for each key value among ``keys[mask]`` (one sort, instead
    of one pass over all rows per surface)."""
    idx = np.flatnonzero(mask)
    if not idx.size:
        return []
    k = keys[idx]
    order = np.argsort(k, kind="stable")
    idx = idx[order]
    k = k[order]
    cut = np.flatnonzero(np.diff(k)) + 1
    return [(int(k[a]), idx[a:b]) for a, b in zip(np.r_[0, cut], np.r_[cut, idx.size])]


def _pack(surfaces):
    """Concatenate the surfaces' kernel arrays (see :mod:`geomkit._kernels.project`)."""
    meta = np.zeros((len(surfaces), 7), dtype=np.int64)
    dom = np.zeros((len(surfaces), 4))
    Pw, U, V = [], [], []
    o = uo = vo = 0
    for i, s in enumerate(surfaces):
        H = s.homogeneous
        nu, nv = H.shape[:2]
        meta[i] = (o, nu, nv, s.degree_u, s.degree_v, uo, vo)
        (a, b), (c, d) = s.domain
        dom[i] = (a, b, c, d)
        Pw.append(H.reshape(-1, 4))
        U.append(s.knots_u)
        V.append(s.knots_v)
        o += nu * nv
        uo += s.knots_u.size
        vo += s.knots_v.size
    out = (np.ascontiguousarray(np.concatenate(Pw)), np.concatenate(U), np.concatenate(V))
    for a in out:
        # read-only like every Surface array, so the kernels share one compiled
        # signature of the evaluation chain (numba types read-only arrays apart)
        a.setflags(write=False)
    return out + (meta, dom)


def _c0_breaks(surfaces):
    """Borders of the C0 pieces of each surface (domain ends and interior knots of
    multiplicity >= degree): ``brk_all`` and ``brk_off[s] = (u offset, u count, v
    offset, v count)``."""
    parts, off, o = [], np.zeros((len(surfaces), 4), dtype=np.int64), 0
    for i, s in enumerate(surfaces):
        for k, (U, p) in enumerate(((s.knots_u, s.degree_u), (s.knots_v, s.degree_v))):
            inner = np.unique(U[p + 1:-p - 1])
            cuts = [t for t in inner if np.count_nonzero(U == t) >= p]
            b = np.array([U[p], *cuts, U[-p - 1]], dtype=np.float64)
            parts.append(b)
            off[i, 2 * k] = o
            off[i, 2 * k + 1] = b.size
            o += b.size
    return np.ascontiguousarray(np.concatenate(parts)), off


def _pack_trims(surfaces):
    """Trim segments of all surfaces for the kernel's foot classification
    (:func:`geomkit._kernels.foot_class._foot_class`): ``tseg`` (S, pmax+1, 3), ``tdeg``,
    ``tloop`` (S,), ``toff[s] = (offset, count, loops)``
    (:func:`geomkit.nurbs.trims.concat_segments`) and the band ``ttol[s]``
    (:func:`geomkit.nurbs.trimming.classify_uv`'s default)."""
    seg, deg, lp, toff = concat_segments(surfaces)
    ttol = np.array([tols.TRIM_TOL * max(s.domain[0][1] - s.domain[0][0],
                                         s.domain[1][1] - s.domain[1][0]) for s in surfaces])
    return seg, deg, lp, toff, ttol


class Projector(QueryBase):
    """Reusable projection onto fixed surfaces: the candidate mesh and voxel grid are
    built once (:func:`project_points` caches one per surface list).

    Parameters
    ----------
    surfaces : Surface or list of Surface
    mesh_tol : float, optional
        Chord tolerance of the candidate mesh (model units); default
        :data:`DEFAULT_MESH_TOL` times the largest surface size, which is also the
        largest value used (coarser meshes give too many near-tie candidates).  Finer
        meshes change speed, not the answer: it always comes from the exact surface.
    voxel_size : float, optional
        See :class:`~geomkit.VoxelGrid`; default its rule, or
        :func:`geomkit.query.voxel.sliver_voxel_size` for a mesh of slivers.
    size : float, optional
        The model size that relative tolerances scale with; default the largest
        surface's (a :class:`~geomkit.query.projection_part.PartProjector` gives its
        blocks the whole part's).
    """

    def __init__(self, surfaces, mesh_tol: float | None = None,
                 voxel_size: float | None = None, size: float | None = None):
        t0 = time.perf_counter()
        self.surfaces = as_surfaces(surfaces)
        self.size = max(s.size for s in self.surfaces) if size is None else float(size)
        if mesh_tol is None:
            mesh_tol = DEFAULT_MESH_TOL * self.size
        mesh_tol = self.check_mesh_tol(mesh_tol)
        # coarser candidate meshes let near-tie basins slip past the candidate limit
        # (seen at 2.5x the default on freeform_1): the default is also the maximum
        mesh_tol = min(mesh_tol, DEFAULT_MESH_TOL * self.size)
        self.mesh = tessellate_with_target(self.surfaces, mesh_tol, None, None, SAMPLES_PER_EDGE,
                                PROJ_TRIM_TARGET)
        # faces the mesh left out (a FaceFailedWarning was given): no candidate there
        self.face_errors = {i: st["failed"] for i, st in
                            enumerate(self.mesh.stats["surfaces"]) if "failed" in st}
        self.grid = VoxelGrid(self.mesh, voxel_size if voxel_size is not None
                              else sliver_voxel_size(self.mesh))
        self.trimmed = np.array([s.is_trimmed for s in self.surfaces], dtype=np.int64)
        tb = _trim_boundary_triangles(self.mesh, self.trimmed)
        self.fdev = np.ascontiguousarray(DEVIATION_SAFETY * (
            self.mesh.face_deviation + PROJ_TRIM_TARGET * self.mesh.tol * tb))
        self.dmax = float(self.fdev.max()) if self.fdev.size else 0.0
        # second-order certificate: the parameter box of each candidate's piece of its
        # face (trim slivers included, NaN: never settled; the deep flag: a foot in
        # the box is inside the face), each trimmed surface's grid of deep parameter
        # cells, and per-span derivative bounds
        # (geomkit.query.projection_cert)
        self.trim_pack = _pack_trims(self.surfaces)
        self.cert_pack = (*cert_boxes(self.mesh, self.surfaces, self.trimmed,
                                      self.trim_pack[4]),
                          *pack_span_bounds(
            self.surfaces, np.bincount(self.mesh.face_surface, minlength=len(self.surfaces))))
        self.certify = True
        # candidates of a trimmed face settled by a foot outside it
        # (geomkit._kernels.project_outside)
        self.outside_rule = True
        self.face_uv = np.ascontiguousarray(self.mesh.face_uv)
        self.face_surf = np.ascontiguousarray(self.mesh.face_surface.astype(np.int64))
        self.packed = _pack(self.surfaces)
        self.breaks = _c0_breaks(self.surfaces)
        # closed directions (seams are crossed) and free edges (only these are edges)
        self.closed = np.zeros((len(self.surfaces), 2), dtype=np.int64)
        self.free_edges = np.ones((len(self.surfaces), 4), dtype=bool)
        for i, s in enumerate(self.surfaces):
            cu, cv = closed_directions(s, s.size)
            self.closed[i] = (cu, cv)
            H = s.homogeneous
            X = H[..., :3] / H[..., 3:]
            eps = 1e-10 * s.size
            rows = (X[0], X[-1], X[:, 0], X[:, -1])  # u0, u1, v0, v1 edges
            for e, row in enumerate(rows):
                collapsed = np.ptp(row, axis=0).max() <= eps
                self.free_edges[i, e] = not (collapsed or (cu if e < 2 else cv))
        # achieved approximation error of each face (0 for exact NURBS; set on offset
        # surfaces approximated by NURBS): distances hold to the approximation, and
        # the lower bounds are widened by the largest one
        self.face_approx_error = np.array([float(getattr(s, "approx_error", 0.0) or 0.0)
                                           for s in self.surfaces])
        self.approx_error = float(self.face_approx_error.max())
        self.trims = {i: _TrimData(s) for i, s in enumerate(self.surfaces) if s.is_trimmed}
        self.morton = False  # Morton-ordered points: same answers, speed gain not
        # shown on the loaded machine (-20% .. +16% per case), so off by default
        self.build_time = time.perf_counter() - t0

    def __repr__(self) -> str:
        return (f"<Projector {len(self.surfaces)} surfaces, {self.mesh.faces.shape[0]} "
                f"candidate triangles, {self.grid!r}>")

    # ------------------------------------------------------------------ one chunk
    def _chunk(self, P: np.ndarray, max_distance, step_tol: float,
               K: int | None = None, prev=None) -> Projection:
        """Project the points of one chunk (``max_distance``: one for all, or one per
        point).  ``K`` and ``prev`` are given to a rerun:
        ``prev`` = (surface, uv, distance, Newton status, class, count, skip) of each
        point's feet from the earlier pass and the candidate index it stopped at; the
        rerun continues from there instead of repeating those Newton runs."""
        t0 = time.perf_counter()
        n = P.shape[0]
        # one search radius per point (a PartProjector gives each its best so far)
        max_distance = np.array(np.broadcast_to(max_distance, (n,)), dtype=np.float64)
        first = K is None
        if first:
            K = MAX_STARTS_TRIMMED if self.trims else MAX_STARTS
        # the kernel writes feet 0 .. nf-1 of each row before reading them; the columns
        # beyond are masked below (distance inf) and never read
        fs = np.empty((n, K), dtype=np.int64)
        fuv = np.empty((n, K, 2))
        fd = np.empty((n, K))
        fst = np.empty((n, K), dtype=np.int64)
        fcls = np.empty((n, K), dtype=np.int8)
        nf = np.zeros(n, dtype=np.int64)
        skip = np.zeros(n, dtype=np.int64)
        if prev is not None:
            k0 = prev[0].shape[1]
            for a, b in zip((fs, fuv, fd, fst, fcls), prev[:5]):
                a[:, :k0] = b
            nf[:] = prev[5]
            skip[:] = prev[6]
        nf0 = nf.copy()
        lb = np.zeros(n)
        rest = np.full(n, np.inf)
        flags = np.zeros(n, dtype=np.int64)
        work = np.zeros((n, 5), dtype=np.int64)
        g = self.grid
        Pw, U, V, meta, dom = self.packed
        # points in Morton order of their voxel: neighbours share cells and triangles
        # (cache locality); the kernel's answers are per point, unpermuted below
        order = _morton_order(P, g.origin, g.voxel_size) if self.morton and n > 1 else None
        if order is not None:
            fs, fuv, fd, fst, fcls, nf, skip = (a[order] for a in
                                                (fs, fuv, fd, fst, fcls, nf, skip))
        Pk = P if order is None else np.ascontiguousarray(P[order])
        mdk = max_distance if order is None else np.ascontiguousarray(max_distance[order])
        _pk.project_batch(Pk, g.vertices, g.faces, self.fdev, self.face_surf, self.face_uv,
                          self.dmax, *g._args(), Pw, U, V, meta, dom, self.closed,
                          self.trimmed, *self.breaks, *self.trim_pack, *self.cert_pack,
                          int(self.certify) | (2 if self.outside_rule else 0), step_tol,
                          mdk, K, skip, fs, fuv, fd,
                          fst, fcls, nf, lb, rest, flags, work)
        if order is not None:
            inv = np.empty(n, dtype=np.int64)
            inv[order] = np.arange(n)
            fs, fuv, fd, fst, fcls, nf, lb, rest, flags, work = (
                a[inv] for a in (fs, fuv, fd, fst, fcls, nf, lb, rest, flags, work))
        t1 = time.perf_counter()
        fd_raw = fd.copy()  # the kernel's feet, for a rerun that continues this pass
        cols = np.arange(K)[None, :]
        fd[cols >= nf[:, None]] = np.inf
        # trimmed faces: feet outside the face (classified in the kernel) are replaced
        # by the trim-boundary foot
        extra_d = np.full(n, np.inf)
        extra_uv = np.zeros((n, 2))
        extra_s = np.full(n, -1, dtype=np.int64)
        fdf = fd.reshape(-1)
        for si, flat in _groups(fs.reshape(-1), np.isfinite(fdf)
                                & (fcls.reshape(-1) == OUTSIDE)):
            td = self.trims[si]
            fdf[flat] = np.inf
            rows = np.unique(flat // K)
            s = self.surfaces[si]
            tuv = np.empty((rows.size, 2))
            td_ = np.empty(rows.size)
            tseg = np.empty(rows.size, dtype=np.int64)
            tt = np.empty(rows.size)
            Pr = np.ascontiguousarray(P[rows])
            _tf.trim_feet(Pr, s.homogeneous, s.degree_u, s.degree_v, s.knots_u, s.knots_v,
                          dom[si], td.seg, td.deg, td.nearest_samples(Pr), td.samp_seg,
                          td.samp_t, step_tol, tuv, td_, tseg, tt)
            better = td_ < extra_d[rows]
            r = rows[better]
            extra_d[r] = td_[better]
            extra_uv[r] = tuv[better]
            extra_s[r] = si
        t2 = time.perf_counter()
        # the nearest foot; feet within rounding of it (a foot on an edge shared by
        # two faces is found from both) go to the lowest surface index, so a point
        # gets one answer whatever the order the candidates came in
        rows = np.arange(n)
        dmin = np.minimum(fd.min(axis=1), extra_d)
        tie = (TIE_TOL * np.maximum(self.size, np.where(np.isfinite(dmin), dmin, 0.0)))[:, None]
        big = np.iinfo(np.int64).max
        key = np.where(fd <= dmin[:, None] + tie, fs, big)
        j = np.argmin(key, axis=1)
        best_d = fd[rows, j]
        trim_key = np.where(extra_d <= dmin + tie[:, 0], extra_s, big)
        use_trim = (trim_key < key[rows, j]) | ~np.isfinite(best_d)
        use_trim &= np.isfinite(extra_d)
        dist = np.where(use_trim, extra_d, best_d)
        uv = np.where(use_trim[:, None], extra_uv, fuv[rows, j])
        surf = np.where(use_trim, extra_s, fs[rows, j])
        cls = np.where(use_trim, BOUNDARY, fcls[rows, j])
        newton_ok = np.where(use_trim, True, fst[rows, j] == _pk.FOOT_OK)
        status = np.full(n, R.INTERIOR, dtype=np.int8)
        status[use_trim] = R.TRIM_EDGE
        found = np.isfinite(dist)
        beyond = ~found | (dist > max_distance)
        status[~newton_ok] = R.FAILED
        status[beyond] = R.BEYOND
        foot = np.full((n, 3), np.nan)
        nrm = np.full((n, 3), np.nan)
        resid = np.full(n, np.nan)
        live = (status != R.BEYOND) & (status != R.FAILED)
        idx = np.flatnonzero(live)
        if idx.size:
            # clamped to the domain; point and normal of every answer in one kernel pass
            ds = dom[surf[idx]]
            q = np.ascontiguousarray(uv[idx])
            q[:, 0] = np.clip(q[:, 0], ds[:, 0], ds[:, 1])
            q[:, 1] = np.clip(q[:, 1], ds[:, 2], ds[:, 3])
            uv[idx] = q
            fp = np.empty((idx.size, 3))
            fnr = np.empty((idx.size, 3))
            _pf.foot_frames(q, np.ascontiguousarray(surf[idx], dtype=np.int64), Pw, U, V,
                            meta, dom, tols.DEGENERATE_NORMAL, fp, fnr)
            foot[idx] = fp
            nrm[idx] = fnr
        for si, sel in _groups(surf, live):
            s = self.surfaces[si]
            (u0, u1), (v0, v1) = s.domain
            q = uv[sel]
            st = status[sel]
            eps_u = 1e-12 * (u1 - u0)
            eps_v = 1e-12 * (v1 - v0)
            fe = self.free_edges[si]
            edge = ((fe[0] & (q[:, 0] <= u0 + eps_u)) | (fe[1] & (q[:, 0] >= u1 - eps_u))
                    | (fe[2] & (q[:, 1] <= v0 + eps_v)) | (fe[3] & (q[:, 1] >= v1 - eps_v)))
            st[(st == R.INTERIOR) & edge] = R.DOMAIN_EDGE
            if s.is_trimmed:
                inner = st == R.INTERIOR
                if inner.any():
                    c = cls[sel][inner]  # the kernel's class of the foot (classify_uv's)
                    sub = st[inner]
                    sub[c != INSIDE] = R.TRIM_EDGE
                    st[inner] = sub
            status[sel] = st
        ok = (status != R.BEYOND) & (status != R.FAILED)
        diff = P - foot
        dist = np.where(ok, np.linalg.norm(diff, axis=1), np.nan)
        along = np.einsum("ij,ij->i", diff, nrm)
        signed = np.where(ok, np.copysign(dist, along), np.nan)
        signed[ok & (dist == 0)] = 0.0
        tang = np.sqrt(np.maximum(0.0, dist ** 2 - along ** 2))
        resid = np.where(status == R.INTERIOR, tang, np.where(ok, 0.0, np.nan))
        uv[~ok] = np.nan
        surf = np.where(ok, surf, -1).astype(np.int32)
        lower = np.where(ok, np.minimum(lb, dist), lb)
        if self.approx_error > 0.0:
            # approximated faces (e.g. IGES offset surfaces): the true face lies within
            # its approx_error of the one projected on
            lower = np.maximum(0.0, lower - self.approx_error)
        # the start cap left candidates untried whose lower bound is below the
        # answer: those points again with every candidate tried (the cap only
        # bounds the first pass's work), else they are counted as not proven
        open_ = rest < np.where(ok, dist, np.inf) - TIE_TOL * self.size
        # a later pass reruns only points whose cap left candidates untried (more
        # candidates than K): with every candidate tried, an open point is not proven
        again = open_ if first else open_ & (work[:, 2] > K)
        reruns = int(np.count_nonzero(again))
        n_open = 0 if first else int(np.count_nonzero(open_ & ~again))
        out = Projection(point=foot, uv=uv, surface=surf, distance=dist,
                         signed_distance=signed, normal=nrm, status=status,
                         lower_bound=lower, residual=resid,
                         feet_tried=np.minimum(nf, 127).astype(np.int8),
                         stats={"candidate_overflow": int(np.count_nonzero(flags & 1)),
                                 "cells_opened": int(work[:, 0].sum()),
                                 "triangles_tested": int(work[:, 1].sum()),
                                 "newton_runs": int((nf - nf0).sum()),
                                 "certified_skips": int(work[:, 4].sum()),
                                 "lower_bound_above_distance":
                                     int(np.count_nonzero(ok & (lb > dist))),
                                 "approx_error": self.approx_error,
                                 "start_cap_reruns": reruns,
                                 "not_proven": n_open,
                                 "time_kernel": t1 - t0, "time_trim": t2 - t1,
                                 "time_finish": time.perf_counter() - t2})
        if reruns:
            rows = np.flatnonzero(again)
            most = int(work[rows, 2].max())
            if first:  # the second pass: as many starts as its points' candidates
                K2 = int(min(RERUN_STARTS_MAX, max(RERUN_STARTS, most)))
                batches = [rows]
            else:  # the last resort for the few points beyond that: every candidate,
                K2 = most  # in batches of bounded memory (points x starts)
                step = max(1, RERUN_BUDGET // K2)
                batches = [rows[i:i + step] for i in range(0, rows.size, step)]
            for b in batches:
                prev_b = (fs[b], fuv[b], fd_raw[b], fst[b], fcls[b], nf[b], work[b, 3])
                sub = self._chunk(np.ascontiguousarray(P[b]), max_distance[b], step_tol, K2,
                                  prev_b)
                for f in ("point", "uv", "surface", "distance", "signed_distance",
                          "normal", "status", "lower_bound", "residual", "feet_tried"):
                    getattr(out, f)[b] = getattr(sub, f)
                for k_ in ("newton_runs", "not_proven", "start_cap_reruns",
                           "certified_skips"):
                    out.stats[k_] += sub.stats[k_]
        return out

    def _stats(self) -> dict:
        return {"candidate_triangles": int(self.mesh.faces.shape[0]),
                "faces_failed": dict(self.face_errors)}
