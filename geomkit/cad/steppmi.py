"""Semantic PMI of STEP AP242 files: geometric tolerances, datums and dimensions with
the faces they apply to, read from the file's records (:mod:`geomkit.cad.p21`) by
geomkit alone.

What is read follows the CAx-IF *Recommended Practices for the Representation and
Presentation of PMI (AP242)*:

* **Geometric tolerances**: ``GEOMETRIC_TOLERANCE`` subtypes, simple or complex
  (``GEOMETRIC_TOLERANCE_WITH_DATUM_REFERENCE``, ``_WITH_MODIFIERS``,
  ``_WITH_DEFINED_UNIT``, ``_WITH_DEFINED_AREA_UNIT``, ``_WITH_MAXIMUM_TOLERANCE``,
  ``UNEQUALLY_DISPOSED_GEOMETRIC_TOLERANCE``, AP214's ``MODIFIED_GEOMETRIC_TOLERANCE``);
  the zone magnitude with its unit, the zone form (``TOLERANCE_ZONE``: diameter,
  spherical), a projected zone's length, the datum system (``DATUM_SYSTEM`` ->
  ``DATUM_REFERENCE_COMPARTMENT`` -> ``DATUM`` or common datums of
  ``DATUM_REFERENCE_ELEMENT``; AP214's ``DATUM_REFERENCE``) with modifiers, and
  ``GEOMETRIC_TOLERANCE_RELATIONSHIP`` (composite frames).
* **Datums**: ``DATUM`` letters, their datum features and datum targets (through
  ``SHAPE_ASPECT_RELATIONSHIP``), a target's feature through
  ``FEATURE_FOR_DATUM_TARGET_RELATIONSHIP``.
* **Dimensions**: ``DIMENSIONAL_SIZE`` / ``ANGULAR_SIZE`` / ``..._WITH_PATH`` and
  ``DIMENSIONAL_LOCATION`` / ``ANGULAR_LOCATION`` / ``DIRECTED_...`` / ``..._WITH_PATH``;
  values from ``DIMENSIONAL_CHARACTERISTIC_REPRESENTATION`` ->
  ``SHAPE_DIMENSION_REPRESENTATION`` (nominal value, limits, ``TYPE_QUALIFIER``),
  tolerances from ``PLUS_MINUS_TOLERANCE`` (``TOLERANCE_VALUE``, ``LIMITS_AND_FITS``).
* **Faces**: a shape aspect's faces are the ``ADVANCED_FACE`` items its
  ``GEOMETRIC_ITEM_SPECIFIC_USAGE`` / ``ITEM_IDENTIFIED_REPRESENTATION_USAGE`` name,
  and those of the aspects it is made of (``SHAPE_ASPECT_RELATIONSHIP`` from a
  ``COMPOSITE_SHAPE_ASPECT``, ``ALL_AROUND_SHAPE_ASPECT``,
  ``COMPOSITE_GROUP_SHAPE_ASPECT``, ``SHAPE_ASPECT_DERIVING_RELATIONSHIP`` from a
  derived aspect), numbered in :func:`geomkit.read_step`'s order (computed the way
  :func:`geomkit.cad.stepbrep.read_native` numbers them).

Anything else that is PMI is listed in ``Pmi.unsupported`` with why: tolerances of
no known characteristic, zone definitions other than projected (runout, non-uniform),
dimension values the reader does not read, graphic PMI with no semantic item
(``DRAUGHTING_CALLOUT`` linked to nothing by a ``DRAUGHTING_MODEL_ITEM_ASSOCIATION``).
Nothing is dropped silently.  A reference to a missing record or to a record of the
wrong kind is a :class:`~geomkit.errors.FileFormatError` naming the record.
"""

from __future__ import annotations

from pathlib import Path

from geomkit.cad.loops import Unsupported
from geomkit.cad.p21 import P21, Ref, Typed, read_p21
from geomkit.cad.stepasm import instances
from geomkit.cad.stepbrep import (_MALFORMED, _holds_brep, _placed, _rep_items, _shells,
                                  file_units)
from geomkit.cad.stepgeom import StepGeometry
from geomkit.cad.steppmi_types import (
    MM_PER_UNIT, TOLERANCE_TYPES, _ASPECT_MODIFIERS, _DECOMPOSE, _DIAMETER_FORMS, _FACES,
    _FORMS, _LOCATIONS, _NAMED, _SI_LENGTH, _SIZES, _TARGETS, _UNREAD_KINDS, _USAGES,
    _ZONE_DEFS, Datum, DatumRef, DatumTarget, Dimension, Pmi, Tolerance, Unread)
