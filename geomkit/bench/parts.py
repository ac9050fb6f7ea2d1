"""Whole real parts against Open CASCADE, same run: read, mesh, section, project.

For each STEP part (default: the real parts in the repository's ``tests/data/parts``,
see its README for their sources), beside OCC in the same process:

* **read** -- :func:`geomkit.cad.step.read_step` with ``cache=False`` (geomkit's own
  STEP reader: parse, convert every face with its trims from the 3-D edges, edge
  gaps) against ``STEPControl_Reader.ReadFile`` + ``TransferRoots`` alone.  No error
  column: the faces are checked against OCC face by face in
  ``tests/cad/test_real_parts.py``.  **read again**: the same file read a second time,
  from the read cache (:mod:`geomkit.cad.readcache`), against the same OCC read.
* **tessellate** at 1e-3 of the part's size -- :func:`geomkit.tessellate` against
  ``BRepMesh_IncrementalMesh`` at the same linear deflection.  Error (both): the
  largest distance to the exact model of triangle centroids and edge midpoints of up to
  4,000 sampled triangles (geomkit's exact projection onto all faces).
* **section** through the middle of the part's box, normal to each axis --
  :func:`geomkit.plane_section` with the file's edge gap, chord tolerance 1e-4 of the
  size, against ``BRepAlgoAPI_Section`` with its edges discretised at the same
  deflection.  Note: curves (closed) against OCC's wires (closed), joined within the
  gap.
* **projector build** -- :func:`geomkit.query.projection_part.make_projector` (a
  :class:`~geomkit.PartProjector` above 128 faces: bounds only, blocks built when a
  query reaches them), with the time of a first query of 20 points near one spot (the
  blocks it builds) in the note.  OCC's distance has no build step.
* **project** -- :meth:`project` of 2,000 points within 1 % of the size of the
  surface on the projector once built, per point, against
  ``BRepExtrema_DistShapeShape`` per point on the first 40.  Error: geomkit's largest
  difference from OCC on those 40 (OCC measures to the edges' 3-D curves near edges,
  up to the file's edge tolerance away).

Reading and meshing are timed in turn with OCC's (:func:`alternate`: medians of 3 runs
each, 7 with ``--full``), so that a slow first run or the machine's drift falls on both
sides; the other stages are medians of their own runs.

Usage: ``python -m geomkit.bench.parts [--full]``
"""

from __future__ import annotations

import argparse
import time
import warnings
from pathlib import Path

import numpy as np

PARTS_DIR = Path(__file__).resolve().parents[2] / "tests" / "data" / "parts"
QUICK = ("nx9_face_recognition_ap214.stp", "sw2013_featuretype_ap214.step",
         "nist_ctc_01_ap203.stp")


def _occ_read(path):
    from geomkit.cad.step import occ_shape

    return occ_shape(path)[0]


def _occ_mesh_points(shape, deflection):
    """BRepMesh of the shape; returns (centroids and edge midpoints (m, 3), triangles)."""
    from OCP.BRep import BRep_Tool
    from OCP.BRepMesh import BRepMesh_IncrementalMesh
    from OCP.TopAbs import TopAbs_FACE
    from OCP.TopExp import TopExp_Explorer
    from OCP.TopLoc import TopLoc_Location

    from geomkit.cad.occ import cast_shape, xyz

    BRepMesh_IncrementalMesh(shape, deflection)
    pts, ntri = [], 0
    ex = TopExp_Explorer(shape, TopAbs_FACE)
    while ex.More():
        f = cast_shape("Face", ex.Current())
        ex.Next()
        loc = TopLoc_Location()
        tri = BRep_Tool.Triangulation_s(f, loc)
        if tri is None:
            continue
        T = loc.Transformation()
        V = np.array([xyz(tri.Node(i).Transformed(T)) for i in range(1, tri.NbNodes() + 1)])
        F = np.array([tri.Triangle(i).Get() for i in range(1, tri.NbTriangles() + 1)]) - 1
        ntri += len(F)
        pts.append((V, F))
    return pts, ntri


