"""Open CASCADE oracles for tests/cad/test_cad_oracle.py: distances of points to a shape
and plane sections compared both ways (helpers, not tests)."""

from __future__ import annotations

import numpy as np

import geomkit
from geomkit.section.joins import EDGE_REACH


def _occ_faces(shape):
    from OCP.TopAbs import TopAbs_FACE
    from OCP.TopExp import TopExp_Explorer

    from geomkit.cad.occ import cast_shape

    ex, out = TopExp_Explorer(shape, TopAbs_FACE), []
    while ex.More():
        out.append(cast_shape("Face", ex.Current()))
        ex.Next()
    return out


def _occ_distances(shape, pts, bound):
    """OCC's distance of each point, over the faces whose bounding box is within
    ``bound[i]`` (+1e-6) of the point: exact pruning for the comparison (a face farther
    away than ``bound`` cannot hold a distance below it).  Returns (d, on_edge)."""
    from OCP.Bnd import Bnd_Box
    from OCP.BRep import BRep_Builder
    from OCP.BRepBndLib import BRepBndLib
    from OCP.BRepBuilderAPI import BRepBuilderAPI_MakeVertex
    from OCP.BRepExtrema import BRepExtrema_DistShapeShape, BRepExtrema_SupportType
    from OCP.gp import gp_Pnt
    from OCP.TopoDS import TopoDS_Compound

    faces = _occ_faces(shape)
    lo, hi = np.empty((len(faces), 3)), np.empty((len(faces), 3))
    for i, f in enumerate(faces):
        b = Bnd_Box()
        BRepBndLib.Add_s(f, b)
        a, c = b.CornerMin(), b.CornerMax()
        lo[i], hi[i] = (a.X(), a.Y(), a.Z()), (c.X(), c.Y(), c.Z())
    d, edge = np.empty(len(pts)), np.zeros(len(pts), bool)
    for k, p in enumerate(pts):
        gap = np.linalg.norm(np.maximum(0, np.maximum(lo - p, p - hi)), axis=1)
        near = np.nonzero(gap <= bound[k] + 1e-6)[0]
        comp, bb = TopoDS_Compound(), BRep_Builder()
        bb.MakeCompound(comp)
        for i in near:
            bb.Add(comp, faces[i])
        ds = BRepExtrema_DistShapeShape(BRepBuilderAPI_MakeVertex(gp_Pnt(*p)).Vertex(), comp)
        d[k] = ds.Value()
        edge[k] = any(ds.SupportTypeShape2(j) != BRepExtrema_SupportType.BRepExtrema_IsInFace
                      for j in range(1, ds.NbSolution() + 1))
    return d, edge


# ------------------------------------------------------------ sections
SECTION_TOL = 1e-3
RESAMPLE = 2e-3
"""Both sides' curves are resampled (linearly along their polylines) at most this far
apart for the k-d tree distance checks; a nearest-sample distance overestimates the
distance to the polyline by at most half of it."""

OCC_DEFLECTION = 1e-4
"""OCC's section edges are sampled by GCPnts_QuasiUniformDeflection with this chord
deflection: its polyline lies within it of OCC's curve."""

SECTION_PLANES = [  # (axis, coordinate): what the plane cuts
    (0, 5.9),      # blades and hub; OCC adds a shared edge 0.12 off the plane (see below)
    (0, -33.3),    # rim and two blades
    (0, 30.75),    # rim, near its tangency (normal along x at x ~ 30.75)
    (1, -41.3),    # grazing the rim (y >= -41.39 on the model)
    (1, 23.3),     # blades, hub, rim
    (1, 15.15),    # near a tangency (normal along y at y ~ 15.15)
    (2, 1.2),      # top
    (2, 2.8),      # just below the top's tangency at z = 2.837
    (2, -9.3),     # all the blades and the hub
    (2, -29.55),   # hub fillets, normal nearly along z
    (2, -30.1),    # the blades' sliver faces (u-width 4.6e-4, e.g. 144@8731)
]
STEP_PLANES = [(0, 5.9), (2, -9.3)]

_OCC_SECTIONS: dict = {}