from geomkit.errors import FileFormatError

__all__ = ["Datum", "DatumRef", "DatumTarget", "Dimension", "Pmi", "Tolerance", "Unread",
           "face_order", "read_pmi"]



def face_order(p: P21) -> dict:
    """``{face record id: [face indices]}`` in :func:`geomkit.read_step`'s order
    (Open CASCADE's ``TopExp_Explorer`` order), computed as
    :func:`geomkit.cad.stepbrep.read_native` numbers the faces: every face of every
    shell of the B-rep items in file order, each placement of an assembly's part in
    turn (a face of a part placed twice has two indices).  Raises what the B-rep
    reader raises for a file it does not number (``Unsupported``, ``FileFormatError``).
    """
    _, angle, _ = file_units(p)
    geom = StepGeometry(p, angle)
    if _placed(p, geom):
        placed = [_shells(p, [r]) for r, _ in
                  instances(p, geom, _rep_items(p), lambda r: _holds_brep(p, r))]
    else:
        placed = [_shells(p)]
    out: dict = {}
    k = 0
    for shells in placed:
        for sh in shells:
            _, sa = geom.rec(sh, "CLOSED_SHELL", "OPEN_SHELL", "CONNECTED_FACE_SET",
                             "ORIENTED_CLOSED_SHELL")
            for face in sa[1]:
                out.setdefault(int(face), []).append(k)
                k += 1
    return out


class _Bad(Exception):
    """A record of the wrong kind (turned into a FileFormatError naming the item)."""


