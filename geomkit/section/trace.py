"""Tracing of a plane section on one surface: leaves -> crossings -> chains -> exact points.

Private helper of :mod:`geomkit.section.plane` (Paper 2 plus certification and Newton
refinement).  Works in the parameter plane of one surface; joining across surfaces,
trims and the public result live in :mod:`geomkit.section.plane`.
"""

from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree

from geomkit.tolerances import EDGE_ROOT_TOL
from geomkit._kernels import section as K, section_project as KP, section_trims as KT
from geomkit._kernels.section_refine import refine_chains
from geomkit._kernels.surface import surface_points, surface_points_range

SERIAL_POINTS = 8192
""":meth:`_Eval.points` evaluates up to this many points in the calling thread (the same
bits as the threaded batch: each point alone).  A section's points per surface are
mostly a few hundred: 166 batches of 6 bench planes (26,144 points, at most 1,430 in
one) took 1.8-2.1 ms serial against 3.2-4.9 ms threaded, CPU and wall alike."""

MAX_ROUNDS = 60
"""Chord refinement halves a chain segment at most this many times
(:func:`geomkit._kernels.section_refine.refine_chains`)."""


class _Eval:
    """Kernel arguments of one surface and the plane, bundled."""

    def __init__(self, surface, plane):
        self.s = surface
        self.args = (surface.homogeneous, surface.degree_u, surface.degree_v,
                     surface.knots_u, surface.knots_v, plane)
        (u0, u1), (v0, v1) = surface.domain
        self.box = np.array([u0, u1, v0, v1])
        self.plane = plane

    def f(self, uv):
        uv = np.ascontiguousarray(uv, dtype=np.float64).reshape(-1, 2)
        out = np.empty(uv.shape[0])
        K.plane_values(*self.args, uv, out)
        return out

    def points(self, uv):
        uv = np.ascontiguousarray(uv, dtype=np.float64).reshape(-1, 2)
        out = np.empty((uv.shape[0], 3))
        a = self.args
        if uv.shape[0] <= SERIAL_POINTS:
            surface_points_range(0, uv.shape[0], a[0], a[1], a[2], a[3], a[4], uv, out)
        else:
            surface_points(a[0], a[1], a[2], a[3], a[4], uv, out)
        return out

    def roots(self, a, b, fa, fb):
        """Parameters of the root on segments a -> b (fa * fb < 0), (n, 2)."""
        a = np.ascontiguousarray(a, dtype=np.float64)
        b = np.ascontiguousarray(b, dtype=np.float64)
        t = np.empty(a.shape[0])
        K.edge_roots(*self.args, a, b, np.ascontiguousarray(fa), np.ascontiguousarray(fb),
                     EDGE_ROOT_TOL, t)
        return a + t[:, None] * (b - a)

    def project(self, uv, maxstep, ftol, maxit=40):
        uv = np.ascontiguousarray(uv, dtype=np.float64).reshape(-1, 2)
        out = np.empty_like(uv)
        f = np.empty(uv.shape[0])
        KP.project(*self.args, uv, np.ascontiguousarray(maxstep, dtype=np.float64), self.box,
                  ftol, maxit, out, f)
        return out, f

    def trim_crossings(self, a, b, ftol, band, wide_tol, iters, stop):
        """:func:`geomkit._kernels.section_trims.trim_crossings` against the surface's trims:
        ``a``, ``b`` (n, 2) float64 C arrays, bisected in place."""
        seg, deg, lp, nloops = self.s.trim_segments()
        KT.trim_crossings(*self.args, a, b, self.box, float(ftol), float(band),
                         float(wide_tol), seg, deg, lp, nloops, int(iters), float(stop))

    def densify(self, uv, h, ftol, maxdepth):
        """:func:`geomkit._kernels.section_project.densify` of the polyline ``uv`` (n, 2)."""
        uv = np.ascontiguousarray(uv, dtype=np.float64).reshape(-1, 2)
        return KP.densify(*self.args, uv, float(h), self.box, float(ftol), int(maxdepth))


SMALL_ROWS = 32
""":func:`unique_rows` sorts at most this many rows in Python (no numpy call per step:
a surface's leaves are mostly one or two)."""


def unique_rows(a):
    """``np.unique(a, axis=0, return_inverse=True)`` of an (n, 2) array, n >= 1: the
    distinct rows in lexicographic order and the index of each row among them (by a
    stable lexsort, ~5x faster than unique's sort of a structured view; of rows equal
    as numbers, e.g. -0.0 and 0.0, the first is kept).  Up to :data:`SMALL_ROWS` rows
    without NaN are sorted as Python lists (compared element by element with ``==``
    and ``<``, as lexsort compares: the same order, the same rows kept)."""
    n = len(a)
    if n <= SMALL_ROWS:
        rows = a.tolist()
        if all(x == x and y == y for x, y in rows):
            order = sorted(range(n), key=rows.__getitem__)
            first, inv, prev = [], [0] * n, None
            for i in order:
                if prev is None or rows[i] != prev:
                    first.append(i)
                    prev = rows[i]
                inv[i] = len(first) - 1
            return a[first], np.array(inv, dtype=np.intp)
    return _unique_rows_sorted(a)