def _occ_section(shape, axis, c):
    """OCC's section of ``shape`` by the plane ``x[axis] = c``: BRepAlgoAPI_Section built
    once per plane, approximation and p-curves off.  Returns a dict: ``edges`` (list of
    (k, 3) points of each edge, chord deflection <= OCC_DEFLECTION), ``tols`` (OCC's
    tolerance of each edge), ``time`` (seconds in Build) and ``occ_edges`` (the edges)."""
    key = (id(shape), axis, c)
    if key in _OCC_SECTIONS:
        return _OCC_SECTIONS[key]
    import time

    from OCP.BRep import BRep_Tool
    from OCP.BRepAdaptor import BRepAdaptor_Curve
    from OCP.BRepAlgoAPI import BRepAlgoAPI_Section
    from OCP.GCPnts import GCPnts_QuasiUniformDeflection
    from OCP.gp import gp_Dir, gp_Pln, gp_Pnt
    from OCP.TopAbs import TopAbs_EDGE
    from OCP.TopExp import TopExp_Explorer

    from geomkit.cad.occ import cast_shape

    n = np.zeros(3)
    n[axis] = 1
    t0 = time.perf_counter()
    sec = BRepAlgoAPI_Section(shape, gp_Pln(gp_Pnt(*(n * c)), gp_Dir(*n)), False)
    sec.Approximation(False)
    sec.ComputePCurveOn1(False)
    sec.ComputePCurveOn2(False)
    sec.Build()
    assert sec.IsDone()
    t = time.perf_counter() - t0
    ex, edges, tols, occ_edges = TopExp_Explorer(sec.Shape(), TopAbs_EDGE), [], [], []
    while ex.More():
        e = cast_shape("Edge", ex.Current())
        q = GCPnts_QuasiUniformDeflection(BRepAdaptor_Curve(e), OCC_DEFLECTION)
        assert q.IsDone()
        edges.append(np.array([[p.X(), p.Y(), p.Z()] for p in map(q.Value, range(
            1, q.NbPoints() + 1))]))
        tols.append(BRep_Tool.Tolerance_s(e))
        occ_edges.append(e)
        ex.Next()
    out = _OCC_SECTIONS[key] = {"edges": edges, "tols": np.array(tols), "time": t,
                                "occ_edges": occ_edges}
    return out


def _occ_wires(occ_edges, keep, join):
    """OCC's wires (ShapeAnalysis_FreeBounds.ConnectEdgesToWires within ``join``) of the
    edges ``keep``: a list of (closed, (m, 3) points: each edge's ends and middle)."""
    from OCP.BRep import BRep_Tool
    from OCP.BRepAdaptor import BRepAdaptor_Curve
    from OCP.collections import HSequence_TopoDS_Shape
    from OCP.ShapeAnalysis import ShapeAnalysis_FreeBounds
    from OCP.TopAbs import TopAbs_EDGE, TopAbs_VERTEX
    from OCP.TopExp import TopExp_Explorer
    from scipy.spatial import cKDTree

    from geomkit.cad.occ import cast_shape

    seq = HSequence_TopoDS_Shape()
    for i in keep:
        seq.Append(occ_edges[i])
    wires = ShapeAnalysis_FreeBounds.ConnectEdgesToWires_s(seq, join, False)
    out = []
    for k in range(1, wires.Length() + 1):
        w = wires.Value(k)
        # closed: every vertex of the wire is shared by two of its edge ends
        ends, pts = [], []
        ex = TopExp_Explorer(w, TopAbs_EDGE)
        while ex.More():
            e = cast_shape("Edge", ex.Current())
            a = BRepAdaptor_Curve(e)
            for t in (a.FirstParameter(), 0.5 * (a.FirstParameter() + a.LastParameter()),
                      a.LastParameter()):
                p = a.Value(t)
                pts.append((p.X(), p.Y(), p.Z()))
            vx = TopExp_Explorer(e, TopAbs_VERTEX)
            while vx.More():
                p = BRep_Tool.Pnt_s(cast_shape("Vertex", vx.Current()))
                ends.append((p.X(), p.Y(), p.Z()))
                vx.Next()
            ex.Next()
        E = np.array(ends)
        cnt = np.array([len(j) for j in cKDTree(E).query_ball_point(E, join)])
        out.append((bool(np.all(cnt >= 2)), np.array(pts)))
    return out


def _resample(curves, closed, h):
    """Points along each polyline (closed ones wrap) at most ``h`` apart, its vertices
    included; and the curve index of each."""
    P, ids = [], []
    for k, (X, cl) in enumerate(zip(curves, closed)):
        Y = np.vstack([X, X[:1]]) if cl else X
        d = np.diff(Y, axis=0)
        m = np.maximum(1, np.ceil(np.linalg.norm(d, axis=1) / h)).astype(int)
        seg = np.repeat(np.arange(len(d)), m)
        t = (np.arange(m.sum()) - np.repeat(np.cumsum(m) - m, m)) / np.repeat(m, m)
        Q = np.vstack([Y[seg] + t[:, None] * d[seg], Y[-1:]])
        P.append(Q)
        ids.append(np.full(len(Q), k))
    return np.concatenate(P), np.concatenate(ids)