def _occ_mesh_run(path, deflection):
    """``(seconds, None)`` of one ``BRepMesh_IncrementalMesh`` alone, on a fresh read
    (a meshed shape is not meshed again)."""
    from OCP.BRepMesh import BRepMesh_IncrementalMesh

    shape = _occ_read(path)
    t0 = time.perf_counter()
    BRepMesh_IncrementalMesh(shape, deflection)
    return time.perf_counter() - t0, None


def _timed(fn):
    """A run of ``fn()`` as ``(seconds, result)``."""
    def run():
        t0 = time.perf_counter()
        out = fn()
        return time.perf_counter() - t0, out
    return run


def alternate(run_a, run_b, repeat):
    """``(median a, last result of a, median b, last result of b, runs)``: the runs
    ``run_a() -> (seconds, result)`` and ``run_b()`` taken in turn, ``repeat`` times
    each, b first every other round (a slow first run in a round, the machine's
    drift, fall on both sides alike)."""
    ta, tb, out_a, out_b = [], [], None, None
    for r in range(max(1, int(repeat))):
        for side in ((0, 1) if r % 2 else (1, 0)):
            if side == 0:
                t, out_a = run_a()
                ta.append(t)
            else:
                t, out_b = run_b()
                tb.append(t)
    return float(np.median(ta)), out_a, float(np.median(tb)), out_b, len(ta)


def _mesh_error(projector, parts, rng, n=4000):
    """Largest distance to the exact model of the centroids and edge midpoints of up
    to ``n`` triangles drawn from ``parts`` [(V, F), ...]."""
    V = np.concatenate([v for v, _ in parts])
    off = np.cumsum([0] + [len(v) for v, _ in parts[:-1]])
    F = np.concatenate([f + o for (_, f), o in zip(parts, off)])
    F = F[rng.choice(len(F), min(n, len(F)), replace=False)]
    A, B, C = V[F[:, 0]], V[F[:, 1]], V[F[:, 2]]
    P = np.concatenate([(A + B + C) / 3, (A + B) / 2, (B + C) / 2, (C + A) / 2])
    return float(projector.project(P).distance.max())


def _occ_section(shape, normal, offset, deflection, gap):
    """(seconds, wires, closed wires) of BRepAlgoAPI_Section, edges discretised."""
    from OCP.BRep import BRep_Tool
    from OCP.BRepAdaptor import BRepAdaptor_Curve
    from OCP.BRepAlgoAPI import BRepAlgoAPI_Section
    from OCP.collections import HSequence_TopoDS_Shape
    from OCP.GCPnts import GCPnts_QuasiUniformDeflection
    from OCP.gp import gp_Dir, gp_Pln, gp_Pnt
    from OCP.ShapeAnalysis import ShapeAnalysis_FreeBounds
    from OCP.TopAbs import TopAbs_EDGE
    from OCP.TopExp import TopExp_Explorer

    from geomkit.cad.occ import cast_shape

    t0 = time.perf_counter()
    n = np.asarray(normal, float)
    sec = BRepAlgoAPI_Section(shape, gp_Pln(gp_Pnt(*(n * offset)), gp_Dir(*n)))
    sec.Build()
    edges = HSequence_TopoDS_Shape()
    ex = TopExp_Explorer(sec.Shape(), TopAbs_EDGE)
    while ex.More():
        e = cast_shape("Edge", ex.Current())
        GCPnts_QuasiUniformDeflection(BRepAdaptor_Curve(e), deflection)
        edges.Append(e)
        ex.Next()
    dt = time.perf_counter() - t0
    wires = HSequence_TopoDS_Shape()
    ShapeAnalysis_FreeBounds.ConnectEdgesToWires_s(edges, max(gap, 1e-7), False, wires)
    closed = sum(BRep_Tool.IsClosed_s(cast_shape("Wire", wires.Value(i)))
                 for i in range(1, wires.Length() + 1))
    return dt, wires.Length(), closed


