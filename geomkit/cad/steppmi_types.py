"""The result types of :func:`geomkit.cad.steppmi.read_pmi`: plain records of a STEP
file's semantic PMI (geometric tolerances, datums, dimensions) and of what the reader
left uninterpreted.

Every item keeps the id of the record it was read from (``id``: ``#id`` in the
file), the value and the unit as the file writes them (``unit``: ``"mm"``, ``"in"``,
``"deg"``, ...; :attr:`Tolerance.value_mm` converts lengths) and the faces it applies
to twice: ``face_ids`` the ``ADVANCED_FACE`` record ids, ``faces`` their indices in
:func:`geomkit.read_step`'s face order (``IgesResult.entities``; equal to the index in
``surfaces`` when no face was skipped).
"""

from __future__ import annotations

from dataclasses import asdict, dataclass, field

__all__ = [
    "MM_PER_UNIT",
    "TOLERANCE_TYPES",
    "Datum",
    "DatumRef",
    "DatumTarget",
    "Dimension",
    "Pmi",
    "Tolerance",
    "Unread",
]

MM_PER_UNIT = {"mm": 1.0, "m": 1000.0, "cm": 10.0, "um": 1e-3, "km": 1e6,
               "in": 25.4, "ft": 304.8, "mil": 0.0254, "uin": 2.54e-5}
"""Millimetres per length unit, for the unit names the reader gives."""

# the AP242 entity names the reader knows (geomkit.cad.steppmi)
TOLERANCE_TYPES = {
    "FLATNESS_TOLERANCE": "flatness", "STRAIGHTNESS_TOLERANCE": "straightness",
    "ROUNDNESS_TOLERANCE": "roundness", "CYLINDRICITY_TOLERANCE": "cylindricity",
    "LINE_PROFILE_TOLERANCE": "line_profile",
    "SURFACE_PROFILE_TOLERANCE": "surface_profile",
    "PARALLELISM_TOLERANCE": "parallelism",
    "PERPENDICULARITY_TOLERANCE": "perpendicularity",
    "ANGULARITY_TOLERANCE": "angularity", "POSITION_TOLERANCE": "position",
    "CONCENTRICITY_TOLERANCE": "concentricity", "COAXIALITY_TOLERANCE": "coaxiality",
    "SYMMETRY_TOLERANCE": "symmetry", "CIRCULAR_RUNOUT_TOLERANCE": "circular_runout",
    "TOTAL_RUNOUT_TOLERANCE": "total_runout"}
"""Entity name -> the ``Tolerance.type`` it gives."""

_FORMS = {"GEOMETRIC_TOLERANCE", "GEOMETRIC_TOLERANCE_WITH_DATUM_REFERENCE",
          "GEOMETRIC_TOLERANCE_WITH_MODIFIERS", "GEOMETRIC_TOLERANCE_WITH_DEFINED_UNIT",
          "GEOMETRIC_TOLERANCE_WITH_DEFINED_AREA_UNIT",
          "GEOMETRIC_TOLERANCE_WITH_MAXIMUM_TOLERANCE",
          "UNEQUALLY_DISPOSED_GEOMETRIC_TOLERANCE", "MODIFIED_GEOMETRIC_TOLERANCE"}
_SIZES = {"DIMENSIONAL_SIZE", "ANGULAR_SIZE", "DIMENSIONAL_SIZE_WITH_PATH",
          "DIMENSIONAL_SIZE_WITH_DATUM_FEATURE"}
_LOCATIONS = {"DIMENSIONAL_LOCATION", "ANGULAR_LOCATION", "DIMENSIONAL_LOCATION_WITH_PATH",
              "DIRECTED_DIMENSIONAL_LOCATION", "DIMENSIONAL_LOCATION_WITH_DATUM_FEATURE"}
_TARGETS = {"DATUM_TARGET", "PLACED_DATUM_TARGET_FEATURE"}
_DECOMPOSE = ("SHAPE_ASPECT_RELATIONSHIP", "SHAPE_ASPECT_DERIVING_RELATIONSHIP")
_USAGES = ("GEOMETRIC_ITEM_SPECIFIC_USAGE", "ITEM_IDENTIFIED_REPRESENTATION_USAGE")
_FACES = {"ADVANCED_FACE", "FACE_SURFACE"}
_ZONE_DEFS = {"PROJECTED_ZONE_DEFINITION", "RUNOUT_ZONE_DEFINITION",
              "NON_UNIFORM_ZONE_DEFINITION", "PROJECTED_ZONE_DEFINITION_WITH_OFFSET",
              "TOLERANCE_ZONE_DEFINITION"}
