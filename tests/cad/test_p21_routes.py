"""The Part 21 parser's four routes read a record alike: the plain route (one regex:
a label and simple tokens), the flat route (no nested
list, at most a leading string: split at commas), the fast route (cut at strings and
punctuation) and the exact token-by-token route, which alone names a fault.  Checked
on every record of the real parts and on records mutated at random: a route that
accepts a record reads it as the exact route does, and accepts nothing the exact
route refuses."""

from __future__ import annotations

import random

import pytest

from geomkit.cad import p21
from geomkit.cad.p21 import read_p21
from geomkit.errors import FileFormatError
from helpers.paths import DATA

PARTS = sorted((DATA / "parts").glob("*.st*p"))


def _exact(body):
    """The record read by the token-by-token route alone (or its error)."""
    saved = p21._plain, p21._flat, p21._items_fast
    p21._plain = p21._flat = p21._items_fast = lambda s: None
    try:
        return p21._parse(body, "x")
    except FileFormatError as exc:
        return exc
    finally:
        p21._plain, p21._flat, p21._items_fast = saved


def _shape(v):
    """A parsed value with its types spelled out (Ref and int, Enum and str, True and
    1 compare equal)."""
    if isinstance(v, (list, tuple)):
        return type(v).__name__, [_shape(x) for x in v]
    if isinstance(v, dict):
        return {k: _shape(x) for k, x in v.items()}
    if isinstance(v, p21.Typed):
        return "Typed", v.name, _shape(v.value)
    return type(v).__name__, repr(v)


def _bodies():
    out = []
    for path in PARTS:
        out += list(read_p21(path)._raw.values())
    return out


def test_every_record_of_the_parts_reads_alike_by_every_route():
    bodies = _bodies()
    flat = plain = 0
    for b in bodies:
        got = p21._parse(b, "x")
        ref = _shape(_exact(b))
        assert _shape(got) == ref, b
        f = p21._flat(b)
        flat += f is not None
        assert f is None or _shape(f) == ref, b
        plain += p21._plain(b) is not None
    assert len(bodies) > 50_000 and flat > 20_000   # the flat route is taken
    assert plain > 20_000


@pytest.mark.parametrize("seed", range(4))
def test_mutated_records_read_alike_or_are_refused_alike(seed):
    """Characters inserted, deleted or replaced (quotes, parentheses, commas, dots,
    signs, letters, spaces) in flat records and others."""
    rng = random.Random(seed)
    bodies = rng.sample(_bodies(), 2500)
    alphabet = "'(),.#$*+-eE0123456789 AZ_/"
    for b in bodies:
        s = list(b)
        for _ in range(rng.randint(1, 3)):
            k = rng.randrange(len(s) + 1)
            op = rng.randrange(3)
            if op == 0:
                s.insert(k, rng.choice(alphabet))
            elif s and k < len(s):
                if op == 1:
                    del s[k]
                else:
                    s[k] = rng.choice(alphabet)
        m = "".join(s)
        ref = _exact(m)
        f, g = p21._flat(m), p21._plain(m)
        if isinstance(ref, FileFormatError):
            assert f is None and g is None, m
            with pytest.raises(FileFormatError):
                p21._parse(m, "x")
        else:
            for h in (f, g):
                if h is not None:
                    assert _shape(h) == _shape(ref), m
            assert _shape(p21._parse(m, "x")) == _shape(ref), m


@pytest.mark.parametrize("body", [
    "A('',#1,#2)", "A ( 'x' , #1 , .T. , $ , * , -1.E-3 , 7 )", "A(#1,2.,.F.)", "A()",
    "A('')", "A( )", "a_b-c('q',.u.,.Foo_1.,+.5,5.,1E5,-0)", "A('',#1,)", "A('',,#1)",
    "A(#1 #2)", "A('',#1x)", "A('it''s',#1)", "A('',#\u0661)", "A('',1.5\n,\t#2)",
    "A('',(#1,#2))", "A('','b')", "A('',.T)", "A('',1.e)", "A('' ,#1)", "A(#1,'x')",
    "A('a\x00b',#1)", "(A(#1)B(2))", "A('',.5,.5E2,.E.,.5.)",
    "A(.13634,#1)"])
def test_plain_route_reads_as_the_exact_route(body):
    ref = _exact(body)
    got = p21._plain(body)
    if isinstance(ref, FileFormatError):
        assert got is None
    elif got is not None:
        assert _shape(got) == _shape(ref)
    if body in ("A('',#1,#2)", "A(#1,2.,.F.)", "A()", "A( )", "A('')"):
        assert got is not None


def test_of_type_from_its_index_is_the_scan():
    """``of_type`` (an index of the names) gives the records a scan of the file gives,
    in file order, for one name and for several, on files whose ids increase through
    the file and on files whose ids do not."""
    orders = set()
    for path in PARTS:
        p = read_p21(path)
        names = sorted(set(p.names.values()))
        combos = [(n,) for n in names] + [tuple(names[k:k + 3]) for k in range(0, 30, 3)]
        combos += [("edge_curve", "vertex_point"), ("NO_SUCH_ENTITY",), ()]
        for combo in combos:
            want = {n.upper() for n in combo}
            got = p.of_type(*combo)
            assert got == [i for i, n in p.names.items() if n in want]
            got.append(-1)  # a copy: the index is not the caller's
            assert p.of_type(*combo) == got[:-1]
        orders.add(p._ordered)
    assert orders == {True, False}
