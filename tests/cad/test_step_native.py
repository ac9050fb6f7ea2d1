"""geomkit's own STEP reader (no Open CASCADE): the Part 21 parser, malformed files,
every single-part test file read whole, and the hard cases checked against closed
forms.  Face by face against Open CASCADE: ``tests/cad/test_real_parts.py`` (its
``read_step`` default is this reader)."""

from __future__ import annotations

import math

import numpy as np
import pytest

import geomkit
from geomkit.cad import step as step_mod
from geomkit.cad.p21 import DERIVED, P21, Enum, Ref, Typed
from geomkit.cad.step import read_step
from geomkit.cad.stepbrep import read_native
from geomkit.errors import FileFormatError, InvalidInputError
from helpers.paths import DATA

PARTS = DATA / "parts"
FACES = {"nist_ftc_06_ap242.stp": 187, "nist_ftc_07_ap242.stp": 306,
         "nist_ctc_01_ap203.stp": 139, "nist_ctc_05_ap203.stp": 209,
         "sw2013_featuretype_ap214.step": 96, "sw2018_base_interface_ap203.step": 30,
         "nx9_face_recognition_ap214.stp": 23, "ug16_io1_ap214.stp": 17,
         "euclid_screw_ap214.step": 10, "inventor2015_cylinder_block_face6.stp": 1,
         "catia_v5_ventilator_swept_faces.stp": 5, "proe_as1_ap203.stp": 160}
"""Open CASCADE's face count of each test file (the Pro/E file is an assembly)."""


def _file(data: str) -> str:
    return ("ISO-10303-21;\nHEADER;\nFILE_DESCRIPTION(('x'),'2;1');\n"
            "FILE_NAME('a','t',('me'),('org'),'pp','SYS X','');\n"
            "FILE_SCHEMA(('CONFIG_CONTROL_DESIGN'));\nENDSEC;\nDATA;\n" + data
            + "\nENDSEC;\nEND-ISO-10303-21;\n")


def test_parser_values():
    p = P21(_file("#1=CARTESIAN_POINT('a;b''c',(1.,-2.5E-1,3));\n"
                  "/* a comment; with a semicolon */\n"
                  "#2=(NAMED_UNIT(*)SI_UNIT(.MILLI.,.METRE.)LENGTH_UNIT());\n"
                  "#3=UNCERTAINTY_MEASURE_WITH_UNIT(LENGTH_MEASURE(1.E-05),#2,'d',$);\n"
                  "#4=FACE_BOUND('',#5,.T.);#5=X(.F.,.U.,());"))
    assert p.schema == "CONFIG_CONTROL_DESIGN" and p.system == "SYS X"
    name, a = p.get(1)
    assert name == "CARTESIAN_POINT" and a == ["a;b'c", [1.0, -0.25, 3]]
    assert isinstance(a[1][2], int)
    name, parts = p.get(2)
    assert name is None and parts["SI_UNIT"] == [Enum("MILLI"), Enum("METRE")]
    assert parts["NAMED_UNIT"] == [DERIVED]
    _, a = p.get(3)
    assert isinstance(a[0], Typed) and a[0].name == "LENGTH_MEASURE" and a[0].value == 1e-5
    assert isinstance(a[1], Ref) and a[1] == 2 and a[3] is None
    assert p.get(4)[1][2] is True and p.get(5)[1] == [False, None, []]
    assert p.of_type("face_bound") == [4] and p.complex_ids() == [2]


def test_coordinates_of_many_points_at_once():
    p = P21(_file("#1=CARTESIAN_POINT('',(1.,-2.5E-1,3));#2=CARTESIAN_POINT('p',( 4 , 5.5,6.));"
                  "#3=CARTESIAN_POINT('',(1.,2.));#4=CARTESIAN_POINT('',(1.D0,2.,3.));"
                  "#5=DIRECTION('',(0.,0.,1.));#6=CARTESIAN_POINT('',(1.,2.,3.,4.));"))
    np.testing.assert_array_equal(p.coordinates([2, 1, 2], "CARTESIAN_POINT", 3),
                                  [[4, 5.5, 6], [1, -0.25, 3], [4, 5.5, 6]])
    assert p.coordinates([], "CARTESIAN_POINT", 3).shape == (0, 3)
    # anything else is left to the record-by-record reading (which names the fault)
    for ids in ([1, 3], [4], [5], [1, 6], [1, 99]):
        assert p.coordinates(ids, "CARTESIAN_POINT", 3) is None, ids


