"""510 faces over a B-spline surface whose 508 loops carry no pcurves (edges only in
model space): the 3-D edges are projected onto the surface (``geomkit.project_points``)
within the model's resolution / 1e-6 x size, instead of the face being skipped.

Open CASCADE writes a B-spline face with a round hole cut by a cylinder in B-rep mode
(510 over 128, 508 loops with pcurves); the test rewrites the file with every 508's
pcurve count set to 0.  The face read from the stripped file has OCC's area (the
exact shape OCC wrote), and classifies a 60 x 60 UV grid exactly as the face read
with the file's own pcurves.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("OCP", reason="Open CASCADE (OCP) writes the test file")

import geomkit  # noqa: E402
from geomkit.cad.iges.reader import read_iges  # noqa: E402

from helpers.igeswrite import write_iges  # noqa: E402


def _holed_face():
    from OCP.BRepAlgoAPI import BRepAlgoAPI_Cut
    from OCP.BRepBuilderAPI import BRepBuilderAPI_MakeFace
    from OCP.BRepPrimAPI import BRepPrimAPI_MakeCylinder
    from OCP.GeomAPI import GeomAPI_PointsToBSplineSurface
    from OCP.gp import gp_Ax2, gp_Dir, gp_Pnt

    from geomkit.cad.occ import ocp_array

    A = ocp_array("Array2_gp_Pnt")(1, 8, 1, 8)
    for i in range(8):
        for j in range(8):
            x, y = i * 10 / 7, j * 10 / 7
            A.SetValue(i + 1, j + 1, gp_Pnt(x, y, 0.8 * np.sin(x / 3) * np.cos(y / 4)))
    face = BRepBuilderAPI_MakeFace(GeomAPI_PointsToBSplineSurface(A).Surface(), 1e-7).Face()
    cyl = BRepPrimAPI_MakeCylinder(gp_Ax2(gp_Pnt(5, 4, -5), gp_Dir(0, 0, 1)), 2.0, 10).Shape()
    return BRepAlgoAPI_Cut(face, cyl).Shape()


def _strip_pcurves(src: Path, dst: Path) -> int:
    """Rewrite ``src`` with every 508 edge's pcurve count K set to 0; returns how many
    pcurves were dropped."""
    from geomkit.cad.iges.file import directory, param_records

    recs, _ = param_records(src)
    ents, dropped = [], 0
    for k, (de, e) in enumerate(sorted(directory(src).items())):
        assert de == 2 * k + 1
        r = recs[de]
        if e.d["entity_type_number"] == 508:
            n, a, out = int(r[1]), 2, [r[1]]
            for _ in range(n):
                typ, edge, ndx, of, kk = r[a: a + 5]
                a += 5 + 2 * int(kk)
                dropped += int(kk)
                out += [typ, edge, ndx, of, "0"]
            r = ["508"] + out
        ents.append((e.d["entity_type_number"], r[1:], e.d["form_number"],
                     e.d["transform"] or 0, f"{e.d['status_number']:08d}"))
    write_iges(dst, ents)
    return dropped


def test_510_without_pcurves_projects_its_edges(tmp_path):
    from OCP.BRepGProp import BRepGProp
    from OCP.GProp import GProp_GProps
    from OCP.IGESControl import IGESControl_Controller, IGESControl_Writer
    from OCP.Interface import Interface_Static

    shape = _holed_face()
    IGESControl_Controller.Init_s()
    Interface_Static.SetIVal_s("write.iges.brep.mode", 1)
    w = IGESControl_Writer("MM", 1)
    w.AddShape(shape)
    w.ComputeModel()
    src, dst = tmp_path / "holed.igs", tmp_path / "holed_nopc.igs"
    assert w.Write(str(src))
    assert _strip_pcurves(src, dst) >= 2
    ref, res = read_iges(src), read_iges(dst)
    (s0,), (s1,) = ref.surfaces, res.surfaces
    assert s1.name == "510@3" and len(s1.trim) == 2 and not res.skipped
    size = float(np.linalg.norm(np.ptp(s1.control_points.reshape(-1, 3), axis=0)))
    assert ref.edge_fit_error == 0 and 0 < res.edge_fit_error <= 1e-6 * size
    g = GProp_GProps()
    BRepGProp.SurfaceProperties_s(shape, g, 1e-10)
    a = geomkit.tessellate(res.surfaces, 1e-3).area
    assert abs(a - g.Mass()) <= 2e-5 * g.Mass()
    (u0, u1), (v0, v1) = s0.domain
    uv = np.stack(np.meshgrid(np.linspace(u0, u1, 60), np.linspace(v0, v1, 60)),
                  -1).reshape(-1, 2)
    c0, c1 = geomkit.classify_uv(s0, uv), geomkit.classify_uv(s1, uv)
    sure = (c0 != geomkit.ON_BOUNDARY) & (c1 != geomkit.ON_BOUNDARY)
    assert sure.sum() > 3000 and np.array_equal(c0[sure], c1[sure])
    assert 0 < (c1 == geomkit.OUTSIDE).sum() < (c1 == geomkit.INSIDE).sum()


def test_510_edge_off_the_surface_is_listed(tmp_path):
    """Edges that are not on the face's surface (the surface moved 0.5 off them) are
    refused with the reason, never trimmed to a wrong loop."""
    from OCP.IGESControl import IGESControl_Controller, IGESControl_Writer
    from OCP.Interface import Interface_Static

    IGESControl_Controller.Init_s()
    Interface_Static.SetIVal_s("write.iges.brep.mode", 1)
    w = IGESControl_Writer("MM", 1)
    w.AddShape(_holed_face())
    w.ComputeModel()
    src, dst = tmp_path / "holed.igs", tmp_path / "holed_off.igs"
    assert w.Write(str(src))
    _strip_pcurves(src, dst)
    from geomkit.cad.iges.file import directory, param_records

    recs, _ = param_records(dst)
    d = directory(dst)
    move = 2 * len(d) + 1  # a 124 appended: the surface moved 0.5 along z
    ents = []
    for de, e in sorted(d.items()):
        t = e.d["entity_type_number"]
        ents.append((t, recs[de][1:], e.d["form_number"],
                     move if t == 128 else (e.d["transform"] or 0),
                     f"{e.d['status_number']:08d}"))
    ents.append((124, [1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0.5]))
    write_iges(dst, ents)
    with pytest.raises(geomkit.errors.FileFormatError, match="is not on the surface"):
        read_iges(dst)
    with pytest.raises(geomkit.errors.FileFormatError, match="no readable surface.*"
                       "510@3: loop 508 at DE .* is not on the surface"):
        read_iges(dst, skip_unsupported=True)  # the only face: nothing left