def _check_section(surfaces, gap, shape, occ, axis, c, label):
    """geomkit's plane_section(surfaces, x[axis] = c, tol=SECTION_TOL, gap) against OCC's
    section ``occ`` (see _occ_section) both ways:

    * OCC edges farther than tol from the plane are not sections (OCC's IGES translation
      gives some shared edges a tolerance up to 0.16 and its Boolean then takes an edge
      lying within its tolerance of the plane as lying in it): each must be within
      OCC's own tolerance of the plane; they are left out.
    * every other OCC point within tol + gap (+ RESAMPLE / 2) of a geomkit curve;
    * every geomkit point within tol + gap (+ OCC_DEFLECTION + RESAMPLE / 2) of OCC's
      edges, or else a real point of its face, inside the trim, on the plane, and
      within tol + gap of OCC's model ``shape`` (OCC's section skips some sliver
      faces and, near a tangency, part of a face's section);
    * closed where OCC's wires (its edges connected within tol + gap) are closed.
    """
    import time

    from scipy.spatial import cKDTree

    tol = SECTION_TOL
    n = np.zeros(3)
    n[axis] = 1
    t0 = time.perf_counter()
    S = geomkit.plane_section(surfaces, np.append(n, -c), tol=tol, gap=gap)
    t_gk = time.perf_counter() - t0
    name = f"{label} {'xyz'[axis]} = {c}"
    if not occ["edges"]:  # OCC finds nothing: neither may geomkit
        print(f"\n{name}: no section (OCC), geomkit {len(S.curves)} curves")
        assert not S.curves and not len(S.points)
        return
    # ends joined within max(tol, gap), or across an edge the plane crosses obliquely
    assert S.curves and S.max_gap_bridged <= EDGE_REACH * gap
    resid = np.array([np.abs(Q[:, axis] - c).max() for Q in occ["edges"]])
    off = np.nonzero(resid > tol)[0]
    assert np.all(resid[off] <= occ["tols"][off]), (name, resid[off], occ["tols"][off])
    keep = np.nonzero(resid <= tol)[0]
    O = np.concatenate([occ["edges"][i] for i in keep])
    # OCC -> geomkit
    G, gid = _resample(S.curves, S.closed, RESAMPLE)
    d_occ, near = cKDTree(G).query(O)
    allow = tol + gap + RESAMPLE / 2
    # geomkit -> OCC
    Oc, _ = _resample([occ["edges"][i] for i in keep], [False] * len(keep), RESAMPLE)
    X = np.concatenate(S.curves)
    d_gk = cKDTree(Oc).query(X)[0]
    far = np.nonzero(d_gk > allow + OCC_DEFLECTION)[0]
    sid, uv = np.concatenate(S.surface_index), np.concatenate(S.uv)
    for i in far:
        f = surfaces[sid[i]]
        assert f.classify_uv(uv[i:i + 1])[0] != geomkit.OUTSIDE, (name, i)
        assert np.linalg.norm(f.evaluate(uv[i:i + 1])[0] - X[i]) < 1e-9 * f.size
        assert abs(X[i] @ n - c) < 1e-9 * f.size
    # ... and OCC's model holds them (BRepExtrema), on up to 8 of them
    some = far[np.linspace(0, far.size - 1, min(8, far.size)).astype(int)] if far.size else far
    d_model = _occ_distances(shape, X[some], np.full(some.size, allow))[0]
    assert np.all(d_model <= tol + gap), (name, X[some], d_model)
    # closed where OCC's wires are closed
    wires = _occ_wires(occ["occ_edges"], keep, tol + gap)
    tree = cKDTree(G)
    open_where_occ_closed = 0
    for closed, W in wires:
        if closed:
            dw, j = tree.query(W)
            touched = set(gid[j[dw <= allow]].tolist())
            open_where_occ_closed += sum(not S.closed[k] for k in touched)
    print(f"\n{name}: geomkit {len(S.curves)} curves ({sum(S.closed)} closed) in "
          f"{t_gk:.2f} s, OCC {len(occ['edges'])} edges, {len(wires)} wires "
          f"({sum(w[0] for w in wires)} closed) in {occ['time']:.2f} s; OCC edges off the "
          f"plane {off.size} (OCC tolerance {occ['tols'][off].max() if off.size else 0:.3g})"
          f"; bridged {S.max_gap_bridged:.3g}; OCC -> geomkit {d_occ.max():.3g}, geomkit "
          f"-> OCC {d_gk.max():.3g} (allowed {allow:.3g}); geomkit points off OCC's edges "
          f"{far.size} (faces {sorted({surfaces[sid[i]].name for i in far})}; OCC's model "
          f"within {d_model.max() if some.size else 0:.3g} of them)")
    assert d_occ.max() <= allow, (name, O[np.argmax(d_occ)])
    assert open_where_occ_closed == 0, name