_UNREAD_KINDS = {
    "TOLERANCE_ZONE_WITH_DATUM": "a tolerance zone with datum is not read",
    "DIMENSION_RELATED_TOLERANCE_ZONE_ELEMENT": "a dimension-related zone element is "
                                                "not read",
    "GEOMETRIC_TOLERANCE_AUXILIARY_CLASSIFICATION": "an auxiliary classification is "
                                                    "not read",
    "CONTACTING_FEATURE": "a contacting feature is not read"}
_ASPECT_MODIFIERS = {"ALL_AROUND_SHAPE_ASPECT": "all_around",
                     "ALL_OVER_SHAPE_ASPECT": "all_over", "BETWEEN_SHAPE_ASPECT": "between"}
"""Toleranced shape aspects that stand for a modifier of the tolerance (all around, all
over, between), as the CAx-IF practices write them."""
_DIAMETER_FORMS = {"cylindrical or circular", "within a circle", "within a cylinder"}
_SI_LENGTH = {"MILLI": "mm", "CENTI": "cm", "MICRO": "um", "KILO": "km", None: "m"}
_NAMED = {"inch": "in", "in": "in", "foot": "ft", "mil": "mil", "microinch": "uin",
          "millimetre": "mm", "millimeter": "mm", "metre": "m", "meter": "m",
          "centimetre": "cm", "degree": "deg", "degrees": "deg", "radian": "rad"}


def _mm(value, unit):
    if value is None or unit not in MM_PER_UNIT:
        return None
    return value * MM_PER_UNIT[unit]


@dataclass
class DatumRef:
    """One compartment of a datum system (primary, secondary, ... in list order).

    ``label`` is the datum letter, or the letters of a common datum joined by ``-``
    (``"A-B"``); ``datums`` the ``DATUM`` record ids; ``modifiers`` the datum
    reference modifiers in lower case (``"maximum_material_requirement"``, ...; a
    modifier with a value as ``"name=value unit"``)."""

    id: int
    label: str
    datums: list[int]
    modifiers: list[str] = field(default_factory=list)


@dataclass
class Tolerance:
    """A geometric tolerance (``GEOMETRIC_TOLERANCE`` and its subtypes).

    ``type`` is the characteristic in lower case without ``_tolerance``
    (``"flatness"``, ``"position"``, ``"surface_profile"``, ...); ``value`` the
    zone magnitude in ``unit``; ``zone`` the tolerance zone form (``"cylindrical or
    circular"`` is a diameter zone: ``diameter`` True; ``"spherical"`` also sets
    ``spherical``); ``modifiers`` the ``GEOMETRIC_TOLERANCE_MODIFIER`` values in
    lower case (``"maximum_material_requirement"``, ``"free_state"``, ...);
    ``datums`` the datum system in order; ``whole_part`` when it applies to the
    product's whole shape (no faces); ``items`` the geometric items it applies to that
    are not faces (edges, curves); ``extra`` the values of the complex-entity forms
    (``"unit_size"``, ``"area_type"``, ``"displacement"``, ``"maximum_upper_tolerance"``,
    ``"projected_length"``, each with its unit); ``related`` the tolerance
    relationships (``("composite", other id)``) it is the relating one of."""

    id: int
    type: str
    name: str
    value: float | None
    unit: str | None
    zone: str | None = None
    diameter: bool = False
    spherical: bool = False
    modifiers: list[str] = field(default_factory=list)
    datums: list[DatumRef] = field(default_factory=list)
    faces: list[int] = field(default_factory=list)
    face_ids: list[int] = field(default_factory=list)
    items: list[int] = field(default_factory=list)
    whole_part: bool = False
    extra: dict = field(default_factory=dict)
    related: list[tuple] = field(default_factory=list)

    @property
    def value_mm(self) -> float | None:
        """The zone magnitude in millimetres (None for a unit the reader does not
        know)."""
        return _mm(self.value, self.unit)

    @property
    def datum_labels(self) -> list[str]:
        return [d.label for d in self.datums]


@dataclass
class DatumTarget:
    """A ``DATUM_TARGET`` / ``PLACED_DATUM_TARGET_FEATURE``: ``label`` its target id
    (``"1"``), ``kind`` its description (``"point"``, ``"line"``, ``"area"``, ...),
    ``faces`` those of the feature it sits on, ``items`` its own geometry."""

    id: int
    label: str
    kind: str | None
    faces: list[int] = field(default_factory=list)
    face_ids: list[int] = field(default_factory=list)
    items: list[int] = field(default_factory=list)