def _occ_distances(shape, P):
    from OCP.BRepBuilderAPI import BRepBuilderAPI_MakeVertex
    from OCP.BRepExtrema import BRepExtrema_DistShapeShape

    from geomkit.cad.occ import face_compound, gp_pnt

    faces = face_compound(shape)
    return np.array([BRepExtrema_DistShapeShape(BRepBuilderAPI_MakeVertex(gp_pnt(p)).Vertex(),
                                                faces).Value() for p in P])


def exercise(parts=None, parts_dir=None) -> int:
    """geomkit's side of :func:`sweep` once per part, untimed and without Open CASCADE:
    read (geomkit's own STEP reader), mesh at 1e-3 of the size, section through the
    middle normal to each axis, project points near the mesh.  The ahead-of-time build
    records the kernel calls of this run beside the demo's (``aot_build.py record``), so
    that a real part's first read, mesh, section and projection on a fresh install run
    compiled code.  ``parts``: file names in ``parts_dir`` (default: every STEP file of
    the repository's parts folder); returns the number of parts run."""
    import geomkit
    from geomkit.cad.step import read_step
    from geomkit.query.projection_part import make_projector

    folder = Path(parts_dir) if parts_dir is not None else PARTS_DIR
    if not folder.is_dir():
        return 0
    names = sorted(p.name for p in folder.iterdir() if p.suffix.lower() in (".stp", ".step")) \
        if parts is None else parts
    rng = np.random.default_rng(0)
    for name in names:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            res = read_step(folder / name, cache=False)
        S = res.surfaces
        B = np.array([s.bounds for s in S])
        lo, hi = B[:, 0].min(axis=0), B[:, 1].max(axis=0)
        size = float(np.linalg.norm(hi - lo))
        mesh = geomkit.tessellate(S, 1e-3 * size)
        for ax in range(3):
            n = np.zeros(3)
            n[ax] = 1.0
            geomkit.plane_section(S, [*n, -0.5 * (lo[ax] + hi[ax])], 1e-4 * size,
                                  gap=res.edge_gap or 0.0)
        V = mesh.vertices[rng.choice(len(mesh.vertices), 200)]
        make_projector(S).project(V + rng.normal(size=V.shape) * 0.01 * size)
    return len(names)


