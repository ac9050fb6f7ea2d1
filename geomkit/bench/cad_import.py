"""Reading a real CAD model against Open CASCADE, same run.

The impeller that ships with pyiges (277 trimmed faces, 30 of them surfaces of
revolution): median wall time of :func:`geomkit.read_iges` (every face an exact NURBS
with its trims) against ``IGESControl_Reader`` (``ReadFile`` + ``TransferRoots``) followed
by the NURBS conversion of every face (``BRepBuilderAPI_NurbsConvert`` on faces whose
surface is not already a B-spline, ``GeomConvert.SurfaceToBSplineSurface`` on all), i.e.
the same end product.  Also the same for the impeller written to STEP by OCC
(:func:`geomkit.read_step` runs OCC's reader itself, so it cannot be faster than it).

Usage: ``python -m geomkit.bench.cad_import [--repeat 3]``
"""

from __future__ import annotations

import argparse
import contextlib
import io
import os
import tempfile
from pathlib import Path

from geomkit.bench._common import median_time, occ_or_none


def _impeller() -> Path:
    from pyiges import examples

    return Path(examples.impeller)


def _occ_nurbs_faces(shape):
    from OCP.BRep import BRep_Tool
    from OCP.BRepBuilderAPI import BRepBuilderAPI_NurbsConvert
    from OCP.GeomConvert import GeomConvert
    from OCP.TopAbs import TopAbs_FACE
    from OCP.TopExp import TopExp_Explorer

    from geomkit.cad.occ import cast_shape

    ex, n = TopExp_Explorer(shape, TopAbs_FACE), 0
    while ex.More():
        f = cast_shape("Face", ex.Current())
        if BRep_Tool.Surface_s(f).DynamicType().Name() != "Geom_BSplineSurface":
            f = cast_shape("Face", BRepBuilderAPI_NurbsConvert(f, True).Shape())
        GeomConvert.SurfaceToBSplineSurface_s(BRep_Tool.Surface_s(f))
        n += 1
        ex.Next()
    return n


def _occ_iges(path):
    from OCP.IGESControl import IGESControl_Reader

    rd = IGESControl_Reader()
    rd.ReadFile(str(path))
    rd.TransferRoots()
    return _occ_nurbs_faces(rd.OneShape())


def _occ_step(path):
    from OCP.STEPControl import STEPControl_Reader

    rd = STEPControl_Reader()
    rd.ReadFile(str(path))
    rd.TransferRoots()
    return _occ_nurbs_faces(rd.OneShape())


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=3)
    a = ap.parse_args(argv)
    from geomkit import read_iges, read_step

    path = _impeller()
    read_iges(path)  # warm-up (imports, numba cache)
    tg, res, n = median_time(lambda: read_iges(path), a.repeat)
    print(f"impeller.igs: geomkit read_iges {tg:.3f} s median of {n} "
          f"({len(res.surfaces)} faces, {len(res.skipped)} skipped)")
    if occ_or_none() is None:
        print("reference skipped: Open CASCADE (cadquery-ocp) not installed")
        return 0
    sink = io.StringIO()
    with contextlib.redirect_stdout(sink):
        to, nf, _ = median_time(lambda: _occ_iges(path), a.repeat)
    print(f"impeller.igs: OCC IGESControl_Reader + NURBS faces {to:.3f} s ({nf} faces); "
          f"geomkit / OCC = {tg / to:.2f}")
    from OCP.IGESControl import IGESControl_Reader
    from OCP.STEPControl import STEPControl_AsIs, STEPControl_Writer

    with tempfile.TemporaryDirectory() as d, contextlib.redirect_stdout(sink):
        rd = IGESControl_Reader()
        rd.ReadFile(str(path))
        rd.TransferRoots()
        w = STEPControl_Writer()
        w.Transfer(rd.OneShape(), STEPControl_AsIs)
        step = os.path.join(d, "impeller.step")
        w.Write(step)
        read_step(step)
        ts, rs, _ = median_time(lambda: read_step(step), a.repeat)
        tso, nfs, _ = median_time(lambda: _occ_step(step), a.repeat)
    print(f"impeller.step: geomkit read_step {ts:.3f} s ({len(rs.surfaces)} faces); OCC "
          f"STEPControl_Reader + NURBS faces {tso:.3f} s ({nfs} faces); geomkit / OCC = "
          f"{ts / tso:.2f}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