@dataclass
class Datum:
    """A ``DATUM``: its letter, its datum features (record ids) and their faces, its
    datum targets."""

    id: int
    label: str
    features: list[int] = field(default_factory=list)
    faces: list[int] = field(default_factory=list)
    face_ids: list[int] = field(default_factory=list)
    items: list[int] = field(default_factory=list)
    targets: list[DatumTarget] = field(default_factory=list)


@dataclass
class Dimension:
    """A dimension: ``kind`` ``"size"`` (``DIMENSIONAL_SIZE``, ``ANGULAR_SIZE``, ...)
    or ``"location"`` (``DIMENSIONAL_LOCATION``, ``ANGULAR_LOCATION``, ...);
    ``type`` the entity name; ``name`` the file's label (``"diameter"``,
    ``"radius"``, ``"linear distance"``, ...).

    ``value`` is the nominal value in ``unit`` (None when the file gives none: a
    dimension without a ``DIMENSIONAL_CHARACTERISTIC_REPRESENTATION``);
    ``lower`` / ``upper`` the plus/minus deviations as written (``lower`` usually
    negative) from ``PLUS_MINUS_TOLERANCE`` / ``TOLERANCE_VALUE``; ``limits``
    ``(lower limit, upper limit)`` when the file gives limits; ``fit`` an ISO 286
    fit (``LIMITS_AND_FITS``: ``"H7"``); ``qualifier`` ``"maximum"`` /
    ``"minimum"`` / ``"average"``; ``notes`` the dimensional notes (``"auxiliary"``:
    a reference dimension, ``"theoretical"``: a basic one).  ``faces`` are those of the feature (a size) or
    of both features (a location: ``origin_faces`` from the relating, ``target_faces``
    from the related shape aspect)."""

    id: int
    kind: str
    type: str
    name: str | None
    value: float | None
    unit: str | None
    lower: float | None = None
    upper: float | None = None
    limits: tuple | None = None
    fit: str | None = None
    qualifier: str | None = None
    notes: list[str] = field(default_factory=list)
    faces: list[int] = field(default_factory=list)
    face_ids: list[int] = field(default_factory=list)
    origin_faces: list[int] = field(default_factory=list)
    target_faces: list[int] = field(default_factory=list)
    items: list[int] = field(default_factory=list)

    @property
    def value_mm(self) -> float | None:
        return _mm(self.value, self.unit)


@dataclass
class Unread:
    """A PMI record the reader did not interpret, and why."""

    id: int
    entity: str
    reason: str


@dataclass
class Pmi:
    """The semantic PMI of a STEP file (:func:`geomkit.cad.steppmi.read_pmi`).

    ``units``: ``"length"`` the geometry's length unit, ``"pmi_length"`` /
    ``"angle"`` the units the PMI values use (a file may give its geometry in
    millimetres and its tolerances in inches, as NIST FTC-06 does);
    ``face_order``: None when the faces were numbered in ``read_step``'s order, else
    why they could not be (then ``faces`` are empty and ``face_ids`` hold the
    records)."""

    source: str
    tolerances: list[Tolerance] = field(default_factory=list)
    datums: list[Datum] = field(default_factory=list)
    dimensions: list[Dimension] = field(default_factory=list)
    unsupported: list[Unread] = field(default_factory=list)
    units: dict = field(default_factory=dict)
    face_order: str | None = None

    @property
    def has_pmi(self) -> bool:
        """Whether the file holds any PMI: semantic items, read or not, or graphic
        PMI without semantics (listed in ``unsupported``)."""
        return bool(self.tolerances or self.datums or self.dimensions or self.unsupported)

    def counts(self) -> dict:
        """``{"tolerances": n, "datums": n, "dimensions": n, "unsupported": n}``."""
        return {"tolerances": len(self.tolerances), "datums": len(self.datums),
                "dimensions": len(self.dimensions), "unsupported": len(self.unsupported)}

    def to_dict(self) -> dict:
        """Plain JSON-ready data (lists, dicts, numbers, strings, None)."""
        d = asdict(self)
        d["has_pmi"] = self.has_pmi
        for t, src in zip(d["tolerances"], self.tolerances):
            t["value_mm"] = src.value_mm
            t["related"] = [list(r) for r in t["related"]]
        for m, src in zip(d["dimensions"], self.dimensions):
            m["value_mm"] = src.value_mm
            m["limits"] = None if m["limits"] is None else list(m["limits"])
        return d
