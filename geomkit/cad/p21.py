"""STEP physical files (ISO 10303-21): the records of the DATA section, parsed when
first asked for.

A record is cut from the text at once (``#id = ...;``); its parameters are parsed only
when it is read (:meth:`P21.get`), so a file's presentation and PMI records cost only
their cutting when the B-rep is all that is wanted.  Parameter values:

* integers ``int``, reals ``float``, strings ``str`` (``''`` unescaped),
* references :class:`Ref` (an ``int``), enumerations :class:`Enum` (a ``str``;
  ``.T.`` / ``.F.`` are ``True`` / ``False``, ``.U.`` is ``None``),
* ``$`` (unset) ``None``, ``*`` (derived) :data:`DERIVED`,
* aggregates ``list``, typed values ``NAME(value)`` :class:`Typed`.

A simple record is ``(NAME, [params])``; a complex one (``#id = (A(...) B(...));``)
is ``(None, {NAME: [params], ...})``.  Anything else is a
:class:`~geomkit.errors.FileFormatError` naming the record.
"""

from __future__ import annotations

import math
import re
from pathlib import Path

import numpy as np

from geomkit.cad.p21_cut import Bodies, cut
from geomkit.cad.p21_numbers import BY_FLOAT, OTHER, CoordinateTable
from geomkit.errors import FileFormatError

__all__ = ["P21", "Ref", "Enum", "Typed", "DERIVED", "read_p21"]


class Ref(int):
    """A reference ``#n``."""

    def __repr__(self) -> str:
        return f"#{int(self)}"


class Enum(str):
    """An enumeration value ``.NAME.`` (without the dots)."""


class Typed:
    """A typed parameter ``NAME(value)``, e.g. ``LENGTH_MEASURE(1.E-05)``."""

    __slots__ = ("name", "value")

    def __init__(self, name, value):
        self.name, self.value = name, value

    def __repr__(self) -> str:
        return f"{self.name}({self.value!r})"


DERIVED = Enum("*")

_TOKEN = re.compile(r"\s*(?:'((?:[^']|'')*)'|#(\d+)|\.([A-Za-z_][A-Za-z_0-9]*)\."
                    r"|([-+]?(?:\d+\.\d*|\d*\.\d+|\d+)(?:[Ee][-+]?\d+)?)"
                    r"|([A-Za-z_][A-Za-z_0-9\-]*)|([()$*,]))")
_VALID = re.compile(r"(?:\s*+(?>'(?:[^']|'')*+'|#\d++|\.[A-Za-z_][A-Za-z_0-9]*+\."
                    r"|[-+]?(?:\d+\.\d*|\d*\.\d+|\d+)(?:[Ee][-+]?\d+)?"
                    r"|[A-Za-z_][A-Za-z_0-9\-]*+|[()$*,]))*+\s*+")
"""A record body made of tokens only (atomic groups: no backtracking)."""
_COORDS = re.compile(r"[A-Za-z_]+\s*\(\s*'[^']*'\s*,\s*\(([-+0-9.EeDd,\s]*)\)\s*\)\s*")
"""``NAME('label', (numbers))``: the common point and direction records."""
_ENUMS = {"T": True, "F": False, "U": None}


def _unexpected(s: str, where: str):
    """Raise at the first text of ``s`` that is not a token."""
    pos = 0
    while True:
        m = _TOKEN.match(s, pos)
        if m is None or m.end() == pos:
            raise FileFormatError(f"{where}: unexpected {s[pos:pos + 20]!r}")
        pos = m.end()


_SPLIT = re.compile(r"('(?:[^']|'')*'|[(),])")
"""Strings and the punctuation ``( ) ,`` of a record body, kept by ``re.split``."""
_NUMBER = re.compile(r"[-+]?(?:\d+\.\d*|\d*\.\d+|\d+)(?:[Ee][-+]?\d+)?")
_WORD = re.compile(r"[A-Za-z_][A-Za-z_0-9\-]*")
_ENUM = re.compile(r"\.[A-Za-z_][A-Za-z_0-9]*\.")
_PUNCT = {"(": 6, ")": 6, ",": 6}