def _unique_rows_sorted(a):
    """:func:`unique_rows` by numpy's lexsort."""
    order = np.lexsort((a[:, 1], a[:, 0]))
    s = a[order]
    new = np.empty(len(a), bool)
    new[0] = True
    new[1:] = (s[1:, 0] != s[:-1, 0]) | (s[1:, 1] != s[:-1, 1])
    inv = np.empty(len(a), np.intp)
    inv[order] = np.cumsum(new) - 1
    return s[new], inv


def _merge_nodes(uv, radius):
    """Union nodes closer than ``radius`` in UV; returns (representative index per node).

    Nodes are first checked for any pair within ``radius`` (times 1 + 1e-9) along both
    u and v (:func:`geomkit._kernels.section.has_close_pair`, a superset of the pairs
    the tree finds); without one, every node is its own (most surfaces)."""
    n = uv.shape[0]
    parent = np.arange(n)
    if n > 1 and K.has_close_pair(uv, np.lexsort((uv[:, 1], uv[:, 0])),
                                  float(radius) * (1 + 1e-9)):
        pairs = cKDTree(uv).query_pairs(radius, output_type="ndarray")

        def find(i):
            while parent[i] != i:
                parent[i] = parent[parent[i]]
                i = parent[i]
            return i

        for i, j in pairs:
            ri, rj = find(i), find(j)
            if ri != rj:
                parent[max(ri, rj)] = min(ri, rj)
        for i in range(n):
            parent[i] = find(i)
    return parent


