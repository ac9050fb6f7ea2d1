"""Real parts read whole with the default options, checked against Open CASCADE.

NIST FTC-06 (AP242, mm): face 115 is a spherical patch whose outer wire runs along the
pole (v = pi/2), where its pcurves leave the domain by 0.085 in u and do not meet in UV
(0.0848 apart) although they meet in 3-D: the pole is one point.  Such a loop is
repaired when the repair, measured in 3-D, is within the face's own tolerance (its
edges' and vertices' tolerances in the file, or the model resolution), and the repair
is stated on the face as ``approx_error``."""

from __future__ import annotations

import numpy as np
import pytest

import geomkit
from geomkit.cad.occ import HAVE_OCP
from helpers.paths import DATA

pytestmark = [pytest.mark.occ,
              pytest.mark.skipif(not HAVE_OCP, reason="reading STEP needs cadquery-ocp")]

FTC06 = DATA / "parts" / "nist_ftc_06_ap242.stp"


def _occ_faces(path):
    from OCP.BRep import BRep_Tool
    from OCP.STEPControl import STEPControl_Reader
    from OCP.TopAbs import TopAbs_EDGE, TopAbs_FACE, TopAbs_VERTEX
    from OCP.TopExp import TopExp_Explorer

    from geomkit.cad.occ import cast_shape
    from geomkit.cad.step import _file_units

    rd = STEPControl_Reader()
    rd.ReadFile(str(path))
    _, mm = _file_units(rd)
    if mm is not None:
        rd.SetSystemLengthUnit(mm)
    rd.TransferRoots()
    faces, tols = [], []
    ex = TopExp_Explorer(rd.OneShape(), TopAbs_FACE)
    while ex.More():
        f = cast_shape("Face", ex.Current())
        t = 0.0
        for kind, name in ((TopAbs_EDGE, "Edge"), (TopAbs_VERTEX, "Vertex")):
            tx = TopExp_Explorer(f, kind)
            while tx.More():
                t = max(t, BRep_Tool.Tolerance_s(cast_shape(name, tx.Current())))
                tx.Next()
        faces.append(f)
        tols.append(t)
        ex.Next()
    return faces, tols


@pytest.fixture(scope="module")
def ftc06():
    return geomkit.load_case(FTC06), _occ_faces(FTC06)


def test_read_whole_with_the_defaults(ftc06):
    case, (faces, _) = ftc06
    assert len(case.surfaces) == len(faces) == 187
    assert case.units == "mm"


def test_repairs_are_stated_and_within_the_face_tolerance(ftc06):
    case, (_, tols) = ftc06
    repaired = [s for s in case.surfaces if s.approx_error > 0]
    assert repaired, "the pole face needs a repair"
    assert "face115" in [s.name for s in repaired]
    from geomkit.cad.step import _resolution

    resolution = _resolution(FTC06) or 0.0
    for s in repaired:    # the reader's tolerance: the face's, or the model resolution
        assert s.approx_error <= max(tols[int(s.name[4:])], resolution) + 1e-12, s.name


def test_repaired_faces_match_open_cascade(ftc06):
    """Both ways: points of geomkit's mesh of each repaired face lie on OCC's face, and
    OCC's mesh nodes of it lie on geomkit's trimmed face, within the face's own
    tolerance plus the mesh deviation."""
    from OCP.BRep import BRep_Tool
    from OCP.BRepBuilderAPI import BRepBuilderAPI_MakeVertex
    from OCP.BRepExtrema import BRepExtrema_DistShapeShape
    from OCP.BRepMesh import BRepMesh_IncrementalMesh
    from OCP.gp import gp_Pnt
    from OCP.TopLoc import TopLoc_Location

    case, (faces, tols) = ftc06
    rng = np.random.default_rng(0)
    for s in [s for s in case.surfaces if s.approx_error > 0]:
        k = int(s.name[4:])
        tol = 1e-3 * s.size
        m = geomkit.tessellate(s, tol)
        P = m.vertices[rng.choice(len(m.vertices), min(40, len(m.vertices)), replace=False)]
        d1 = max(BRepExtrema_DistShapeShape(BRepBuilderAPI_MakeVertex(gp_Pnt(*p)).Vertex(),
                                            faces[k]).Value() for p in P)
        BRepMesh_IncrementalMesh(faces[k], tol)
        tri = BRep_Tool.Triangulation_s(faces[k], TopLoc_Location())
        Q = np.array([[tri.Node(i + 1).X(), tri.Node(i + 1).Y(), tri.Node(i + 1).Z()]
                      for i in range(tri.NbNodes())])
        d2 = float(np.max(geomkit.project_points(s, Q).distance))
        allow = tols[k] + m.max_deviation + 1e-9 * s.size
        assert d1 <= allow and d2 <= allow, (s.name, d1, d2, allow)