def _tokens_fast(s: str):
    """``[(kind, text)]`` of a body whose tokens are separated by punctuation (all a
    writer produces), with the kinds of :data:`_TOKEN`'s groups; None for anything
    else (two tokens side by side, a character that is not a token), left to the
    exact tokenizer."""
    out = []
    for j, t in enumerate(_SPLIT.split(s)):
        if j % 2:
            if t[0] == "'":
                out.append((1, t[1:-1]))
            else:
                out.append((6, t))
            continue
        t = t.strip()
        if not t:
            continue
        c = t[0]
        if c == "#":
            if not (t[1:].isascii() and t[1:].isdigit()):
                return None
            out.append((2, t[1:]))
        elif c == "$" or c == "*":
            if len(t) != 1:
                return None
            out.append((6, t))
        elif _NUMBER.fullmatch(t) is not None:
            out.append((4, t))
        elif c == ".":
            if _ENUM.fullmatch(t) is None:
                return None
            out.append((3, t[1:-1]))
        elif _WORD.fullmatch(t) is not None:
            out.append((5, t))
        else:
            return None
    return out


def _items(s: str, where: str):
    """The top-level items of a record body, token by token (raises naming the
    fault)."""
    toks = _tokens_fast(s)
    if toks is None:
        if _VALID.fullmatch(s) is None:
            _unexpected(s, where)
        toks = [(m.lastindex, m.group(m.lastindex)) for m in _TOKEN.finditer(s)]
    stack: list = []   # (enclosing list, keyword that opened this one or None)
    cur: list = []
    pending = None     # a keyword waiting for its '('
    # kinds: 1 string, 2 reference, 3 enumeration, 4 number, 5 keyword, 6 punctuation
    for k, v in toks:
        if pending is not None and v != "(":
            raise FileFormatError(f"{where}: {pending} is not followed by '('")
        if k == 6:
            if v == "(":
                stack.append((cur, pending))
                cur, pending = [], None
            elif v == ")":
                if not stack:
                    raise FileFormatError(f"{where}: unbalanced ')'")
                done = cur
                cur, name = stack.pop()
                cur.append(done if name is None else Typed(name, done))
            elif v == "$":
                cur.append(None)
            elif v == "*":
                cur.append(DERIVED)
        elif k == 2:
            cur.append(Ref(v))
        elif k == 4:
            cur.append(float(v) if ("." in v or "e" in v or "E" in v) else int(v))
        elif k == 1:
            cur.append(v.replace("''", "'"))
        elif k == 3:
            e = v.upper()
            cur.append(_ENUMS[e] if e in _ENUMS else Enum(e))
        else:
            pending = v.upper()
    if stack or pending is not None:
        raise FileFormatError(f"{where}: the record ends inside a parameter list")
    return cur


_NOT = object()
"""What :func:`_atom` returns for a token that is not a simple value."""


def _atom(t: str):
    """The value of one stripped, non-empty token that is a simple value (a
    reference, ``$``, ``*``, a number, an enumeration), else :data:`_NOT`."""
    c = t[0]
    if c == "#":
        d = t[1:]
        return Ref(d) if d.isascii() and d.isdigit() else _NOT
    if c == "$" or c == "*":
        return _NOT if len(t) != 1 else None if c == "$" else DERIVED
    if _NUMBER.fullmatch(t) is not None:
        return float(t) if ("." in t or "e" in t or "E" in t) else int(t)
    if c == "." and _ENUM.fullmatch(t) is not None:
        e = t[1:-1].upper()
        return _ENUMS[e] if e in _ENUMS else Enum(e)
    return _NOT


def _items_fast(s: str):
    """``(top-level items, deepest nesting a typed parameter closed at)`` of a record
    body parsed in one pass over its pieces cut at strings and punctuation (what
    writers produce), or None for anything else (two tokens side by side, a character
    that is not a token, a malformed nesting): the token-by-token route then parses
    it or names the fault."""
    stack: list = []   # (enclosing list, keyword that opened this one or None)
    cur: list = []
    pending = None     # a keyword waiting for its '('
    deep = 0           # the deepest nesting a typed parameter was closed at
    for j, t in enumerate(_SPLIT.split(s)):
        if j % 2:  # a string or one of ( ) ,
            c = t[0]
            if pending is not None and c != "(":
                return None
            if c == "'":
                cur.append(t[1:-1].replace("''", "'"))
            elif c == "(":
                stack.append((cur, pending))
                cur, pending = [], None
            elif c == ")":
                if not stack:
                    return None
                done = cur
                cur, name = stack.pop()
                if name is None:
                    cur.append(done)
                else:
                    cur.append(Typed(name, done))
                    deep = max(deep, len(stack))
            continue
        t = t.strip()
        if not t:
            continue
        if pending is not None:
            return None
        c = t[0]  # (a letter or '_' starts no simple value: a keyword, or nothing)
        v = _NOT if c.isalpha() or c == "_" else _atom(t)
        if v is not _NOT:
            cur.append(v)
        elif _WORD.fullmatch(t) is not None:
            pending = t.upper()
        else:
            return None
    if stack or pending is not None:
        return None
    return cur, deep


