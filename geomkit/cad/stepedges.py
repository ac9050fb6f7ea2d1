"""The line and circle edges of a STEP B-rep built file-wide, for
:class:`geomkit.cad.stepbrep._Faces`, and the plain records they and the faces'
oriented edges are read from (:func:`fields`).

Most edges of a machined part are ``EDGE_CURVE``\\ s on a ``LINE`` or a ``CIRCLE``
between two ``VERTEX_POINT``\\ s.  Built one by one, each goes through a dozen
record lookups and small array operations; here the points, directions and
parameters of all of them are gathered in a few array operations, with the values
the edge-by-edge route (:meth:`~geomkit.cad.stepbrep._Faces.edge`) computes, bit for
bit: the same parsed numbers, each dot product taken as that route takes it (one
pair at a time, as ``numpy`` sums three terms), element-wise operations in the same
order.  An edge with anything else (a complex or non-plain record, a non-finite or
zero value, vertices in reverse order on the curve) is left to the edge-by-edge
route, which reads it or names the fault.
"""

from __future__ import annotations

import re

import numpy as np

from geomkit.cad.analytic import arc_curve, norm3
from geomkit.cad.p21 import DERIVED, P21, Ref
from geomkit.cad.stepgeom import reverse_curve
from geomkit._kernels.arcs import circle_frames, circle_nets, line_edges

__all__ = ["line_and_circle_edges", "fields", "fields_of"]


_NUM = r"([-+]?(?:\d+\.\d*|\d*\.\d+|\d+)(?:[Ee][-+]?\d+)?)"
_REF = r"\s*,\s*#(\d+)"
_LABEL = r"\s*\(\s*'[^']*'"
_FIELDS = {
    "EDGE_CURVE": re.compile("EDGE_CURVE" + _LABEL + _REF * 3 + r"\s*,\s*\.([TF])\.\s*\)"),
    "VERTEX_POINT": re.compile("VERTEX_POINT" + _LABEL + _REF + r"\s*\)"),
    "LINE": re.compile("LINE" + _LABEL + _REF * 2 + r"\s*\)"),
    "VECTOR": re.compile("VECTOR" + _LABEL + _REF + r"\s*,\s*" + _NUM + r"\s*\)"),
    "AXIS2_PLACEMENT_3D": re.compile("AXIS2_PLACEMENT_3D" + _LABEL + _REF * 3 + r"\s*\)"),
    "CIRCLE": re.compile("CIRCLE" + _LABEL + _REF + r"\s*,\s*" + _NUM + r"\s*\)"),
    "ORIENTED_EDGE": re.compile("ORIENTED_EDGE" + _LABEL + r"\s*,\s*\*\s*,\s*\*" + _REF
                                + r"\s*,\s*\.([TF])\.\s*\)"),
}
"""The writers' plain form of each record read here: a label, then references, a
number, an enumeration (read at once; any other form goes through the parser)."""
_KINDS = {"EDGE_CURVE": "rrre", "VERTEX_POINT": "r", "LINE": "rr", "VECTOR": "rn",
          "AXIS2_PLACEMENT_3D": "rrr", "CIRCLE": "rn", "ORIENTED_EDGE": "re"}
"""The fields after the label: r a reference, n a number, e an enumeration (T, F)."""


_CONVERT = {
    "EDGE_CURVE": lambda g: (int(g[0]), int(g[1]), int(g[2]), g[3] == "T"),
    "VERTEX_POINT": lambda g: (int(g[0]),),
    "LINE": lambda g: (int(g[0]), int(g[1])),
    "VECTOR": lambda g: (int(g[0]), float(g[1])),
    "AXIS2_PLACEMENT_3D": lambda g: (int(g[0]), int(g[1]), int(g[2])),
    "CIRCLE": lambda g: (int(g[0]), float(g[1])),
    "ORIENTED_EDGE": lambda g: (int(g[0]), g[1] == "T"),
}
"""Each record's fields from its regex groups (what :func:`fields` converts)."""
_MANY = {name: re.compile("(?:" + r.pattern + r"|[^\x00]*)\x00") for name, r in _FIELDS.items()}
"""The plain form of each record, else anything, up to the separator: one match per
record of a joined text (:func:`fields_of`)."""


