"""P21.numbers, P21.xyz and P21.coordinates (every point / direction record read at once from
its bytes: geomkit/cad/p21_numbers.py and the p21_scan kernel) against the
record-by-record reading (the oracle below: the regex and float of each record), and
the kernel's numbers against float."""

from __future__ import annotations

import glob
import os
import re

import numpy as np
import pytest

from geomkit.cad.p21 import P21, read_p21

PARTS = sorted(glob.glob(os.path.join(os.path.dirname(__file__), "..", "data", "parts",
                                      "*.st*p")))
_COORDS = re.compile(r"[A-Za-z_]+\s*\(\s*'[^']*'\s*,\s*\(([-+0-9.EeDd,\s]*)\)\s*\)\s*")


def _numbers(p, i, name):
    raw = p._raw.get(int(i))
    if raw is None or p.names.get(int(i)) != name:
        return None
    m = _COORDS.fullmatch(raw)
    if m is None:
        return None
    try:
        return tuple(float(x) for x in m.group(1).split(","))
    except ValueError:
        return None


def _coordinates(p, ids, name, k):
    groups = []
    for i in ids:
        body = p._raw.get(int(i))
        if body is None or p.names.get(int(i)) != name:
            return None
        m = _COORDS.fullmatch(body)
        if m is None or m.group(1).count(",") != k - 1:
            return None
        groups.append(m.group(1))
    if not groups:
        return np.empty((0, k))
    try:
        out = np.array([float(x) for x in ",".join(groups).split(",")])
    except ValueError:
        return None
    return out.reshape(-1, k)


def _same(a, b):
    if a is None or b is None:
        return a is None and b is None
    return a.shape == b.shape and a.dtype == b.dtype and a.flags.c_contiguous \
        and np.array_equal(a, b, equal_nan=True) and a.tobytes() == b.tobytes()


def _check(p):
    for name in ("CARTESIAN_POINT", "DIRECTION"):
        ids = p.of_type(name)
        other = list(p.names)[:30] + [10 ** 9]
        for i in ids + other:
            x = _numbers(p, i, name)
            assert p.numbers(i, name) == x, i
            want = np.array(x) if x is not None and len(x) == 3 and \
                np.isfinite(x).all() else None  # (P21.xyz: three finite numbers)
            got = p.xyz(i, name)
            assert _same(got, want), i
            if got is not None:  # (a new array each time)
                got[:] = 7.0
                assert _same(p.xyz(i, name), want), i
        for k in (1, 2, 3, 0):
            for chunk in (ids, ids[:7], ids[::5], ids + other[:1], [], ids[::-1],
                          [str(i) for i in ids[:3]], [np.int64(i) for i in ids[:3]]):
                assert _same(p.coordinates(chunk, name, k), _coordinates(p, chunk, name, k))
        bad = [other[0], [1, 2]] if other[0] not in ids else [[1, 2]]
        try:
            want = _coordinates(p, bad, name, 3)
        except TypeError as exc:
            with pytest.raises(TypeError, match=re.escape(str(exc))):
                p.coordinates(bad, name, 3)
        else:
            assert _same(p.coordinates(bad, name, 3), want)


@pytest.mark.parametrize("path", PARTS, ids=os.path.basename)
def test_parts(path):
    _check(read_p21(path))


def _file(data):
    return P21(f"ISO-10303-21;HEADER;ENDSEC;DATA;{data}ENDSEC;END-ISO-10303-21;", "t")