@pytest.mark.parametrize("data, message", [
    ("#1=LINE('',#2,#3;", "inside a parameter list"),
    ("#1=LINE('',#2));", "unbalanced"),
    ("#1=LINE '',#2;", "not followed by"),
    ("#1 LINE('');", "has no '='"),
    ("#1=LINE('');#1=LINE('');", "defined twice"),
    ("#x=LINE('');", "bad record id"),
    ("LINE('');", "does not start with #id"),
    ("#1=LINE('abc);", "unmatched quote"),
    ("#1=LINE('',@);", "unexpected"),
    ("#1=(A(1) 2);", "complex entity"),
])
def test_parser_refuses_malformed_records(data, message):
    with pytest.raises(FileFormatError, match=message):
        p = P21(_file(data))
        for i in list(p.names):
            p.get(i)


def test_parser_refuses_truncated_and_foreign_files():
    with pytest.raises(FileFormatError, match="truncated"):
        P21(_file("#1=LINE('');")[:-30])
    with pytest.raises(FileFormatError, match="not a STEP file"):
        P21("solid x\nfacet normal 0 0 1\n")
    with pytest.raises(FileFormatError, match="#7 is referenced but not defined"):
        P21(_file("#1=LINE('',#7);")).get(7)


@pytest.mark.parametrize("name", sorted(FACES))
def test_reads_every_single_part_without_open_cascade(name, monkeypatch):
    monkeypatch.setattr(step_mod, "HAVE_OCP", False)
    res = read_step(PARTS / name)
    assert len(res.surfaces) == FACES[name] and not res.skipped
    assert res.units in ("mm", "in")
    assert res.edge_gap is None or 0 <= res.edge_gap < 1e-3 * max(s.size for s in
                                                                  res.surfaces)


def test_assembly_parts_are_placed():
    """The Pro/E "AS1" assembly places its parts (a bolt four times) by item-defined
    transformations: every occurrence is read once per placement, each a rigid copy
    of its part (face by face against OCC: tests/cad/test_real_parts.py)."""
    from geomkit.cad.p21 import read_p21
    from geomkit.cad.stepasm import instances
    from geomkit.cad.stepbrep import _holds_brep, _rep_items, file_units
    from geomkit.cad.stepgeom import StepGeometry

    path = PARTS / "proe_as1_ap203.stp"
    p = read_p21(path)
    inst = instances(p, StepGeometry(p, file_units(p)[1]), _rep_items(p),
                     lambda r: _holds_brep(p, r))
    reps = [r for r, _ in inst]
    assert len(inst) > len(set(reps))            # parts used more than once
    for _, M in inst:                             # rigid motions
        R = M[:3, :3]
        assert np.allclose(R @ R.T, np.eye(3), atol=1e-12) and np.isclose(
            np.linalg.det(R), 1.0)
    res = read_step(path, reader="geomkit")
    assert len(res.surfaces) == 160


def test_reader_choice():
    with pytest.raises(InvalidInputError, match="reader"):
        read_step(PARTS / "ug16_io1_ap214.stp", reader="parasolid")
    res = read_step(PARTS / "ug16_io1_ap214.stp", reader="geomkit")
    assert len(res.surfaces) == 17


def _area(s):
    m = geomkit.tessellate(s, 1e-4 * s.size)
    T = m.vertices[m.faces]
    return 0.5 * float(np.linalg.norm(np.cross(T[:, 1] - T[:, 0], T[:, 2] - T[:, 0]),
                                      axis=1).sum())


def _faces(path):
    from geomkit.cad.p21 import read_p21
    from geomkit.cad.stepbrep import _shells

    p = read_p21(path)
    return p, [f for sh in _shells(p) for f in p.get(sh)[1][1]]


