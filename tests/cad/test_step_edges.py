"""Line and circle edges built file-wide (:mod:`geomkit.cad.stepedges`) are the
edge-by-edge route's curves on every part, to the last bit where numpy's 3-element
dot is OpenBLAS's fused one (as the file-wide kernels compute it; another BLAS may
round it differently: then within an ulp of the coordinates); an edge they cannot
take is left to that route, which reads it or names the fault."""

from __future__ import annotations

import numpy as np
import pytest

from geomkit.cad import stepbrep
from geomkit.cad.loops import Unsupported
from geomkit.cad.p21 import P21, read_p21
from geomkit.cad.stepedges import line_and_circle_edges
from geomkit.cad.stepgeom import StepGeometry
from geomkit.errors import FileFormatError
from helpers.paths import DATA

PARTS = sorted((DATA / "parts").glob("*.st*p"))


def _one_by_one(p, ids):
    """The edge-by-edge route's curves (the file-wide ones taken out)."""
    F = stepbrep._Faces(p, StepGeometry(p))
    F._edges = {}
    return {i: F.edge(i) for i in ids}


def _same(a, b):
    """The same curve within a few ulps of its size (the edge-by-edge route's frames
    take numpy's dots, OpenBLAS's, whose rounding depends on the CPU's kernel: on a
    Zen 5 machine an arc's points came out 3 ulps away)."""
    return a[0] == b[0] and all(
        x.dtype == y.dtype and x.shape == y.shape
        and np.allclose(x, y, rtol=0, atol=2e-15 * max(1.0, float(np.abs(y).max())))
        for x, y in zip(a[1:], b[1:]))


@pytest.mark.parametrize("path", PARTS, ids=[p.name[:24] for p in PARTS])
def test_file_wide_edges_are_the_edge_by_edge_curves(path):
    p = read_p21(path)
    bulk = line_and_circle_edges(p)
    ref = _one_by_one(read_p21(path), bulk)
    for i, c in bulk.items():
        assert _same(c, ref[i]), i
    names = [p.names[int(p.get(i)[1][3])] for i in p.of_type("EDGE_CURVE")]
    # every plain line and circle edge of the NIST, NX, SolidWorks, Pro/E parts
    if path.name.startswith(("nist", "nx9", "sw20", "proe", "ug16")):
        assert len(bulk) == sum(n in ("LINE", "CIRCLE") for n in names) > 0


HEAD = """ISO-10303-21;
HEADER;
FILE_DESCRIPTION((''),'2;1');
FILE_NAME('t','',(''),(''),'','','');
FILE_SCHEMA(('AUTOMOTIVE_DESIGN'));
ENDSEC;
DATA;
"""

RECORDS = """#1=CARTESIAN_POINT('',(0.,0.,0.));
#2=CARTESIAN_POINT('',(10.,0.,0.));
#3=VERTEX_POINT('',#1);
#4=VERTEX_POINT('',#2);
#5=DIRECTION('',(1.,0.,0.));
#6=VECTOR('',#5,{mag});
#7=CARTESIAN_POINT('',(-1.,0.,0.));
#8=LINE('',#7,#6);
#9=EDGE_CURVE('',#3,#4,#8,{same});
#10=CARTESIAN_POINT('',(5.,0.,0.));
#11=DIRECTION('',(0.,0.,1.));
#12=DIRECTION('',({xref}));
#13=AXIS2_PLACEMENT_3D('',#10,#11,#12);
#14=CIRCLE('',#13,{radius});
#15=EDGE_CURVE('',#4,#3,#14,.T.);
"""


def _file(**kw):
    args = dict(mag="2.", same=".T.", xref="1.,0.,0.", radius="5.")
    args.update(kw)
    return P21(HEAD + RECORDS.format(**args) + "ENDSEC;\nEND-ISO-10303-21;\n", "t.stp")


@pytest.mark.parametrize("kw, taken", [
    ({}, {9, 15}),
    ({"same": ".F."}, {15}),                # the line's vertices then run backwards
    ({"mag": "0."}, {15}),                  # a zero vector: no parameter
    ({"mag": "LENGTH_MEASURE(2.)"}, {15}),  # a typed magnitude: not plain
    ({"xref": "0.,0.,1."}, {9}),            # X along Z: the default X is taken
    ({"xref": "1.,0."}, {9}),               # a 2-D direction
    ({"radius": "-5."}, {9}),               # a negative radius
])
def test_edges_left_to_the_edge_by_edge_route(kw, taken):
    p = _file(**kw)
    bulk = line_and_circle_edges(p)
    assert set(bulk) == taken
    F = stepbrep._Faces(_file(**kw), StepGeometry(_file(**kw)))
    F._edges = {}
    for i in (9, 15):
        try:
            c = F.edge(i)
        except (Unsupported, FileFormatError) as exc:
            assert i not in bulk
            if kw.get("mag") == "0.":
                assert "zero magnitude" in str(exc)
            continue
        if i in bulk:
            assert _same(bulk[i], c)