def _flat_tokens(tokens, out: list, sub) -> bool:
    """Append the simple tokens ``tokens`` to ``out`` (``sub`` for the marker of a
    list read before); False at anything else."""
    for t in tokens:
        t = t.strip()
        if not t:
            return False
        v = _atom(t)
        if v is not _NOT:
            out.append(v)
        elif t == "\x00" and sub is not None:
            out.append(sub)
        else:
            return False
    return True


def _flat(s: str):
    """``(NAME, params)`` of a body with at most one nested list, of simple tokens,
    and at most a leading string (``EDGE_CURVE('',#13,#14,#6,.T.)``,
    ``EDGE_LOOP('',(#1,#2,#3))``: most of a part's records), read by splitting at
    its commas, or None for anything else (then :func:`_items_fast` reads it)."""
    k = s.find("(")
    if k <= 0 or s[-1] != ")" or "\x00" in s:
        return None
    inner = s[k + 1:-1]
    name = s[:k].strip()
    if _WORD.fullmatch(name) is None:
        return None
    sub = None
    i = inner.find("(")
    if i >= 0:  # one list of simple tokens, as a parameter of its own
        j = inner.find(")")
        if j < i or inner.find("(", i + 1) >= 0 or inner.find(")", j + 1) >= 0:
            return None
        head, body, tail = inner[:i], inner[i + 1:j], inner[j + 1:]
        h, t = head.rstrip(), tail.lstrip()
        if (h and h[-1] != ",") or (t and t[0] != ",") or "'" in body:
            return None
        sub = []
        if body.strip() and not _flat_tokens(body.split(","), sub, None):
            return None
        inner = head + "\x00" + tail
    elif ")" in inner:
        return None
    out: list = []
    if "'" in inner:  # one string, first: a label
        inner = inner.lstrip()
        if inner[0] != "'" or inner.count("'") != 2:
            return None
        j = inner.index("'", 1)
        out.append(inner[1:j])
        rest = inner[j + 1:].lstrip()
        if not rest:
            return name.upper(), out
        if rest[0] != ",":
            return None
        tokens = rest[1:].split(",")
    elif not inner.strip():
        return name.upper(), out
    else:
        tokens = inner.split(",")
    if not _flat_tokens(tokens, out, sub):
        return None
    return name.upper(), out


_TOK = (r"(?:#[0-9]+|[$*]|\.[A-Za-z_][A-Za-z_0-9]*\.|[-+]?(?:\d+\.\d*|\d*\.\d+|\d+)"
        r"(?:[Ee][-+]?\d+)?)")
_PLAIN = re.compile(r"([A-Za-z_][A-Za-z_0-9\-]*)\s*\(\s*(?:'([^']*)'((?:\s*,\s*" + _TOK
                    + r")*)|(" + _TOK + r"(?:\s*,\s*" + _TOK + r")*))?\s*\)")
"""``NAME('label', token, ...)`` or ``NAME(token, ...)`` of simple tokens (references,
``$``, ``*``, enumerations, numbers): what writers give most records."""


def _plain(s: str):
    """``(NAME, params)`` of a body of :data:`_PLAIN`'s form, else None (the values
    :func:`_atom` gives its tokens)."""
    m = _PLAIN.fullmatch(s)
    if m is None:
        return None
    if m[2] is not None:  # a label, then ',' before each token
        out = [m[2]]
        tokens = m[3].split(",")[1:]
    else:
        out = []
        tokens = m[4].split(",") if m[4] else ()
    for t in tokens:
        t = t.strip()
        c = t[0]
        if c == "#":
            out.append(Ref(t[1:]))
        elif c == "." and t[-1] == ".":  # (a number may begin with '.', not end so)
            e = t[1:-1].upper()
            out.append(_ENUMS[e] if e in _ENUMS else Enum(e))
        elif c == "$":
            out.append(None)
        elif c == "*":
            out.append(DERIVED)
        else:
            out.append(float(t) if ("." in t or "e" in t or "E" in t) else int(t))
    return m[1].upper(), out