def test_band_between_two_circles():
    """Unigraphics writes a cylinder band as two circle loops and no seam edge:
    joined across the seam, the face is the whole band (area 2 pi R h)."""
    path = PARTS / "ug16_io1_ap214.stp"
    res = read_native(path)
    p, faces = _faces(path)
    checked = 0
    for k, f in enumerate(faces):
        _, a = p.get(f)
        name, sa = p.get(a[2])
        loops = [p.get(p.get(b)[1][1]) for b in a[1]]
        if name != "CYLINDRICAL_SURFACE" or len(loops) != 2 or any(
                len(lp[1][1]) != 1 for lp in loops):
            continue
        R = sa[2]
        s = res.surfaces[k]
        m = geomkit.tessellate(s, 1e-4 * s.size)
        h = float(np.ptp(m.vertices @ _axis(p, sa[1]), axis=0))
        assert _area(s) == pytest.approx(2 * math.pi * R * h, rel=2e-3), s.name
        checked += 1
    assert checked >= 3


def _axis(p, ax):
    _, a = p.get(ax)
    d = np.array(p.get(a[2])[1][1], float)
    return d / np.linalg.norm(d)


def test_cone_closed_at_its_apex():
    """NIST CTC-01 faces 73 and 75: a cone bounded by one circle and a vertex loop at
    the apex: the face runs to the apex (area pi r l)."""
    path = PARTS / "nist_ctc_01_ap203.stp"
    res = read_native(path)
    p, faces = _faces(path)
    for k in (73, 75):
        _, a = p.get(faces[k])
        name, sa = p.get(a[2])
        assert name == "CONICAL_SURFACE"
        s = res.surfaces[k]
        m = geomkit.tessellate(s, 1e-4 * s.size)
        O = np.array(p.get(p.get(sa[1])[1][1])[1][1], float)
        A = _axis(p, sa[1])
        alpha = math.radians(sa[3]) if sa[3] > 1.6 else sa[3]
        d = m.vertices - O
        h = d @ A
        r = np.linalg.norm(d - np.outer(h, A), axis=1)
        rmax = float(r.max())
        slant = rmax / math.sin(alpha)
        assert float(r.min()) < 1e-6 * s.size          # it reaches the apex
        assert _area(s) == pytest.approx(math.pi * rmax * slant, rel=2e-3)


def test_spindle_torus_faces_lie_on_their_torus():
    """EUCLID's screw: tori whose minor radius exceeds the major one; points of the
    inner part pass the axis, so they are inverted at the angle + pi."""
    path = PARTS / "euclid_screw_ap214.step"
    res = read_native(path)
    p, faces = _faces(path)
    n = 0
    for k, f in enumerate(faces):
        name, sa = p.get(p.get(f)[1][2])
        if name != "TOROIDAL_SURFACE" or sa[3] <= sa[2]:
            continue
        R, r = sa[2], sa[3]
        O = np.array(p.get(p.get(sa[1])[1][1])[1][1], float)
        A = _axis(p, sa[1])
        X = geomkit.tessellate(res.surfaces[k], 1e-3 * r).vertices - O
        h = X @ A
        rho = np.linalg.norm(X - np.outer(h, A), axis=1)
        res_ = np.minimum(np.abs(np.hypot(rho - R, h) - r), np.abs(np.hypot(rho + R, h) - r))
        assert res_.max() < 1e-9 * r
        n += 1
    assert n == 3


def test_a_malformed_record_is_an_error_never_handed_on(tmp_path):
    """A face whose records lack parameters is a malformed file: a FileFormatError
    naming the face, not a fall-back to Open CASCADE."""
    text = (PARTS / "nx9_face_recognition_ap214.stp").read_text(encoding="latin-1")
    bad = tmp_path / "bad.stp"
    bad.write_text(text.replace("#278=VERTEX_POINT('',#839);", "#278=VERTEX_POINT('');"),
                   encoding="latin-1")
    with pytest.raises(FileFormatError, match="face .*missing or mistyped"):
        read_step(bad)
    res = read_step(bad, skip_unsupported=True)     # the other faces, named what is left
    assert len(res.surfaces) + len(res.skipped) == 23 and res.skipped


@pytest.mark.occ
@pytest.mark.skipif(not step_mod.HAVE_OCP, reason="needs cadquery-ocp")
def test_a_file_that_crashes_open_cascade_is_an_error():
    """geomkit's reader cannot convert three faces of this file (a misspelt entity),
    so it goes to Open CASCADE, which crashes on it (segmentation fault): in a child
    process, so here it is one FileFormatError and this process goes on."""
    path = DATA / "malformed" / "nx9_misspelt_entities.stp"
    with pytest.raises(FileFormatError, match="Open CASCADE crashed"):
        read_step(path)
    res = read_step(path, skip_unsupported=True)    # geomkit's reader, without them
    assert len(res.surfaces) == 20 and len(res.skipped) == 3
    with pytest.raises(FileFormatError, match="Open CASCADE crashed"):
        read_step(path, reader="occ")               # OCC asked for: in a child too