def test_a_full_circle_and_a_line_read_alike():
    p = _file()
    bulk = line_and_circle_edges(p)
    line, circle = bulk[9], bulk[15]
    np.testing.assert_array_equal(line[1], [0.5, 0.5, 5.5, 5.5])  # t = (X - O).D / D.D
    assert circle[1][0] == 0.0 and circle[1][-1] == pytest.approx(np.pi)


def test_fields_read_by_regex_as_the_parser_reads_them(monkeypatch):
    """Every record of the kinds read at once (edges, vertices, lines, vectors,
    placements, circles, oriented edges), on all parts: the regex's fields are the
    parser's."""
    from geomkit.cad import stepedges

    kinds = set(stepedges._FIELDS)
    seen = 0
    for path in PARTS:
        p = read_p21(path)
        ids = [i for i, n in p.names.items() if n in kinds]
        fast = {i: stepedges.fields(p, i, p.names[i]) for i in ids}
        with monkeypatch.context() as m:
            m.setattr(p, "body", lambda i: "")   # no regex match: the parser's route
            slow = {i: stepedges.fields(p, i, p.names[i]) for i in ids}
        assert fast == slow
        seen += sum(v is not None for v in fast.values())
    assert seen > 15_000


def test_fields_of_many_records_are_each_records_fields():
    """``fields_of`` (one regex pass over the joined records) against ``fields``
    record by record: every record of each kind on all parts, with records of other
    kinds, complex records and ids that are not records mixed in, and a hand-written
    file whose records are not all of the plain form."""
    from geomkit.cad import stepedges

    for path in PARTS[:6] + [None]:
        p = read_p21(path) if path is not None else _file(mag="LENGTH_MEASURE(2.)",
                                                           xref="1.,0.")
        other = list(p.names)[:40] + p.complex_ids()[:10] + [10 ** 9]
        for name in stepedges._FIELDS:
            ids = p.of_type(name) + other
            assert stepedges.fields_of(p, ids, name) == \
                [stepedges.fields(p, i, name) for i in ids]
    p = _file()
    p._raw[6] = "VECTOR('',#5,\x00 2.)"  # a separator inside a record: record by record
    assert stepedges.fields_of(p, [6, 9], "VECTOR") == [None, None]
    assert stepedges.fields_of(p, [9], "EDGE_CURVE") == [(3, 4, 8, True)]


def test_bspline_curves_read_at_once_are_the_parsers():
    """Every plain B_SPLINE_CURVE_WITH_KNOTS record of the parts, read by its regex,
    gives the curve the parser's fields give; a record not of the plain form (an
    escaped quote in its label, a knot of another form) is read by the parser."""
    from geomkit.cad.stepgeom import _BSPLINE_CURVE

    seen = 0
    for path in PARTS:
        p = read_p21(path)
        g = StepGeometry(p)
        for i in p.of_type("B_SPLINE_CURVE_WITH_KNOTS"):
            seen += _BSPLINE_CURVE.fullmatch(p.body(i)) is not None
            a = g._curve(i).spline
            b = g._bspline_curve(i, *g.rec(i, "B_SPLINE_CURVE_WITH_KNOTS"))
            assert a[0] == b[0] and np.array_equal(a[1], b[1]) and np.array_equal(a[2], b[2])
    assert seen > 400
    body = ("B_SPLINE_CURVE_WITH_KNOTS('{}',2,(#1,#2,#3),.UNSPECIFIED.,.F.,.F.,(3,3),"
            "({}),.UNSPECIFIED.)")
    assert _BSPLINE_CURVE.fullmatch(body.format("a", "0.,1.")) is not None
    assert _BSPLINE_CURVE.fullmatch(body.format("it''s", "0.,1.")) is None
    assert _BSPLINE_CURVE.fullmatch(body.format("a", "0.,PARAMETER_VALUE(1.)")) is None