def trace_surface(surface, plane, tol, zsnap, min_diam, max_depth=80):
    """Section chains of one surface in its parameter plane.

    Returns
    -------
    chains : list of dict ``{"uv": (k, 2), "closed": bool, "chord": float}``, points
        exact (Newton / bracketed roots on f = 0) and spaced so that the chord
        deviation measured at every segment's curve midpoint is <= ``tol``.
    contacts : (m, 2) UV of isolated contact candidates (tangency, pole).
    stats : dict of counts.
    """
    ev = _Eval(surface, plane)
    bp = surface.bezier_patches()
    leaves, visited = K.subdivide(bp.homogeneous, bp.u_breaks, bp.v_breaks, plane, zsnap,
                                  min_diam, max_depth)
    unres = np.flatnonzero(leaves[:, 4] == K.UNRESOLVED)
    stats = {"subpatches": int(visited), "leaves": int(len(leaves)),
             "unresolved": len(unres)}
    if len(leaves) == 0:
        return [], np.empty((0, 2)), stats
    dom = max(ev.box[1] - ev.box[0], ev.box[3] - ev.box[2])
    # ---- corners: one evaluation per distinct UV corner
    L = len(leaves)
    corners = np.empty((L, 4, 2))       # u0 v0, u1 v0, u1 v1, u0 v1 of each leaf
    corners[:, :, 0] = leaves[:, [0, 1, 1, 0]]
    corners[:, :, 1] = leaves[:, [2, 2, 3, 3]]
    cuniq, cidx = unique_rows(corners.reshape(-1, 2))
    cidx = cidx.reshape(L, 4)
    fc = ev.f(cuniq)
    fc[np.abs(fc) <= zsnap] = 0.0
    # ---- strict crossings on leaf edges (distinct edges only)
    EDGES = ((0, 1), (1, 2), (3, 2), (0, 3))
    ea = cidx[:, [0, 1, 3, 0]]
    eb = cidx[:, [1, 2, 2, 3]]
    fa, fb = fc[ea], fc[eb]
    strict = (fa * fb) < 0
    key = np.column_stack((ea[strict], eb[strict]))
    ukey, kinv = unique_rows(key) if len(key) else (
        np.empty((0, 2), int), np.empty(0, int))
    roots = ev.roots(cuniq[ukey[:, 0]], cuniq[ukey[:, 1]], fc[ukey[:, 0]], fc[ukey[:, 1]]) \
        if len(ukey) else np.empty((0, 2))
    # node table: corners first (ids 0..nc-1), then roots
    nc = len(cuniq)
    node_uv = np.concatenate([cuniq, roots])
    rep = _merge_nodes(node_uv, 1e-11 * dom)
    root_id = np.full((L, 4), -1)
    root_id[strict] = nc + kinv.ravel()
    # ---- link crossings inside each leaf
    edges = {}
    hubs = []  # (leaf, [node ids])
    used = np.zeros(len(node_uv), bool)
    F4 = fc[cidx]
    P1, P2 = F4 >= 0, F4 > 0
    # leaves with a sign change on an edge under either convention (the others link
    # nothing), walked with Python numbers
    act = np.flatnonzero((P1.any(axis=1) & ~P1.all(axis=1)) | (P2.any(axis=1) & ~P2.all(axis=1)))
    rep_l = rep.tolist()
    for li, f4, p1, p2, cid, rid, state in zip(
            act.tolist(), F4[act].tolist(), P1[act].tolist(), P2[act].tolist(),
            cidx[act].tolist(), root_id[act].tolist(), leaves[act, 4].tolist()):
        for pos in (p1, p2):
            cross = []
            for e, (i, j) in enumerate(EDGES):
                if pos[i] == pos[j]:
                    continue
                if f4[i] != 0 and f4[j] != 0:
                    nid = rid[e]
                else:
                    nid = cid[i] if f4[i] == 0 else cid[j]
                cross.append(rep_l[nid])
            if not cross:
                continue
            if len(cross) == 2:
                pairs = [(cross[0], cross[1])]
            elif state != K.UNRESOLVED:
                c = 1 if state == K.MONO_U else 0      # graph coordinate
                order = sorted(cross, key=lambda n: (node_uv[n, c], node_uv[n, 1 - c]))
                pairs = list(zip(order[0::2], order[1::2]))
            else:
                hubs.append((li, cross))
                pairs = []
            for a, b in pairs:
                if a != b:
                    edges[(min(a, b), max(a, b))] = li
                    used[a] = used[b] = True
            break  # the second convention only where the first found nothing
    # hubs: a junction point inside an unresolved leaf (singular crossing)
    if hubs:
        boxes = np.array([leaves[li, :4] for li, _ in hubs])
        huv = np.empty((len(hubs), 2))
        hf = np.empty(len(hubs))
        K.critical_points(*ev.args, boxes, 30, huv, hf)
        base = len(node_uv)
        node_uv = np.concatenate([node_uv, huv])
        rep = np.concatenate([rep, base + np.arange(len(hubs))])
        used = np.concatenate([used, np.ones(len(hubs), bool)])
        for k, (li, cross) in enumerate(hubs):
            for a in cross:
                edges[(min(a, base + k), max(a, base + k))] = li
                used[a] = True
    # ---- contact candidates: zero corners on no segment; unresolved leaves without any
    zero_c = np.nonzero((fc == 0) & ~used[rep[:nc]])[0]
    contacts = [cuniq[zero_c]]
    lonely = [li for li in unres.tolist() if not np.any(used[rep[cidx[li]]])]
    if lonely:
        boxes = np.ascontiguousarray(leaves[lonely, :4])
        cuv = np.empty((len(lonely), 2))
        cf = np.empty(len(lonely))
        K.critical_points(*ev.args, boxes, 30, cuv, cf)
        contacts.append(cuv[cf <= zsnap])
    contacts = np.concatenate(contacts) if contacts else np.empty((0, 2))
    # ---- chains
    chains = _chains(edges)
    stats["crossings"] = int(len(roots))
    out = []
    if chains:
        # every chain of the surface refined in one kernel call
        starts = np.cumsum([0] + [len(nodes) for nodes, _ in chains])
        allnodes = np.concatenate([nodes for nodes, _ in chains])
        segleaf = np.zeros(len(allnodes), np.int64)
        for (nodes, _), s0 in zip(chains, starts):
            segleaf[s0:s0 + len(nodes) - 1] = [edges[(min(a, b), max(a, b))]
                                               for a, b in zip(nodes[:-1], nodes[1:])]
        ruv, rstarts, chord = refine_chains(
            *ev.args, leaves, np.ascontiguousarray(node_uv[allnodes]), segleaf, starts,
            float(tol), float(zsnap), EDGE_ROOT_TOL, ev.box, MAX_ROUNDS)
        for k, (_nodes, closed) in enumerate(chains):
            uv = ruv[rstarts[k]:rstarts[k + 1] - (1 if closed else 0)]
            out.append({"uv": uv, "closed": bool(closed), "chord": float(chord[k])})
    return out, contacts, stats


def _chains(edges):
    """Split a graph (dict of (a, b) edges) into chains of node ids.

    Nodes of degree != 2 end chains (so branches meet at junctions); what remains are
    cycles.  Returns [(nodes list, closed)], a closed chain repeating its first node.
    """
    adj = {}
    for a, b in edges:
        adj.setdefault(a, []).append(b)
        adj.setdefault(b, []).append(a)
    seen = set()
    out = []

    def walk(start, nxt):
        path = [start, nxt]
        seen.add((min(start, nxt), max(start, nxt)))
        prev, cur = start, nxt
        while len(adj[cur]) == 2 and cur != start:
            a, b = adj[cur]
            step = b if a == prev else a
            e = (min(cur, step), max(cur, step))
            if e in seen:
                break
            seen.add(e)
            path.append(step)
            prev, cur = cur, step
        return path

    for n in adj:
        if len(adj[n]) != 2:
            for m in adj[n]:
                if (min(n, m), max(n, m)) not in seen:
                    out.append((walk(n, m), False))
    for n in adj:
        for m in adj[n]:
            if (min(n, m), max(n, m)) not in seen:
                path = walk(n, m)
                out.append((path, path[0] == path[-1]))
    return out