class _Reader:
    def __init__(self, p: P21):
        self.p = p
        self.unread: list[Unread] = []
        self._units: dict = {}
        self.pmi_units = {"length": set(), "angle": set()}
        self.usage = self._index(_USAGES, 2, 4)
        self.down = self._index(_DECOMPOSE, 2, 3)
        self.up = self._index(_DECOMPOSE, 3, 2)
        self.target_feature = self._index(("FEATURE_FOR_DATUM_TARGET_RELATIONSHIP",), 3, 2)
        self.dcr = self._index(("DIMENSIONAL_CHARACTERISTIC_REPRESENTATION",), 0, 1)
        self.pmt = self._index(("PLUS_MINUS_TOLERANCE",), 1, None)
        self.zones: dict = {}
        for z in p.of_type("TOLERANCE_ZONE"):
            _, a = p.get(z)
            for t in a[4] if isinstance(a[4], list) else []:
                self.zones.setdefault(int(t), []).append(z)
        self.zone_defs = self._index(_ZONE_DEFS, 0, None)

    # ------------------------------------------------------------------ records
    def _index(self, names, key, val) -> dict:
        """``{params[key]: [params[val] (the record id when val is None), ...]}`` over
        the simple records ``names``; list values (a ``SET_REPRESENTATION_ITEM``)
        spread."""
        out: dict = {}
        for i in self.p.of_type(*names):
            _, a = self.p.get(i)
            try:
                k, v = a[key], (i if val is None else a[val])
            except IndexError:
                raise FileFormatError(f"{self.p.source} #{i} ({self.p.names[i]}): too "
                                      "few parameters") from None
            if isinstance(v, Typed):
                v = v.value
            for x in v if isinstance(v, list) else [v]:
                if isinstance(k, Ref) and isinstance(x, (Ref, int)):
                    out.setdefault(int(k), []).append(int(x))
        return out

    def kinds(self, i) -> set:
        """The entity names of record ``i`` (one, or a complex record's parts)."""
        name, a = self.p.get(i)
        return {name} if name is not None else set(a)

    def label(self, i) -> str:
        name, a = self.p.get(i)
        return name if name is not None else "(" + " ".join(a) + ")"

    def ref(self, x, want, what):
        """``x`` as a record id, which must be one of the entities ``want``."""
        if not isinstance(x, Ref):
            raise _Bad(f"its {what} is {x!r}, not a reference")
        if want and not (self.kinds(x) & set(want)):
            raise _Bad(f"its {what} #{int(x)} is {self.label(x)}, expected "
                       f"{' or '.join(sorted(want))}")
        return int(x)

    # -------------------------------------------------------------------- units
    def unit(self, u):
        """``(name, kind)`` of a unit record (``("in", "length")``)."""
        if u is None:
            return None, None
        key = int(self.ref(u, (), "unit"))
        if key in self._units:
            return self._units[key]
        name, a = self.p.get(key)
        parts = {name: a} if name is not None else a
        kind = ("length" if "LENGTH_UNIT" in parts else
                "angle" if "PLANE_ANGLE_UNIT" in parts else None)
        label = None
        if "SI_UNIT" in parts:
            prefix, base = parts["SI_UNIT"][0], str(parts["SI_UNIT"][1]).upper()
            if base == "METRE":
                kind = "length"
                label = _SI_LENGTH.get(None if prefix is None else str(prefix).upper(),
                                       f"{str(prefix).lower()}m")
            elif base == "RADIAN":
                kind, label = "angle", "rad"
            else:
                label = base.lower()
        elif "CONVERSION_BASED_UNIT" in parts:
            raw = str(parts["CONVERSION_BASED_UNIT"][0]).strip().lower()
            label = _NAMED.get(raw, raw)
            if kind is None and label in MM_PER_UNIT:
                kind = "length"
        self._units[key] = (label, kind)
        return label, kind

    def measure(self, i):
        """``(value, unit, item name, qualifiers)`` of a measure record: a
        ``..._MEASURE_WITH_UNIT``, a ``MEASURE_REPRESENTATION_ITEM`` or a complex
        measure item."""
        i = self.ref(i, (), "measure")
        name, a = self.p.get(i)
        label, quals = None, []
        if name is None:
            if "MEASURE_WITH_UNIT" not in a:
                raise _Bad(f"#{i} is {self.label(i)}, not a measure with unit")
            value, u = a["MEASURE_WITH_UNIT"][:2]
            label = (a.get("REPRESENTATION_ITEM") or [None])[0]
            quals = (a.get("QUALIFIED_REPRESENTATION_ITEM") or [[]])[0]
        elif name == "MEASURE_REPRESENTATION_ITEM":
            label, value, u = a[:3]
        elif name.endswith("MEASURE_WITH_UNIT"):
            value, u = a[:2]
        else:
            raise _Bad(f"#{i} is {name}, not a measure with unit")
        if isinstance(value, Typed):
            value = value.value
        try:
            value = float(value)
        except (TypeError, ValueError):
            raise _Bad(f"#{i}: the measure {value!r} is not a number") from None
        unit, kind = self.unit(u)
        if kind in self.pmi_units and unit:
            self.pmi_units[kind].add(unit)
        out = []
        for q in quals if isinstance(quals, list) else []:
            qn, qa = self.p.get(q)
            if qn == "TYPE_QUALIFIER":
                out.append(str(qa[0]))
        return value, unit, label, out

    # -------------------------------------------------------------------- faces
    def faces(self, aspects):
        """``(face record ids, other item ids, whole part)`` of shape aspects and what
        they are made of."""
        faces, items, whole = set(), set(), False
        stack, seen = [int(a) for a in aspects], set()
        while stack:
            a = stack.pop()
            if a in seen:
                continue
            seen.add(a)
            k = self.kinds(a)
            if "PRODUCT_DEFINITION_SHAPE" in k:
                whole = True
                continue
            _, prm = self.p.get(a)
            if k & _SIZES and isinstance(prm, list):
                stack.append(self.ref(prm[0], (), "applies_to"))
            elif k & _LOCATIONS and isinstance(prm, list):
                stack += [self.ref(prm[2], (), "relating aspect"),
                          self.ref(prm[3], (), "related aspect")]
            for it in self.usage.get(a, []):
                (faces if self.p.names.get(it) in _FACES else items).add(it)
            if "DATUM" in k:  # its features and targets are the datum's, not the aspect's
                continue
            for r in self.down.get(a, []):
                rk = self.kinds(r)
                if "DATUM" in rk and not ("DATUM_FEATURE" in k or k & _TARGETS):
                    continue
                stack.append(r)
        return sorted(faces), sorted(items), whole

    # --------------------------------------------------------------- tolerances
    def tolerance(self, i):
        p = self.p
        name, a = p.get(i)
        parts = {name: a} if name is not None else dict(a)
        types = sorted(n for n in parts if n in TOLERANCE_TYPES)
        base = parts.get("GEOMETRIC_TOLERANCE")
        ds, mods = [], []
        if name is not None:
            if len(a) < 4:
                raise _Bad("fewer than 4 parameters")
            base = a[:4]
            if len(a) > 4 and name == "MODIFIED_GEOMETRIC_TOLERANCE":
                mods.append(str(a[4]).lower())
            elif len(a) > 4 and isinstance(a[4], list):
                ds = a[4]
        if base is None:
            raise _Bad("a complex tolerance without its GEOMETRIC_TOLERANCE part")
        if len(types) != 1:
            why = "several characteristics " + ", ".join(types) if types else \
                "no characteristic (none of the GEOMETRIC_TOLERANCE subtypes)"
            self.unread.append(Unread(i, self.label(i), f"a geometric tolerance of {why}"))
            return None
        for extra in sorted(set(parts) - _FORMS - set(TOLERANCE_TYPES)):
            self.unread.append(Unread(i, self.label(i), f"its part {extra} is not read "
                                      "(the tolerance is listed without it)"))
        value = unit = None
        if base[2] is not None:
            value, unit, _, _ = self.measure(base[2])
        t = Tolerance(i, TOLERANCE_TYPES[types[0]], str(base[0] or ""), value, unit)
        ds = ds or (parts.get("GEOMETRIC_TOLERANCE_WITH_DATUM_REFERENCE") or [[]])[0]
        t.datums = self.datum_system(ds)
        for m in (parts.get("GEOMETRIC_TOLERANCE_WITH_MODIFIERS") or [[]])[0] or []:
            t.modifiers.append(str(m).lower())
        if "MODIFIED_GEOMETRIC_TOLERANCE" in parts and name is None:
            t.modifiers.append(str(parts["MODIFIED_GEOMETRIC_TOLERANCE"][0]).lower())
        t.modifiers += mods
        for part, keys in (("GEOMETRIC_TOLERANCE_WITH_DEFINED_UNIT", ["unit_size"]),
                           ("GEOMETRIC_TOLERANCE_WITH_MAXIMUM_TOLERANCE",
                            ["maximum_upper_tolerance"]),
                           ("UNEQUALLY_DISPOSED_GEOMETRIC_TOLERANCE", ["displacement"])):
            for key, v in zip(keys, parts.get(part) or []):
                if v is not None:
                    mv, mu, _, _ = self.measure(v)
                    t.extra[key] = (mv, mu)
        dau = parts.get("GEOMETRIC_TOLERANCE_WITH_DEFINED_AREA_UNIT")
        if dau:
            t.extra["area_type"] = str(dau[0]).lower() if dau[0] is not None else None
            if len(dau) > 1 and dau[1] is not None:
                t.extra["second_unit_size"] = self.measure(dau[1])[:2]
        self.zone(t)
        target = self.ref(base[3], (), "toleranced shape aspect")
        for kind, mod in _ASPECT_MODIFIERS.items():
            if kind in self.kinds(target):
                t.modifiers.append(mod)
        f, items, t.whole_part = self.faces([target])
        t.face_ids, t.items = f, items
        return t

    def zone(self, t: Tolerance):
        for z in self.zones.get(t.id, []):
            _, za = self.p.get(z)
            if isinstance(za[5], Ref):
                _, fa = self.p.get(za[5])
                t.zone = str(fa[0]).strip()
                t.diameter = t.zone.lower() in _DIAMETER_FORMS | {"spherical"}
                t.spherical = t.zone.lower() == "spherical"
            for d in self.zone_defs.get(z, []):
                dn, da = self.p.get(d)
                if dn == "PROJECTED_ZONE_DEFINITION" and len(da) > 3:
                    t.extra["projected_length"] = self.measure(da[3])[:2]
                    t.modifiers.append("projected")
                else:
                    self.unread.append(Unread(d, dn, f"a zone definition of tolerance "
                                              f"#{t.id} ({dn}) is not read"))

    def datum_system(self, refs) -> list[DatumRef]:
        out, old = [], []
        for r in refs if isinstance(refs, list) else []:
            k = self.kinds(self.ref(r, (), "datum system"))
            _, a = self.p.get(r)
            if "DATUM_SYSTEM" in k:
                for c in a[4]:
                    out.append(self.compartment(self.ref(
                        c, ("DATUM_REFERENCE_COMPARTMENT",), "datum compartment")))
            elif "DATUM_REFERENCE_COMPARTMENT" in k:
                out.append(self.compartment(int(r)))
            elif "DATUM_REFERENCE" in k:  # AP214: precedence, datum
                prm = a if isinstance(a, list) else a["DATUM_REFERENCE"]
                d = self.ref(prm[1], ("DATUM",), "referenced datum")
                old.append((prm[0], DatumRef(int(r), self.datum_letter(d), [d])))
            else:
                raise _Bad(f"its datum system #{int(r)} is {self.label(r)}")
        return out + [d for _, d in sorted(old, key=lambda x: x[0])]

    def compartment(self, c) -> DatumRef:
        _, a = self.p.get(c)
        base, mods = a[4], self.modifiers(a[5] if len(a) > 5 else None)
        if isinstance(base, list):  # a common datum: DATUM_REFERENCE_ELEMENTs
            datums, letters = [], []
            for e in base:
                e = self.ref(e, ("DATUM_REFERENCE_ELEMENT",), "common datum element")
                _, ea = self.p.get(e)
                d = self.ref(ea[4], ("DATUM",), "datum")
                datums.append(d)
                letters.append(self.datum_letter(d))
                mods += [f"{letters[-1]}:{m}" for m in
                         self.modifiers(ea[5] if len(ea) > 5 else None)]
            return DatumRef(c, "-".join(letters), datums, mods)
        d = self.ref(base, ("DATUM",), "datum")
        return DatumRef(c, self.datum_letter(d), [d], mods)

    def modifiers(self, mods) -> list[str]:
        out = []
        for m in mods if isinstance(mods, list) else []:
            if isinstance(m, Typed):
                out.append(str(m.value).lower())
            elif isinstance(m, Ref):
                _, ma = self.p.get(m)
                v, u, _, _ = self.measure(ma[1])
                out.append(f"{str(ma[0]).lower()}={v:g} {u or ''}".rstrip())
            elif m is not None:
                out.append(str(m).lower())
        return out

    def datum_letter(self, d) -> str:
        _, a = self.p.get(d)
        prm = a if isinstance(a, list) else a["DATUM"]
        return str(prm[4])

    # ------------------------------------------------------------------- datums
    def datum(self, i) -> Datum:
        d = Datum(i, self.datum_letter(i))
        related = self.up.get(i, []) + self.down.get(i, [])
        feats = [r for r in related if "DATUM_FEATURE" in self.kinds(r)]
        targets = [r for r in related if self.kinds(r) & _TARGETS]
        d.features = sorted(set(feats))
        face_ids, items, _ = self.faces([i] + d.features)
        own = self.usage.get(i, [])
        d.face_ids = sorted(set(face_ids) | {x for x in own
                                             if self.p.names.get(x) in _FACES})
        d.items = sorted(set(items) | {x for x in own if self.p.names.get(x) not in _FACES})
        for r in sorted(set(targets)):
            _, ta = self.p.get(r)
            prm = ta if isinstance(ta, list) else next(
                ta[k] for k in ("DATUM_TARGET", "PLACED_DATUM_TARGET_FEATURE") if k in ta)
            tf, ti, _ = self.faces(self.target_feature.get(r, []))
            own = self.usage.get(r, [])
            d.targets.append(DatumTarget(
                r, str(prm[4]) if len(prm) > 4 else "",
                None if prm[1] is None else str(prm[1]),
                face_ids=sorted(set(tf) | {x for x in own if self.p.names.get(x) in _FACES}),
                items=sorted(set(ti) | {x for x in own if self.p.names.get(x) not in _FACES})))
        return d

    # --------------------------------------------------------------- dimensions
    def dimension(self, i) -> Dimension:
        name, a = self.p.get(i)
        k = self.kinds(i)
        if name is None:  # complex: its DIMENSIONAL_SIZE or relationship part
            a = a.get("DIMENSIONAL_SIZE") or a.get("SHAPE_ASPECT_RELATIONSHIP") or []
        kind = "size" if k & _SIZES else "location"
        typ = min(k & (_SIZES | _LOCATIONS))
        if kind == "size":
            aspect = self.ref(a[0], (), "applies_to")
            dm = Dimension(i, kind, typ, None if a[1] is None else str(a[1]), None, None)
            dm.face_ids, dm.items, _ = self.faces([aspect])
        else:
            rel = self.ref(a[2], (), "relating shape aspect")
            red = self.ref(a[3], (), "related shape aspect")
            dm = Dimension(i, kind, typ, None if a[0] is None else str(a[0]), None, None)
            f1, i1, _ = self.faces([rel])
            f2, i2, _ = self.faces([red])
            dm.face_ids, dm.items = sorted(set(f1) | set(f2)), sorted(set(i1) | set(i2))
            dm.origin_faces, dm.target_faces = f1, f2  # face ids until numbered
        for sdr in self.dcr.get(i, []):
            self.dimension_values(dm, sdr)
        for r in self.pmt.get(i, []):
            self.plus_minus(dm, r)
        return dm

    def dimension_values(self, dm: Dimension, sdr):
        sdr = self.ref(Ref(sdr), ("SHAPE_DIMENSION_REPRESENTATION",), "representation")
        _, a = self.p.get(sdr)
        lims: dict = {}
        stack = list(a[1]) if isinstance(a[1], list) else []
        while stack:
            it = stack.pop(0)
            k = self.kinds(it)
            if k & {"VALUE_RANGE", "COMPOUND_REPRESENTATION_ITEM"}:
                _, ca = self.p.get(it)
                prm = ca if isinstance(ca, list) else ca.get(
                    "COMPOUND_REPRESENTATION_ITEM") or ca.get("VALUE_RANGE")
                el = prm[1].value if isinstance(prm[1], Typed) else prm[1]
                stack += list(el) if isinstance(el, list) else []
                continue
            if "DESCRIPTIVE_REPRESENTATION_ITEM" in k:
                _, da = self.p.get(it)
                if isinstance(da, list) and str(da[0]).strip().lower() == "dimensional note":
                    dm.notes.append(str(da[1]))
                    continue
            if not (k & {"MEASURE_WITH_UNIT", "MEASURE_REPRESENTATION_ITEM"} or any(
                    n.endswith("MEASURE_WITH_UNIT") for n in k)):
                self.unread.append(Unread(int(it), self.label(it), f"an item of the "
                                          f"value of dimension #{dm.id} is not read"))
                continue
            v, u, label, quals = self.measure(it)
            label = (label or "").strip().lower()
            if label in ("lower limit", "upper limit"):
                lims[label] = v
                dm.unit = dm.unit or u
            elif dm.value is None:
                dm.value, dm.unit = v, u
            else:
                self.unread.append(Unread(int(it), self.label(it), f"a second value "
                                          f"({label or 'unnamed'}) of dimension #{dm.id}"))
            if quals and dm.qualifier is None:
                dm.qualifier = quals[0]
        if lims:
            dm.limits = (lims.get("lower limit"), lims.get("upper limit"))

    def plus_minus(self, dm: Dimension, r):
        _, a = self.p.get(r)
        rng = self.ref(a[0], ("TOLERANCE_VALUE", "LIMITS_AND_FITS"), "range")
        rn, ra = self.p.get(rng)
        if rn == "TOLERANCE_VALUE":
            dm.lower = self.measure(ra[0])[0]
            dm.upper = self.measure(ra[1])[0]
        else:
            dm.fit = "".join(str(x) for x in ra[:3] if x).strip() or None