def _parse(s: str, where: str):
    """The parameters of one record body ``NAME(...)`` or ``(A(...) B(...))``."""
    flat = _plain(s)
    if flat is not None:
        return flat
    return _parse_other(s, where)


def _parse_other(s: str, where: str):
    """:func:`_parse` of a body that is not of :data:`_PLAIN`'s form."""
    flat = _flat(s)
    if flat is not None:
        return flat
    fast = _items_fast(s)
    cur, deep = (_items(s, where), 2) if fast is None else fast
    if len(cur) != 1:
        raise FileFormatError(f"{where}: expected one entity, found {len(cur)} items")
    top = cur[0]
    if isinstance(top, Typed):
        if not deep:  # no typed parameter inside: nothing to unwrap
            return top.name, top.value
        return top.name, [_unwrap(x) for x in top.value]
    parts = {}
    for part in top:  # '(' A(...) B(...) ')': a complex entity
        if not isinstance(part, Typed):
            raise FileFormatError(f"{where}: a complex entity holds {part!r}, "
                                  "not NAME(...)")
        parts[part.name] = [_unwrap(x) for x in part.value]
    if not parts:
        raise FileFormatError(f"{where}: an empty complex entity")
    return None, parts


def _unwrap(x):
    """Typed parameters inside parameters hold their one value (``LENGTH_MEASURE(1.)``
    -> ``Typed("LENGTH_MEASURE", 1.0)``)."""
    if isinstance(x, Typed):
        v = x.value
        x.value = _unwrap(v[0]) if len(v) == 1 else [_unwrap(y) for y in v]
        return x
    if isinstance(x, list):
        return [_unwrap(y) for y in x]
    return x


