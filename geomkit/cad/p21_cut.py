"""A STEP physical file (ISO 10303-21) cut into its records, for
:class:`geomkit.cad.p21.P21`: the HEADER section's text, each record's body (the text
after ``#id =``) and entity name, and the index of the names.

The DATA section's records end at each ``;`` after an even number of quotes (``''``
escapes count twice); one pass over the text's bytes
(:func:`geomkit._kernels.p21_scan.cut_records`) reads their ids, bodies and names.
A text that pass leaves (a fault to name, a duplicate id, a character outside
Latin-1, whitespace it does not strip) is cut record by record
(:func:`cut_records`), the reference route, with the same result or a
:class:`~geomkit.errors.FileFormatError` naming the fault.
"""

from __future__ import annotations

import re

import numpy as np

from geomkit._kernels.p21_scan import (BODY0, BODY1, CODE, ID, LOWER, NAME0, NAME1,
                                       cut_records as scan_records,
                                       find_upper as find_upper_bytes)
from geomkit.errors import FileFormatError

__all__ = ["cut", "cut_records", "sections", "strip_comments", "find_upper", "Bodies"]

_COMMENT = re.compile(r"'(?:[^']|'')*'|/\*.*?\*/", re.S)
_SHARP_S = "\xdf"
"""The one Latin-1 character whose upper case is longer (``'SS'``)."""


def strip_comments(text: str) -> str:
    """Comments ``/* ... */`` outside strings made one space.  Walks the comments
    (a file has few) keeping the parity of the quotes before each: odd, it is inside
    a string (``''`` escapes count twice); a text whose strings do not close is
    left to :data:`_COMMENT`."""
    if not _has_comment(text):
        return text
    out, pos, scan, odd = [], 0, 0, False
    i = text.find("/*")
    while i >= 0:
        odd ^= bool(text.count("'", scan, i) % 2)
        scan = i
        if odd:  # inside a string
            i = text.find("/*", i + 2)
            continue
        j = text.find("*/", i + 2)
        if j < 0:
            break
        out += [text[pos:i], " "]
        pos = scan = j + 2
        i = text.find("/*", pos)
    if odd ^ bool(text.count("'", scan) % 2):  # a string left open outside comments
        return _COMMENT.sub(lambda m: m.group(0) if m.group(0)[0] == "'" else " ", text)
    out.append(text[pos:])
    return "".join(out)


def _has_comment(text: str) -> bool:
    """``"/*" in text``, from the text's slashes (a file has few; ``str``'s search for
    two characters is slow where the second, ``*``, is common) while they are few."""
    i = text.find("/")
    for _ in range(64):
        if i < 0:
            return False
        if text.startswith("*", i + 1):
            return True
        i = text.find("/", i + 1)
    return "/*" in text


def _semicolons(b, lo: int, hi: int, semis=None):
    """Positions of the ``;`` bytes of ``b[lo:hi]`` (in ``b``), from ``semis`` (those of
    all ``b``) when given."""
    if semis is None:
        return np.flatnonzero(b[lo:hi] == 59) + lo
    return semis[np.searchsorted(semis, lo):np.searchsorted(semis, hi)]


def find_upper(text: str, b, word: str, start: int, semis=None) -> int:
    """``text.upper().find(word, start)`` for a Latin-1 text without a sharp s (whose
    bytes are ``b``; ``semis``: the positions of its ``;``, optional) and an
    upper-case ``word`` ending in a letter and ``;``: the exact word's first place,
    unless a word in other case may come first (a ``;`` after that letter in either
    case before it), then a scan of the bytes."""
    i = text.find(word, start)
    stop = b.size if i < 0 else i + len(word) - 1
    semi = _semicolons(b, start + 1, stop, semis) - 1  # (each ';''s byte before)
    if ((b[semi] | 32) == ord(word[-2].lower())).any():
        return find_upper_bytes(b, np.frombuffer(word.encode(), np.uint8), start)
    return i