def sweep(parts=QUICK, parts_dir=None, repeat=3):
    """Rows of the common schema (:mod:`geomkit.bench._common`), four stages per part
    (see the module docstring); no rows without Open CASCADE (STEP is read through it)
    or without the parts folder."""
    import geomkit
    from geomkit.bench._common import make_row, median_time, occ_or_none
    from geomkit.cad.step import read_step
    from geomkit.query.projection import Projector
    from geomkit.query.projection_part import make_projector

    folder = Path(parts_dir) if parts_dir is not None else PARTS_DIR
    if occ_or_none() is None or not folder.is_dir():
        return []
    rows = []
    rng = np.random.default_rng(0)
    for name in parts:
        path = folder / name
        if not path.exists():
            continue
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            read_step(path, cache=False)                      # warm-up (OCC, JIT)
            tg, res, to, shape, k = alternate(_timed(lambda: read_step(path, cache=False)),
                                              _timed(lambda: _occ_read(path)), repeat)
            read_step(path)                                   # into the read cache
            tc, _, kc = median_time(lambda: read_step(path), repeat)
        S = res.surfaces
        gap = res.edge_gap or 0.0
        B = np.array([s.bounds for s in S])
        lo, hi = B[:, 0].min(axis=0), B[:, 1].max(axis=0)
        size = float(np.linalg.norm(hi - lo))
        rows.append(make_row("parts", name, "read faces", len(S), tg, None,
                             "OCC STEPControl_Reader", to, None, repeats=k,
                             note="OCC: read + transfer; geomkit: its own reader, every "
                                  "face converted"))
        rows.append(make_row("parts", name, "read again faces", len(S), tc, None,
                             "OCC STEPControl_Reader", to, None, repeats=kc,
                             note="geomkit: the same file again, from the read cache "
                                  "(this process's copy: unpickled)"))
        # tessellate at the same linear deflection
        tol = 1e-3 * size
        tm, mesh, tmo, _, k = alternate(_timed(lambda: geomkit.tessellate(S, tol)),
                                        lambda: _occ_mesh_run(path, tol), repeat)
        occ_parts, occ_ntri = _occ_mesh_points(_occ_read(path), tol)
        pj = Projector(S)
        eg = _mesh_error(pj, [(mesh.vertices, mesh.faces)], rng)
        eo = _mesh_error(pj, occ_parts, rng)
        rows.append(make_row("parts", name, "tessellate tol", tol, tm, eg,
                             "OCC BRepMesh_IncrementalMesh", tmo, eo, repeats=k,
                             note=f"{len(mesh.faces)} triangles vs OCC {occ_ntri}"))
        # sections through the middle, normal to each axis
        for ax in range(3):
            n = np.zeros(3)
            n[ax] = 1.0
            x = 0.5 * (lo[ax] + hi[ax])
            stol = 1e-4 * size
            ts, sec, k = median_time(
                lambda: geomkit.plane_section(S, [*n, -x], stol, gap=gap), repeat)
            tso, wires, closed = _occ_section(shape, n, x, stol, gap)
            rows.append(make_row("parts", name, f"section {'xyz'[ax]}", stol, ts, None,
                                 "OCC BRepAlgoAPI_Section", tso, None, repeats=k,
                                 note=f"{len(sec.curves)} curves ({sum(sec.closed)} closed)"
                                      f" vs OCC {wires} ({closed})"))
        # projection of points near the surface: the projector's build, a probe's
        # first query near one spot (building only what it reaches), then many points
        tb, proj, k = median_time(lambda: make_projector(S), repeat)
        V = mesh.vertices[rng.choice(len(mesh.vertices), 2000)]
        P = V + rng.normal(size=V.shape) * 0.01 * size / np.sqrt(3)
        t0 = time.perf_counter()
        first = proj.project(P[:20] - P[0] + V[0])
        tl = time.perf_counter() - t0
        rows.append(make_row("parts", name, "projector build faces", len(S), tb, None,
                             repeats=k, note=f"{type(proj).__name__}; first query of 20 "
                             f"points near one spot {tl:.2f} s (built "
                             f"{first.stats.get('blocks_built', 1)} of "
                             f"{first.stats.get('blocks', 1)} blocks)"))
        proj.project(P)  # every block the points reach is built
        tp, pr, k = median_time(lambda: proj.project(P), repeat)
        t0 = time.perf_counter()
        d_occ = _occ_distances(shape, P[:40])   # to the faces (a solid's inside is 0)
        tpo = (time.perf_counter() - t0) / 40
        err = float(np.abs(pr.distance[:40] - d_occ).max())
        rows.append(make_row("parts", name, "project points", 2000, tp / 2000, err,
                             "OCC BRepExtrema_DistShapeShape", tpo, None, per="point",
                             repeats=k, note=f"built projector; error against OCC on 40, "
                                             f"edge gap {res.edge_gap or 0.0:.2g}"))
    return rows


def main(argv=None):
    from geomkit.bench.suite import format_table

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--full", action="store_true", help="every part in the folder")
    ap.add_argument("--parts-dir", default=None)
    a = ap.parse_args(argv)
    folder = Path(a.parts_dir) if a.parts_dir else PARTS_DIR
    names = sorted(p.name for p in folder.glob("*.st*p")) if a.full else QUICK
    print(format_table(sweep(names, folder, repeat=7 if a.full else 3)))


if __name__ == "__main__":
    main()