def _numbered(ids, order):
    return sorted({k for f in ids for k in order.get(f, [])})


def read_pmi(path) -> Pmi:
    """The semantic PMI of a STEP file (AP242; an AP203 / AP214 file gives what of it
    it holds): geometric tolerances, datums and dimensions with the faces they apply
    to, and what was not interpreted (see the module).

    ``path`` is a file path or a :class:`~geomkit.cad.p21.P21`.  A file without PMI
    gives an empty :class:`Pmi` (``has_pmi`` False).  Face indices follow
    :func:`geomkit.read_step` on the same file (``IgesResult.entities``); when the
    file's faces cannot be numbered (an assembly placed in a way geomkit does not
    read) ``Pmi.face_order`` says why and only ``face_ids`` are filled.

    Raises
    ------
    FileFormatError
        A missing or unreadable file; a PMI record that references a missing record,
        or a record of the wrong kind, or has missing parameters (the message names
        the record).
    """
    p = path if isinstance(path, P21) else read_p21(Path(path))
    r = _Reader(p)
    pmi = Pmi(p.source)

    def each(ids, fn, out):
        for i in ids:
            try:
                item = fn(i)
            except _Bad as exc:
                raise FileFormatError(f"{p.source} #{i} ({r.label(i)}): {exc}") from None
            except FileFormatError as exc:
                raise FileFormatError(f"{p.source} #{i} ({r.label(i)}): {exc}") from None
            except _MALFORMED as exc:
                raise FileFormatError(f"{p.source} #{i} ({r.label(i)}): a record with "
                                      "missing or mistyped parameters "
                                      f"({type(exc).__name__}: {exc})") from None
            if item is not None:
                out.append(item)

    simple = set(TOLERANCE_TYPES) | _FORMS
    tol_ids = p.of_type(*simple) + [
        i for i in p.complex_ids("GEOMETRIC_TOLERANCE") if r.kinds(i) & simple]
    each(sorted(tol_ids), r.tolerance, pmi.tolerances)
    each(p.of_type("DATUM") + [i for i in p.complex_ids("DATUM") if "DATUM" in r.kinds(i)],
         r.datum, pmi.datums)
    dims = p.of_type(*(_SIZES | _LOCATIONS)) + [
        i for i in p.complex_ids("DIMENSION") if r.kinds(i) & (_SIZES | _LOCATIONS)]
    each(sorted(dims), r.dimension, pmi.dimensions)
    by_id = {t.id: t for t in pmi.tolerances}
    for g in p.of_type("GEOMETRIC_TOLERANCE_RELATIONSHIP"):
        _, a = p.get(g)
        if isinstance(a[2], Ref) and int(a[2]) in by_id and isinstance(a[3], Ref):
            by_id[int(a[2])].related.append((str(a[0]), int(a[3])))
        else:
            pmi.unsupported.append(Unread(g, "GEOMETRIC_TOLERANCE_RELATIONSHIP",
                                          "it relates records that are not tolerances "
                                          "read here"))
    for kind, why in _UNREAD_KINDS.items():
        pmi.unsupported += [Unread(i, kind, why) for i in p.of_type(kind)]
    read_dims = {d.id for d in pmi.dimensions}
    for i in p.of_type("DIMENSIONAL_CHARACTERISTIC_REPRESENTATION", "PLUS_MINUS_TOLERANCE"):
        _, a = p.get(i)
        d = a[0] if p.names[i] != "PLUS_MINUS_TOLERANCE" else a[1]
        if not isinstance(d, Ref) or int(d) not in read_dims:
            pmi.unsupported.append(Unread(i, p.names[i], f"it gives the value of {d!r}, "
                                          "which is not a dimension read here"))
    pmi.unsupported += r.unread + _graphic_only(p)
    try:
        order, pmi.face_order = face_order(p), None
    except (Unsupported, FileFormatError, ValueError) + _MALFORMED as exc:  # stated
        order, pmi.face_order = {}, f"{type(exc).__name__}: {exc}"
    for t in pmi.tolerances:
        t.faces = _numbered(t.face_ids, order)
    for d in pmi.datums:
        d.faces = _numbered(d.face_ids, order)
        for tg in d.targets:
            tg.faces = _numbered(tg.face_ids, order)
    for m in pmi.dimensions:
        m.faces = _numbered(m.face_ids, order)
        m.origin_faces = _numbered(m.origin_faces, order)
        m.target_faces = _numbered(m.target_faces, order)
    unit = file_units(p)[0] if (p.of_type("ADVANCED_BREP_SHAPE_REPRESENTATION",
                                          "SHAPE_REPRESENTATION")) else None
    pmi.units = {"length": unit, "pmi_length": sorted(r.pmi_units["length"]),
                 "angle": sorted(r.pmi_units["angle"])}
    return pmi


def _graphic_only(p: P21) -> list[Unread]:
    """``DRAUGHTING_CALLOUT`` records no ``DRAUGHTING_MODEL_ITEM_ASSOCIATION`` links
    to a semantic item (graphic PMI only: its meaning is in the drawing, not the
    data)."""
    linked = set()
    for i in p.of_type("DRAUGHTING_MODEL_ITEM_ASSOCIATION",
                       "DRAUGHTING_MODEL_ITEM_ASSOCIATION_WITH_PLACEHOLDER"):
        _, a = p.get(i)
        if len(a) > 4 and isinstance(a[4], Ref):
            linked.add(int(a[4]))
    out = []
    for c in p.of_type("DRAUGHTING_CALLOUT"):
        _, a = p.get(c)
        parts = [int(x) for x in a[1]] if len(a) > 1 and isinstance(a[1], list) else []
        if c not in linked and not linked.intersection(parts):
            out.append(Unread(c, "DRAUGHTING_CALLOUT",
                              f"graphic PMI only ({a[0]!r}): no semantic item is linked "
                              "to it"))
    return out