@pytest.mark.parametrize("data", [
    "#1=CARTESIAN_POINT('',(1.,2.,3.));#2=CARTESIAN_POINT('a',(1.E-05,-2,+3.5E+2));",
    "#1=CARTESIAN_POINT('',(1.,2.));#2=CARTESIAN_POINT('',(1.,2.,3.));",   # 2 and 3
    "#1=CARTESIAN_POINT('',(1.,2.));#2=CARTESIAN_POINT('',(-0.,4.));",     # all 2
    "#1=CARTESIAN_POINT('',(1.D0,2.,3.));#2=CARTESIAN_POINT('',(1.,2.,3.));",  # 'D'
    "#1=CARTESIAN_POINT('',(1.,,3.));#2=CARTESIAN_POINT('',());#3=CARTESIAN_POINT('',( ));",
    "#1=CARTESIAN_POINT('it''s',(1.,2.,3.));#2=CARTESIAN_POINT('',(1.,2.,3.)) ;",
    "#1=CARTESIAN_POINT('',(1.,2.,LENGTH_MEASURE(3.)));#2=DIRECTION('',(0.,0.,1.));",
    "#1=CARTESIAN_POINT('',(1E999,-1E999,0.));#2=CARTESIAN_POINT('',(1 , 2 ,3));",
    "#1=(CARTESIAN_POINT('',(1.,2.,3.)));#2=CARTESIAN_POINT('x\x00',(1.,2.,3.));",
    "#1=CARTESIAN_POINT('',(1.,2.,3.),#5);#2=CARTESIAN_POINT('',(4.,5.,6.));",
    "#1=cartesian_point('',(1.,2.,3.));#2=CARTESIAN_POINT('',(4.,5.,6.));",
    "#1=CARTESIAN_POINT('',(1.));#2=CARTESIAN_POINT('',(4.,5.,6.,7.));",
    "#1=CARTESIAN_POINT('',(-0.,0.,+0.));#2=CARTESIAN_POINT('',(1.E-30,1.E+300,5E22));",
    "#1=CARTESIAN_POINT('',(0.70710678118654757,-1.2345678901234567E-3,9007199254740993));",
    "#1=DIRECTION('',(1.,2.,3.));#2=DIRECTION('',(1.E,.E1,.));#3=DIRECTION('',(1 2,3,4));",
    "#1=DIRECTION('',(\xa01.\x85,2.\x1c,3.));#2=DIRECTION\xa0('',(1.,2.,3.)\xa0)\x85;",
    "#1=CARTESIAN_POINT('a,b',(1.,2.,3.));#2=CARTESIAN_POINT('',(4. 5.,6.));",
])
def test_records(data):
    _check(_file(data))


def test_kernel_numbers_are_floats():
    """Every number the kernel reads itself is float's, bit for bit (the numbers of the
    parts, random strings of number characters, random values written many ways)."""
    import random
    import struct

    from geomkit._kernels.p21_scan import _number

    texts = set()
    for path in PARTS:
        text = open(path, "rb").read().decode("latin-1")
        texts.update(re.findall(r"[-+]?(?:\d+\.?\d*|\.\d+)(?:[Ee][-+]?\d+)?", text))
    rnd = random.Random(3)
    for _ in range(20000):
        texts.add("".join(rnd.choice("0123456789.+-eE D\t") for _ in range(rnd.randint(0, 12))))
        x = rnd.uniform(-1e3, 1e3) * 10.0 ** rnd.randint(-25, 25)
        texts.update([repr(x), "%.15g" % x, "%.14E" % x, "%.17g" % x, "%.6f" % x])
    read = 0
    for s in texts:
        b = np.frombuffer(s.encode("latin-1"), np.uint8)
        st, v = _number(b, 0, b.size)
        if st == 0:
            read += 1
            assert struct.pack("<d", v) == struct.pack("<d", float(s)), s
    assert read > len(texts) // 3


@pytest.mark.parametrize("path", PARTS, ids=os.path.basename)
def test_table_from_the_file_bytes_is_the_table_from_the_bodies(path):
    """A CoordinateTable read where the records lie in the file's bytes (Bodies.spans,
    what P21 uses) holds what one read from the joined bodies holds, row for row."""
    from geomkit.cad.p21_numbers import CoordinateTable

    p = read_p21(path)
    for name in ("CARTESIAN_POINT", "DIRECTION", "VECTOR"):
        ids = p.of_type(name)
        spans = p._raw.spans(ids)
        assert spans is not None
        b, starts, ends = spans
        bodies = p._raw.many(ids)
        assert [b[a:e].tobytes().decode("latin-1") for a, e in zip(starts, ends)] == bodies

        def each(i):
            return _numbers(p, i, name)

        ref = CoordinateTable(ids, bodies, each)
        got = CoordinateTable(ids, None, each, spans)
        np.testing.assert_array_equal(np.signbit(got.values), np.signbit(ref.values))
        np.testing.assert_array_equal(got.values, ref.values)
        assert (got.count, got.status, got.finite3, got.row) == \
            (ref.count, ref.status, ref.finite3, ref.row)
