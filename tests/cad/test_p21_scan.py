"""The one-pass cutting of a STEP file's records (geomkit/_kernels/p21_scan.py via
geomkit/cad/p21_cut.py) against the record-by-record route (p21_cut.sections and
cut_records, the oracle): the same header, bodies, names, name index and errors."""

from __future__ import annotations

import glob
import os

import numpy as np
import pytest

from geomkit.cad import p21_cut
from geomkit.cad.p21 import P21
from geomkit.errors import FileFormatError

PARTS = sorted(glob.glob(os.path.join(os.path.dirname(__file__), "..", "data", "parts",
                                      "*.st*p")))


def _oracle(text: str):
    """``(schema, system, raw, names)`` by the record-by-record route, or the error."""
    try:
        text = p21_cut.strip_comments(text)
        if not text.lstrip().upper().startswith("ISO-10303-21"):
            raise FileFormatError("t: not a STEP file (it does not begin with "
                                  "ISO-10303-21;)")
        head, data = p21_cut.sections(text, "t")
        schema, system = P21._header(None, head)
        raw, names = p21_cut.cut_records(data, "t")
    except FileFormatError as exc:
        return str(exc)
    return schema, system, list(raw.items()), list(names.items())


def _scanned(text: str):
    try:
        p = P21(text, "t")
    except FileFormatError as exc:
        return str(exc), None
    return (p.schema, p.system, list(p._raw.items()), list(p.names.items())), p


def _check(text: str):
    got, p = _scanned(text)
    assert got == _oracle(text)
    if p is not None:  # the name index as of_type builds it from the names
        idx: dict = {}
        for i, n in p.names.items():
            idx.setdefault(n, []).append(i)
        for n, ids in idx.items():
            assert p.of_type(n) == ids
        ids = list(p.names)
        if p._ordered is not None:
            assert p._ordered == all(a < b for a, b in zip(ids, ids[1:]))
        assert p.complex_ids() == [i for i, n in p.names.items() if n == ""]
        for part in ("B_SPLINE_SURFACE", "representation_relationship", "LENGTH_UNIT",
                     "SI_UNIT(", "X"):
            assert p.complex_ids(part) == [i for i, n in p.names.items() if n == ""
                                           and part.upper() in p._raw[i].upper()]
    return got


def _file(data: str, head: str = "HEADER;\nFILE_SCHEMA(('AP214'));\nENDSEC;\n") -> str:
    return f"ISO-10303-21;\n{head}DATA;\n{data}\nENDSEC;\nEND-ISO-10303-21;\n"


@pytest.mark.parametrize("path", PARTS, ids=os.path.basename)
def test_parts_same_as_record_by_record(path):
    text = open(path, "rb").read().decode("latin-1")
    got, p = _scanned(text)
    assert p._by_name is not None  # the scan's route, not the fallback
    assert got == _oracle(text)
    _check(text)


@pytest.mark.parametrize("data", [
    "#1=A('x;y',1);#2=B(#1);",                       # ';' in a string
    "#1=A('it''s;',1);\n#2 = B ( #1 ) ;",            # escaped quote, spaces
    "#1=A(1);#2=(B(1)C(2));#3=;#4=D;",               # complex, empty, no '('
    "#1=A(1);#2=B(2)",                               # the last without ';'
    "#10=lower_name(1);#2=MiXed(2);#3=LOWER_NAME(3);",  # names upper-cased
    "#1=A(1);;; ;#2=A(2);",                          # empty records
    "#5=A(1);#3=B(2);#4=A(3);",                      # ids not increasing
    "#1=A(1);#1=B(2);",                              # defined twice
    "#1=A('open);#2=B(1);",                          # ends inside a string
    "1=A(1);",                                       # no '#'
    "#1 A(1);",                                      # no '='
    "#x=A(1);",                                      # a bad id
    "# 7 =A(1);#0008=B(2);",                         # spaces and zeros in ids
    "#1=A(1);\x1c#2=B(2);",                          # Latin-1 whitespace strip takes
    "#1=\xa0A(1);#2=B\x85(2);",
    "#1=A(1);#2=B (\xe9)\t;#3=\xc9T\xc9(1);",         # Latin-1 letters
    "#1=A(1);/* a ; comment */#2=B(2);",
    "#1=A('/* not a comment ;*/');#2=B(2);",
    "#1=A(1);#2='x'(1);#3=A B(1);",
    "#12345678901234567890=A(1);",                   # an id past 18 digits
])
def test_records_same_as_record_by_record(data):
    _check(_file(data))