def _check_sections(source, h, d, e):
    """Raise unless the HEADER and DATA sections were found (positions, -1 for none)
    and DATA ends."""
    if h < 0 or d < 0:
        raise FileFormatError(f"{source}: no HEADER or DATA section")
    if e < 0:
        raise FileFormatError(f"{source}: the DATA section does not end "
                              "(no ENDSEC;): the file is truncated")


def sections(text: str, source: str):
    """``(HEADER text, DATA text)`` found in the upper-cased text (the reference
    route)."""
    up = text.upper()
    h = up.find("HEADER;")
    d = up.find("DATA;")
    e = up.find("ENDSEC;", d) if d >= 0 else -1
    _check_sections(source, h, d, e)
    return text[h + 7:d], text[d + 5:e]


def cut(text: str, source: str):
    """``(header, raw, names, by_name, ordered)`` of a STEP file's text: the HEADER
    section's text, ``{id: body}`` and ``{id: entity name}`` (upper case, ``''`` for a
    complex record) in file order, ``{name: ids}`` in file order (None: left to
    :meth:`~geomkit.cad.p21.P21.of_type` to build) and whether the ids increase
    through the file (None: unknown)."""
    text = strip_comments(text)
    lead = len(text) - len(text.lstrip())
    if not text[lead:lead + 12].upper().startswith("ISO-10303-21"):
        raise FileFormatError(f"{source}: not a STEP file (it does not begin with "
                              "ISO-10303-21;)")
    try:
        b = np.frombuffer(text.encode("latin-1"), np.uint8)
    except UnicodeEncodeError:  # (a text not read from a file's bytes)
        b = None
    if b is None or _SHARP_S in text:  # (upper-cased to 'SS': other positions)
        head, data = sections(text, source)
        return (head,) + cut_records(data, source) + (None, None)
    semis = np.flatnonzero(b == 59)  # (every ';', found once)
    h = find_upper(text, b, "HEADER;", 0, semis)
    d = find_upper(text, b, "DATA;", 0, semis)
    e = find_upper(text, b, "ENDSEC;", d, semis) if d >= 0 else -1
    _check_sections(source, h, d, e)
    return (text[h + 7:d],) + _scan(text, b, d + 5, e, source, semis)


class Bodies:
    """``{id: body}`` of a file's records (ids in file order), each body cut from the
    file's text when asked for (a reader asks for a part of them): a dict's reading
    methods; setting a body makes it a dict."""

    __slots__ = ("_text", "_ids", "_row", "_a", "_e", "_dict", "_bytes")

    def __init__(self, text: str, ids: list, a: list, e: list, spans=None):
        self._text, self._ids, self._a, self._e = text, ids, a, e
        self._row = dict(zip(ids, range(len(ids))))  # (fewer than ids: one repeated)
        self._dict = None
        self._bytes = spans  # (the text's Latin-1 bytes, the bodies' starts, ends)

    def spans(self, ids):
        """``(bytes, starts, ends)``: where the bodies of ``ids`` lie in the text's
        bytes (``body(i) == text[starts[k]:ends[k]]``), or None (no bytes kept, or a
        body set since)."""
        if self._bytes is None or self._dict is not None:
            return None
        b, A, E = self._bytes
        rows = np.fromiter(map(self._row.__getitem__, ids), np.int64, len(ids))
        return b, A[rows], E[rows]

    def get(self, i, default=None):
        if self._dict is not None:
            return self._dict.get(i, default)
        r = self._row.get(i)
        return default if r is None else self._text[self._a[r]:self._e[r]]

    def __getitem__(self, i):
        got = self.get(i, _MISSING)
        if got is _MISSING:
            raise KeyError(i)
        return got

    def __setitem__(self, i, body):
        if self._dict is None:
            self._dict = dict(self.items())
        self._dict[i] = body

    def __contains__(self, i) -> bool:
        return i in (self._row if self._dict is None else self._dict)

    def __len__(self) -> int:
        return len(self._row if self._dict is None else self._dict)

    def __iter__(self):
        return iter(self.keys())

    def keys(self):
        return self._row.keys() if self._dict is None else self._dict.keys()

    def values(self):
        if self._dict is not None:
            return self._dict.values()
        t = self._text
        return [t[a:e] for a, e in zip(self._a, self._e)]

    def items(self):
        return zip(self.keys(), self.values())

    def many(self, ids) -> list:
        """``[self[i] for i in ids]``."""
        if self._dict is not None:
            return [self._dict[i] for i in ids]
        t, a, e = self._text, self._a, self._e
        return [t[a[r]:e[r]] for r in map(self._row.__getitem__, ids)]