class P21:
    """The DATA section's records of a STEP file (see the module).

    Attributes
    ----------
    schema : str, the ``FILE_SCHEMA`` (e.g. ``AUTOMOTIVE_DESIGN``, ``CONFIG_CONTROL_DESIGN``).
    system : str, the ``FILE_NAME``'s originating system.
    names : dict, record id -> its (first) entity name, upper case.
    """

    def __init__(self, text: str, source: str = "STEP file"):
        self.source = source
        head, self._raw, self.names, self._by_name, self._ordered = cut(text, source)
        self.schema, self.system = self._header(head)
        self._cache: dict[int, tuple] = {}
        self._tables: dict = {}  # entity name -> its CoordinateTable (numbers)

    def _header(self, head):
        schema = system = ""
        for rec in head.split(";"):
            r = rec.strip()
            if r.upper().startswith("FILE_SCHEMA"):
                m = re.search(r"'([^']*)'", r)
                schema = m.group(1) if m else ""
            elif r.upper().startswith("FILE_NAME"):
                q = re.findall(r"'((?:[^']|'')*)'", r)
                system = q[5] if len(q) > 5 else ""
        return schema, system

    def __len__(self) -> int:
        return len(self._raw)

    def __contains__(self, i) -> bool:
        return int(i) in self._raw

    def get(self, i):
        """Record ``i`` parsed: ``(NAME, params)`` or ``(None, {NAME: params})``."""
        i = int(i)
        out = self._cache.get(i)
        if out is None:
            raw = self._raw.get(i)
            if raw is None:
                raise FileFormatError(f"{self.source}: #{i} is referenced but not defined")
            out = _plain(raw)  # (most records: no message to prepare)
            if out is None:
                out = _parse_other(raw, f"{self.source} #{i}")
            self._cache[i] = out
        return out

    def body(self, i) -> str:
        """Record ``i``'s text after ``#i =`` (stripped, unparsed), or ``''``."""
        return self._raw.get(int(i), "")

    def numbers(self, i, name: str):
        """The coordinate tuple of a plain ``CARTESIAN_POINT`` / ``DIRECTION`` record
        ``i`` (``NAME('label', (x, y[, z]))``) read at once, or None (then
        :meth:`get` parses it).  Read with every record of that name at the first call
        (:class:`~geomkit.cad.p21_numbers.CoordinateTable`), or here
        (:meth:`_numbers_each`)."""
        i = int(i)
        t = self._table(name)
        r = t.row.get(i) if t is not None else None
        if r is None:
            return None if t is not None else self._numbers_each(i, name)
        got = t.numbers(r)
        if got == OTHER:
            return None
        if got == BY_FLOAT:
            return self._numbers_each(i, name)
        return got

    def xyz(self, i, name: str):
        """:meth:`numbers` of record ``i`` as a new (3,) float array when they are three
        finite numbers, else None."""
        t = self._table(name)
        if t is not None:
            r = t.row.get(int(i))
            if r is not None and t.finite3[r]:
                return t.values[r].copy()
        x = self.numbers(i, name)
        if x is None or len(x) != 3 or not all(map(math.isfinite, x)):
            return None
        return np.array(x)

    def _numbers_each(self, i: int, name: str):
        """:meth:`numbers` of one record: its regex and ``float``."""
        raw = self._raw.get(i)
        if raw is None or self.names.get(i) != name:
            return None
        m = _COORDS.fullmatch(raw)
        if m is None:
            return None
        try:
            return tuple(float(x) for x in m.group(1).split(","))
        except ValueError:
            return None

    def coordinates(self, ids, name: str, k: int):
        """The coordinates (n, k) of the plain records ``ids`` of entity ``name``, each
        ``NAME('label', (k numbers))`` (:meth:`numbers` for many records at once), or
        None when any is not of that form (then each is read on its own)."""
        try:
            keys = list(map(int, ids))
        except (TypeError, ValueError):  # (what the record-by-record route names)
            keys = None
        t = self._table(name) if keys and k >= 1 else None
        if t is None:
            return self._coordinates_each(ids, name, k)
        rows = list(map(t.row.get, keys))
        if None in rows:  # a record of another name, or none
            return None
        return t.coordinates(rows, k, lambda j: self._numbers_each(keys[j], name))

    def _table(self, name: str):
        """The :class:`~geomkit.cad.p21_numbers.CoordinateTable` of the records named
        ``name`` (None when their text is not Latin-1)."""
        try:
            return self._tables[name]
        except KeyError:
            pass
        ids = self.of_type(name)
        raw = self._raw
        spans = raw.spans(ids) if isinstance(raw, Bodies) else None
        try:
            t = CoordinateTable(ids, None if spans is not None else raw.many(ids)
                                if isinstance(raw, Bodies) else [raw[i] for i in ids],
                                lambda i: self._numbers_each(i, name), spans)
        except UnicodeEncodeError:
            t = None
        self._tables[name] = t
        return t

    def _coordinates_each(self, ids, name: str, k: int):
        """:meth:`coordinates` record by record."""
        raw, names, groups = self._raw, self.names, []
        for i in ids:
            i = int(i)
            body = raw.get(i)
            if body is None or names.get(i) != name:
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

    def of_type(self, *names: str) -> list[int]:
        """Ids of the simple records of these entity names, in file order (from an
        index of the names built at the first call: a reader asks for a dozen)."""
        if self._by_name is None:
            idx: dict = {}
            for i, n in self.names.items():
                got = idx.get(n)
                if got is None:
                    idx[n] = [i]
                else:
                    got.append(i)
            self._by_name = idx
        want = {n.upper() for n in names}
        lists = [self._by_name[n] for n in want if n in self._by_name]
        if len(lists) <= 1:
            return list(lists[0]) if lists else []
        if self._ordered is None:  # ids increasing through the file: file order
            ids = list(self.names)
            self._ordered = all(a < b for a, b in zip(ids, ids[1:]))
        if self._ordered:
            return sorted(i for ids in lists for i in ids)
        return [i for i, n in self.names.items() if n in want]

    def complex_ids(self, part: str | None = None) -> list[int]:
        """Ids of the complex records (``#id = (A(...) B(...))``), those naming entity
        ``part`` among their parts when given (found in the text, parsed later)."""
        ids = self.of_type("")  # (the complex records' name)
        if part is None:
            return ids
        want, raw = part.upper(), self._raw
        bodies = raw.many(ids) if isinstance(raw, Bodies) else [raw[i] for i in ids]
        return [i for i, b in zip(ids, bodies) if want in b.upper()]


def read_p21(path, data: bytes | None = None) -> P21:
    """Cut a STEP file into records (:class:`P21`); ``data``: its bytes when already
    read."""
    path = Path(path)
    if data is None:
        try:
            data = path.read_bytes()
        except OSError as exc:
            raise FileFormatError(f"cannot read {path}: {exc.strerror or exc}") from None
    return P21(data.decode("latin-1"), str(path))