def fields_of(p: P21, ids, name: str) -> list:
    """``[fields(p, i, name) for i in ids]``: the plain records read by one regex pass
    over their joined texts, the others by :func:`fields`."""
    names, raw = p.names, p.body
    bodies = [raw(i) if names.get(int(i)) == name else "" for i in ids]
    text = "\x00".join(bodies) + "\x00"
    got = _MANY[name].findall(text) if text.count("\x00") == len(bodies) else None
    if got is None or len(got) != len(bodies):
        return [fields(p, i, name) for i in ids]
    if _MANY[name].groups == 1:  # (findall gives the group itself)
        got = [(g,) for g in got]
    conv = _CONVERT[name]
    return [conv(g) if g[0] else fields(p, i, name) for i, g in zip(ids, got)]


def fields(p: P21, i, name: str):
    """The fields of simple record ``i`` of entity ``name`` after its label (ints for
    references, floats for numbers, the enumeration's value), or None when it is
    another entity or its fields are not of those kinds."""
    if p.names.get(int(i)) != name:
        return None
    m = _FIELDS[name].fullmatch(p.body(i))
    if m is not None:
        return tuple(int(g) if k == "r" else float(g) if k == "n" else g == "T"
                     for k, g in zip(_KINDS[name], m.groups()))
    try:
        got = p.get(i)
    except Exception:  # a malformed record: the edge-by-edge route names it
        return None
    a = got[1]
    stars = 2 if name == "ORIENTED_EDGE" else 0
    if got[0] != name or len(a) != len(_KINDS[name]) + 1 + stars:
        return None
    if name == "ORIENTED_EDGE":  # its two derived (*) parameters
        if a[1:3] != [DERIVED, DERIVED]:
            return None
        a = a[:1] + a[3:]
    out = []
    for k, v in zip(_KINDS[name], a[1:]):
        if k == "r" and isinstance(v, Ref):
            out.append(int(v))
        elif k == "n" and isinstance(v, (int, float)) and not isinstance(v, bool):
            out.append(float(v))
        elif k == "e":
            out.append(v is not False)  # .F. reverses, anything else does not
        else:
            return None
    return tuple(out)


def _coords(p: P21, ids, name: str):
    """Coordinates (n, 3) of plain ``name`` records (all finite), or None."""
    if not ids:
        return np.empty((0, 3))
    X = p.coordinates(ids, name, 3)
    if X is None or not np.isfinite(X).all():
        return None
    return X


def _units(V):
    """Rows of ``V`` over their norms (``v / norm3(v)``, row by row), and whether each
    norm is positive and finite."""
    n = np.array([norm3(v) for v in V])
    ok = (n > 0) & np.isfinite(n)
    return V / np.where(ok, n, 1.0)[:, None], ok


def line_and_circle_edges(p: P21, found: dict | None = None) -> dict:
    """``{EDGE_CURVE id: (p, U, Pw)}`` of the file's plain line and circle edges, as
    :meth:`~geomkit.cad.stepbrep._Faces.edge` builds them (the curve run from the start
    vertex to the end vertex, reversed when its sense is ``.F.``).  ``found``: a dict
    given the :func:`fields` read on the way, of every plain ``EDGE_CURVE`` and of
    their plain ``VERTEX_POINT`` records (``{name: {id: fields}}``), for the other edges."""
    edges = []  # (id, start point, end point, curve kind, curve fields, same, closed)
    ids = p.of_type("EDGE_CURVE")
    ecs = [(i, a) for i, a in zip(ids, fields_of(p, ids, "EDGE_CURVE")) if a is not None]
    vids = list({v: None for _, a in ecs for v in a[:2]})
    vf = dict(zip(vids, fields_of(p, vids, "VERTEX_POINT")))
    if found is not None:
        found["EDGE_CURVE"] = dict(ecs)
        found["VERTEX_POINT"] = {v: f for v, f in vf.items() if f is not None}
    cids = {"LINE": [], "CIRCLE": []}
    for _, a in ecs:
        name = p.names.get(a[2])
        if name in cids:
            cids[name].append(a[2])
    cf = {name: dict(zip(c, fields_of(p, c, name))) for name, c in cids.items()}
    for i, (v1, v2, cid, same) in ecs:
        x1, x2 = vf[v1], vf[v2]
        name = p.names.get(cid)
        if x1 is None or x2 is None or name not in cf:
            continue
        c = cf[name][cid]
        if c is not None:
            edges.append((i, x1[0], x2[0], name, c, same, v1 == v2))
    out = {}
    lines = [e for e in edges if e[3] == "LINE"]
    circles = [e for e in edges if e[3] == "CIRCLE"]
    if lines:
        out.update(_lines(p, lines))
    if circles:
        out.update(_circles(p, circles))
    return out