_MISSING = object()


def _scan(text, b, start, stop, source, semis=None):
    """``(raw, names, by_name, ordered)`` of the DATA section ``text[start:stop]``
    (``b``: the text's bytes, ``semis``: the places of its ``;``, optional) from one
    pass over its records, or from :func:`cut_records` for a text that pass leaves."""
    part = b[start:stop]
    ends = _semicolons(b, start, stop, semis)
    quotes = np.flatnonzero(part == 39) + start
    if quotes.size % 2:  # the text ends inside a string
        return cut_records(text[start:stop], source) + (None, None)
    if quotes.size:  # the ';' after an even number of quotes
        ends = ends[(np.searchsorted(quotes, ends) & 1) == 0]
    ends = np.concatenate([[start - 1], ends, [stop]])
    status, recs, firsts, n, m = scan_records(b, ends)
    if status:
        return cut_records(text[start:stop], source) + (None, None)
    recs = recs[:n]
    ids = recs[:, ID].tolist()
    A, E = recs[:, BODY0], recs[:, BODY1]
    raw = Bodies(text, ids, A.tolist(), E.tolist(), (b, A.astype(np.int64), E.astype(np.int64)))
    if len(raw) != n:  # an id defined twice: named record by record
        return cut_records(text[start:stop], source) + (None, None)
    rows = recs[firsts[:m]]
    first = [text[a:e] for a, e in zip(rows[:, NAME0].tolist(), rows[:, NAME1].tolist())]
    codes = recs[:, CODE]
    names = dict(zip(ids, [first[c] for c in codes.tolist()]))
    if recs[:, LOWER].any():  # names to upper-case (then of_type builds the index)
        return raw, {i: v.upper() for i, v in names.items()}, None, None
    order = np.argsort(codes, kind="stable")
    ends = np.cumsum(np.bincount(codes, minlength=m)).tolist()
    ids_by_name = recs[order, ID].tolist()
    by_name = {first[c]: ids_by_name[a:e]
               for c, (a, e) in enumerate(zip([0] + ends[:-1], ends))}
    return raw, names, by_name, bool(np.all(recs[1:, ID] > recs[:-1, ID]))


def cut_records(data: str, source: str):
    """``(raw, names)`` of the DATA section's text, record by record (the reference
    route: it names the first fault)."""
    raw: dict[int, str] = {}
    names: dict[int, str] = {}
    pieces = data.split(";")
    buf = ""
    for piece in pieces:
        buf = buf + ";" + piece if buf else piece
        if buf.count("'") % 2:  # a ';' inside a string: keep collecting
            continue
        rec, buf = buf.strip(), ""
        if not rec:
            continue
        if rec[0] != "#":
            raise FileFormatError(f"{source}: a record that does not start "
                                  f"with #id: {rec[:40]!r}")
        ident, eq, body = rec[1:].partition("=")
        if not eq:
            raise FileFormatError(f"{source}: record {rec[:30]!r} has no '='")
        try:
            i = int(ident)
        except ValueError:
            raise FileFormatError(f"{source}: bad record id "
                                  f"#{ident.strip()[:20]!r}") from None
        if i in raw:
            raise FileFormatError(f"{source}: record #{i} is defined twice")
        body = body.strip()
        raw[i] = body
        k = body.find("(")
        names[i] = body[:k].strip().upper() if k > 0 else ""
    if buf.strip():
        raise FileFormatError(f"{source}: the DATA section ends inside a "
                              "string (an unmatched quote)")
    return raw, names
