"""Assemblies in geomkit's own STEP reader: where each part's B-rep sits.

A STEP assembly places a part's shape representation into its parent's by a
``REPRESENTATION_RELATIONSHIP_WITH_TRANSFORMATION`` whose ``ITEM_DEFINED_TRANSFORMATION``
maps one axis placement onto another (``rep_1`` is the component and ``rep_2`` the
assembly, as writers use it; the ``NEXT_ASSEMBLY_USAGE_OCCURRENCE`` named by its
``CONTEXT_DEPENDENT_SHAPE_REPRESENTATION`` settles it when it says otherwise), or by a
``MAPPED_ITEM`` (its representation map's origin onto its target).  Plain
``SHAPE_REPRESENTATION_RELATIONSHIP`` links join representations of one product (its
placement frame and its B-rep) without moving them.

:func:`instances` walks from the top assembly down and returns each B-rep shell with
the 4 x 4 matrix that carries it into the top assembly's frame, once per occurrence.
"""

from __future__ import annotations

import numpy as np

from geomkit.cad.loops import Unsupported
from geomkit.cad.p21 import P21, Ref

__all__ = ["instances", "frame"]


def frame(geom, i) -> np.ndarray:
    """4 x 4 matrix of an AXIS2_PLACEMENT_3D (local to its context)."""
    O, Z, X = geom.axis2(i)
    M = np.eye(4)
    M[:3, 0], M[:3, 1], M[:3, 2], M[:3, 3] = X, np.cross(Z, X), Z, O
    return M


class _Groups:
    """Union-find over representation ids (identity links)."""

    def __init__(self):
        self.up: dict = {}

    def find(self, i):
        i = int(i)
        while self.up.get(i, i) != i:
            self.up[i] = self.up.get(self.up[i], self.up[i])
            i = self.up[i]
        return i

    def join(self, a, b):
        a, b = self.find(a), self.find(b)
        if a != b:
            self.up[max(a, b)] = min(a, b)


def _product_of_rep(p: P21):
    """Representation id -> product definition id (through the shape definition
    representations of product definition shapes)."""
    out = {}
    for i in p.of_type("SHAPE_DEFINITION_REPRESENTATION"):
        _, a = p.get(i)
        if p.names.get(int(a[0])) != "PRODUCT_DEFINITION_SHAPE":
            continue
        _, d = p.get(a[0])
        if isinstance(d[2], Ref) and p.names.get(int(d[2])) == "PRODUCT_DEFINITION":
            out[int(a[1])] = int(d[2])
    return out


def instances(p: P21, geom, items, holds) -> list:
    """``[(rep id, 4x4 matrix), ...]``: every B-rep representation (``holds(rep)``)
    once per occurrence in the top assembly, with the matrix from its frame to the
    top's; in the order of the file's placements, depth first."""
    groups = _Groups()
    for i in p.of_type("SHAPE_REPRESENTATION_RELATIONSHIP", "REPRESENTATION_RELATIONSHIP"):
        _, a = p.get(i)
        groups.join(a[2], a[3])
    prod = _product_of_rep(p)
    nauo_of_cdsr = {}
    for i in p.of_type("CONTEXT_DEPENDENT_SHAPE_REPRESENTATION"):
        _, a = p.get(i)
        _, pds = p.get(a[1])
        if isinstance(pds[2], Ref) and p.names.get(int(pds[2])) == \
                "NEXT_ASSEMBLY_USAGE_OCCURRENCE":
            nauo_of_cdsr[int(a[0])] = int(pds[2])
    children: dict = {}  # parent group -> [(child group, matrix child -> parent)]
    is_child = set()
    for i in p.complex_ids("REPRESENTATION_RELATIONSHIP_WITH_TRANSFORMATION"):
        _, parts = p.get(i)
        rel = parts.get("REPRESENTATION_RELATIONSHIP")
        t = parts.get("REPRESENTATION_RELATIONSHIP_WITH_TRANSFORMATION", [None])[0]
        if rel is None or t is None or p.names.get(int(t)) != "ITEM_DEFINED_TRANSFORMATION":
            raise Unsupported(f"#{i}: a placement that is not an item-defined "
                              "transformation")
        r1, r2 = int(rel[2]), int(rel[3])
        _, ta = p.get(t)
        T = frame(geom, ta[3]) @ np.linalg.inv(frame(geom, ta[2]))  # rep_1 -> rep_2
        child, parent = r1, r2
        nauo = nauo_of_cdsr.get(i)
        if nauo is not None:
            _, na = p.get(nauo)
            related = int(na[4])
            if prod.get(r2) == related or any(
                    prod.get(r) == related for r in prod if groups.find(r) == groups.find(r2)):
                child, parent, T = r2, r1, np.linalg.inv(T)
        children.setdefault(groups.find(parent), []).append((groups.find(child), T))
        is_child.add(groups.find(child))
    for i in p.of_type("MAPPED_ITEM"):
        _, a = p.get(i)
        _, m = p.get(a[1])
        owners = [r for r in items if int(i) in items[r]]
        T = frame(geom, a[2]) @ np.linalg.inv(frame(geom, m[0]))
        for r in owners:
            children.setdefault(groups.find(r), []).append((groups.find(m[1]), T))
            is_child.add(groups.find(m[1]))
    brep_groups: dict = {}
    for r in items:
        if holds(r):
            brep_groups.setdefault(groups.find(r), []).append(r)
    # the top: groups no placement puts elsewhere, holding a product's shape or
    # placing others (a representation of the same solid attached to a property,
    # outside the product structure, is not a part of its own)
    with_product = {groups.find(r) for r in prod}
    roots = sorted(g for g in {groups.find(r) for r in list(children) + list(brep_groups)}
                   - is_child if g in children or g in with_product)
    out = []

    def walk(g, M, depth):
        if depth > 64:
            raise Unsupported("assembly placements nest deeper than 64 (a cycle?)")
        for r in brep_groups.get(g, []):
            out.append((r, M))
        for c, T in children.get(g, []):
            walk(c, M @ T, depth + 1)

    for g in roots:
        walk(g, np.eye(4), 0)
    return out