def _vertices(p, edges):
    X1 = _coords(p, [e[1] for e in edges], "CARTESIAN_POINT")
    X2 = _coords(p, [e[2] for e in edges], "CARTESIAN_POINT")
    return (None, None) if X1 is None or X2 is None else (X1, X2)


def _with_record(p, edges, slot: int, name: str):
    """The edges whose curve's field ``slot`` is a plain ``name`` record, with that
    record's fields."""
    got = zip(edges, fields_of(p, [e[4][slot] for e in edges], name))
    got = [(e, f) for e, f in got if f is not None]
    return [e for e, _ in got], [f for _, f in got]


def _lines(p, edges):
    out = {}
    edges, vecs = _with_record(p, edges, 1, "VECTOR")
    if not edges:
        return out
    X1, X2 = _vertices(p, edges)
    O = _coords(p, [e[4][0] for e in edges], "CARTESIAN_POINT")
    Dr = _coords(p, [v[0] for v in vecs], "DIRECTION")
    if X1 is None or O is None or Dr is None:
        return out
    U, ok = _units(Dr)
    mag = np.array([v[1] for v in vecs])
    ok &= np.isfinite(mag) & (mag != 0)
    D = U * mag[:, None]
    # every edge's segment in one call (the arithmetic of line_curve and
    # reverse_curve edge by edge)
    keep, Uk, Pw = line_edges(O, D, X1, X2, np.array([e[5] for e in edges], dtype=bool))
    for k in np.flatnonzero(ok & keep).tolist():
        out[edges[k][0]] = (1, Uk[k].copy(), Pw[k].copy())
    return out


def _circles(p, edges):
    out = {}
    edges, axes = _with_record(p, edges, 0, "AXIS2_PLACEMENT_3D")
    if not edges:
        return out
    X1, X2 = _vertices(p, edges)
    C = _coords(p, [a[0] for a in axes], "CARTESIAN_POINT")
    Zr = _coords(p, [a[1] for a in axes], "DIRECTION")
    Xr = _coords(p, [a[2] for a in axes], "DIRECTION")
    if X1 is None or C is None or Zr is None or Xr is None:
        return out
    Z, okz = _units(Zr)
    Xd, okx = _units(Xr)
    r = np.array([e[4][1] for e in edges])
    ok = okz & okx & np.isfinite(r) & (r > 0)
    # every circle's frame and its vertices' angles in one call (the edge-by-edge
    # route's arithmetic)
    same = np.array([e[5] for e in edges], dtype=bool)
    keep, x, y, t = circle_frames(Z, Xd, C, r, X1, X2, same,
                                  np.array([e[6] for e in edges], dtype=bool))
    use = ok & keep
    # every circle's arc (and its reversal) in one call, each edge's arrays views
    built, U, Pw, uo, po = circle_nets(C, x, y, r, t, same, use)
    uo, po = uo.tolist(), po.tolist()
    for k in np.flatnonzero(use).tolist():
        e = edges[k]
        if built:
            out[e[0]] = (2, U[uo[k]:uo[k + 1]], Pw[po[k]:po[k + 1]])
            continue
        rk = float(r[k])  # (the arc one by one: a sweep that is not an arc raises)
        c = arc_curve(C[k], rk * x[k], rk * y[k], 1.0, float(t[k, 0]), float(t[k, 1]))
        out[e[0]] = c if e[5] else reverse_curve(c)
    return out