@pytest.mark.occ
@pytest.mark.skipif(not step_mod.HAVE_OCP, reason="needs cadquery-ocp")
def test_a_file_open_cascade_reads_by_skipping_syntax_errors_says_so(tmp_path, capfd):
    """A missing ';' is an error naming the record for geomkit's reader; Open CASCADE
    (asked for) reads on by skipping the broken records: a FileRecoveredWarning says
    so, and OCC's message stays off stdout (it is logged on ``geomkit.occ``)."""
    text = (PARTS / "nx9_face_recognition_ap214.stp").read_text(encoding="latin-1")
    bad = tmp_path / "nosemi.stp"
    i = text.index(";\n#40=")
    bad.write_text(text[:i] + "\n" + text[i + 2:], encoding="latin-1")
    with pytest.raises(FileFormatError, match="#39"):
        read_step(bad)
    capfd.readouterr()
    with pytest.warns(geomkit.errors.FileRecoveredWarning, match="skipping 1 record"):
        res = read_step(bad, reader="occ")
    assert len(res.surfaces) == 23
    out, _ = capfd.readouterr()
    assert "StepFile" not in out and "Incorrect Syntax" not in out


def _cone_sector(opening: float) -> str:
    """A STEP surface model of one face: the sector of opening ``opening`` of a cone
    (radius 10 at z = 0, half-angle 45 degrees, apex at z = -10) between the rim arc
    and two generator lines that meet at the apex."""
    c, s, h = math.cos(opening), math.sin(opening), math.sqrt(0.5)
    return _file(";\n".join([
        "#1=CARTESIAN_POINT('',(0.,0.,0.))", "#2=DIRECTION('',(0.,0.,1.))",
        "#3=DIRECTION('',(1.,0.,0.))", "#4=AXIS2_PLACEMENT_3D('',#1,#2,#3)",
        f"#5=CONICAL_SURFACE('',#4,10.,{math.pi / 4!r})", "#6=CIRCLE('',#4,10.)",
        "#10=CARTESIAN_POINT('',(10.,0.,0.))",
        f"#11=CARTESIAN_POINT('',({10 * c!r},{10 * s!r},0.))",
        "#12=CARTESIAN_POINT('',(0.,0.,-10.))", "#13=VERTEX_POINT('',#10)",
        "#14=VERTEX_POINT('',#11)", "#15=VERTEX_POINT('',#12)",
        f"#20=DIRECTION('',({-c * h!r},{-s * h!r},{-h!r}))", "#21=VECTOR('',#20,1.)",
        "#22=LINE('',#11,#21)", f"#23=DIRECTION('',({h!r},0.,{h!r}))",
        "#24=VECTOR('',#23,1.)", "#25=LINE('',#12,#24)",
        "#30=EDGE_CURVE('',#13,#14,#6,.T.)", "#31=EDGE_CURVE('',#14,#15,#22,.T.)",
        "#32=EDGE_CURVE('',#15,#13,#25,.T.)", "#40=ORIENTED_EDGE('',*,*,#30,.T.)",
        "#41=ORIENTED_EDGE('',*,*,#31,.T.)", "#42=ORIENTED_EDGE('',*,*,#32,.T.)",
        "#50=EDGE_LOOP('',(#40,#41,#42))", "#51=FACE_OUTER_BOUND('',#50,.T.)",
        "#52=ADVANCED_FACE('',(#51),#5,.T.)", "#53=OPEN_SHELL('',(#52))",
        "#54=SHELL_BASED_SURFACE_MODEL('',(#53))",
        "#55=SHAPE_REPRESENTATION('',(#54),$)"]) + ";")