@pytest.mark.parametrize("text", [
    _file("#1=A(1);").replace("DATA;", "data;"),
    _file("#1=A(1);").replace("HEADER;", "Header;"),
    _file("#1=A('ENDSEC;');#2=B(1);"),
    _file("#1=A('endsec;');#2=B(1);"),
    _file("#1=A(1);#2=B(1);").replace("ENDSEC;\nEND-ISO", "EndSec;\nEND-ISO"),
    _file("#1=A(1);").replace("ENDSEC;\nEND-ISO", "END-ISO"),  # DATA does not end
    _file("#1=A(1);").replace("DATA;", ""),
    _file("#1=A('\xdf');#2=B(1);", "HEADER;\nFILE_NAME('\xdf');ENDSEC;\n"),
    "  iso-10303-21;" + _file("#1=A(1);")[14:],
    "ISO-10303-2;" + _file("#1=A(1);")[14:],
    _file("#1=A('\u0394');"),                        # not Latin-1: the oracle's route
])
def test_sections_same_as_record_by_record(text):
    _check(text)


def test_messages_name_the_fault():
    got, _ = _scanned(_file("#1=A(1);#1=B(2);"))
    assert got == "t: record #1 is defined twice"
    got, _ = _scanned(_file("#1=A('x);"))
    assert "ends inside a string" in got


@pytest.mark.parametrize("word", ["HEADER;", "DATA;", "ENDSEC;"])
def test_find_upper(word):
    rng = np.random.default_rng(5)
    pieces = ["x", ";", "c", "C", "a", "A;", "r;", word, word.lower(), word.title(), "'"]
    for _ in range(300):
        text = "".join(rng.choice(pieces, rng.integers(0, 25)))
        b = np.frombuffer(text.encode("latin-1"), np.uint8)
        for start in range(0, len(text) + 1, 4):
            assert p21_cut.find_upper(text, b, word, start) == text.upper().find(word, start)
            semis = np.flatnonzero(b == 59)  # (the places of every ';' given)
            assert p21_cut.find_upper(text, b, word, start, semis) == \
                text.upper().find(word, start)


def test_has_comment():
    rng = np.random.default_rng(6)
    for _ in range(2000):
        text = "".join(rng.choice(["/", "*", "x", "'", "/*", "*/"], rng.integers(0, 200),
                                  p=[0.4, 0.2, 0.25, 0.05, 0.05, 0.05]))
        assert p21_cut._has_comment(text) == ("/*" in text)
    for text in ("/" * 100 + "x/*", "/" * 100, "a/*", "/*", "/", "", "*/"):
        assert p21_cut._has_comment(text) == ("/*" in text)


def test_bodies_read_as_a_dict():
    """p21_cut.Bodies (bodies cut from the text when asked) against the dict of the
    same bodies: every reading method, and after a body is set."""
    text = "xx#5=A(1);#2=B('a;b');#9=C();"
    spans = [(5, 9), (13, 21), (25, 28)]
    ids = [5, 2, 9]
    ref = {i: text[a:e] for i, (a, e) in zip(ids, spans)}
    got = p21_cut.Bodies(text, ids, [a for a, _ in spans], [e for _, e in spans])
    for _ in range(2):
        assert list(got.items()) == list(ref.items())
        assert list(got) == list(ref) and list(got.keys()) == list(ref.keys())
        assert list(got.values()) == list(ref.values()) and len(got) == len(ref)
        for i in (5, 2, 9, 7):
            assert (i in got) == (i in ref) and got.get(i) == ref.get(i)
            assert got.get(i, "") == ref.get(i, "")
            if i in ref:
                assert got[i] == ref[i]
            else:
                with pytest.raises(KeyError):
                    got[i]
        assert got.many([9, 5, 9]) == [ref[9], ref[5], ref[9]]
        got[2] = ref[2] = "B('c')"  # (then a dict)
        got[7] = ref[7] = "D()"


def test_bodies_of_the_parts():
    for path in PARTS:
        p = P21(open(path, "rb").read().decode("latin-1"), path)
        assert isinstance(p._raw, p21_cut.Bodies)
        text = p21_cut.strip_comments(open(path, "rb").read().decode("latin-1"))
        head, data = p21_cut.sections(text, "t")
        raw, _ = p21_cut.cut_records(data, "t")
        assert list(p._raw.items()) == list(raw.items())