@pytest.mark.parametrize("degrees", [60, 120, 180, 180.1, 240, 359])
def test_cone_sector_from_its_apex(degrees, tmp_path):
    """A cone sector bounded by two generators that meet at the apex: the angle jumps
    there by the opening, either way round (exactly pi for a half cone, where the
    sign of a zero decides). The patch spans the sector's opening, not the whole turn
    (NIST FTC-07 faces 110-121 are half cones), and the face is the sector (area
    opening / 2 * r * slant)."""
    opening = math.radians(degrees)
    path = tmp_path / "sector.stp"
    path.write_text(_cone_sector(opening))
    s = read_native(path).surfaces[0]
    (u0, u1), (v0, v1) = s.domain
    assert v1 - v0 == pytest.approx(opening, abs=1e-9)
    m = geomkit.tessellate(s, 1e-4 * s.size)
    z = m.vertices[:, 2]
    r = np.hypot(m.vertices[:, 0], m.vertices[:, 1])
    assert np.abs(r - (z + 10.0)).max() <= 1e-9 * s.size     # on the cone
    assert float(z.min()) == pytest.approx(-10.0, abs=1e-9)   # to the apex
    a = np.arctan2(m.vertices[:, 1], m.vertices[:, 0]) % (2 * math.pi)
    a[(r < 1e-9) | (a > 2 * math.pi - 1e-6)] = 0.0  # the apex; 2 pi is the seam's 0
    assert float(a.max()) == pytest.approx(opening, abs=1e-6)  # the sector, no more
    # the mesh's area (inscribed: a little less than the sector's)
    assert _area(s) == pytest.approx(opening / 2 * 10.0 * 10.0 * math.sqrt(2), rel=1e-3)


def _parsed_face(F, face):
    """The parser's route to a face, its bounds and their edge loops (the oracle of
    the plain-record regexes)."""
    _, a = F.g.rec(face, "ADVANCED_FACE", "FACE_SURFACE")
    bounds = []
    for b in a[1]:
        bname, ba = F.g.rec(b, "FACE_OUTER_BOUND", "FACE_BOUND")
        lname, la = F.g.rec(ba[1], "EDGE_LOOP", "VERTEX_LOOP", "POLY_LOOP")
        bounds.append((bname, lname, [int(x) for x in la[1]] if lname == "EDGE_LOOP"
                       else la[1], ba[2]))
    return [int(b) for b in a[1]], int(a[2]), a[3], bounds


def test_plain_face_records_read_as_the_parser_reads_them():
    """_Faces.face / _bound (a regex on the writers' plain forms) give the parser's
    fields on every face of the 13 parts, and on faces written otherwise (spaces,
    a quote in a label: the parser's route), a vertex loop, a missing record."""
    from geomkit.cad.p21 import read_p21
    from geomkit.cad.stepbrep import _Faces
    from geomkit.cad.stepgeom import StepGeometry

    def check(p):
        F = _Faces.__new__(_Faces)
        F.p, F.g, F._face_recs = p, StepGeometry(p), {}
        n = 0
        for face in p.of_type("ADVANCED_FACE"):
            bounds, surface, sense = F.face(face)
            got = [(*F._bound(b)[:2], [int(x) for x in F._bound(b)[2][1]]
                    if F._bound(b)[1] == "EDGE_LOOP" else F._bound(b)[2][1],
                    F._bound(b)[3]) for b in bounds]
            assert ([int(b) for b in bounds], int(surface), sense, got) == _parsed_face(F, face)
            n += 1
        return n

    assert sum(check(read_p21(f)) for f in sorted(PARTS.glob("*.st*p"))) > 1000
    odd = P21(_file(
        "#1=ADVANCED_FACE ( 'a''b' , ( #2 , #7 ) , #9 , .F. ) ;"
        "#2=FACE_OUTER_BOUND('',#3,.T.);#3=EDGE_LOOP('l',(#4,#5));"
        "#7= FACE_BOUND ( '' , #8 , .F. ) ;#8=VERTEX_LOOP('',#6);"
        "#10=ADVANCED_FACE('',(#11),#9,.T.);#11=FACE_BOUND('',#12,.T.);"))
    F = _Faces.__new__(_Faces)
    F.p, F.g, F._face_recs = odd, StepGeometry(odd), {}
    assert F.face(1)[1:] == (9, False) and [int(b) for b in F.face(1)[0]] == [2, 7]
    assert F._bound(2) == ("FACE_OUTER_BOUND", "EDGE_LOOP", [None, [4, 5]], True)
    assert F._bound(7)[:2] == ("FACE_BOUND", "VERTEX_LOOP") and F._bound(7)[3] is False
    with pytest.raises(FileFormatError, match="#12 is referenced but not defined"):
        F._bound(11)
