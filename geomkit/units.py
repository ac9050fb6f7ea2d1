"""Length units of a model: names, aliases, and the DXF ``$INSUNITS`` codes.

geomkit computes in the model's own length unit and never converts; the unit is
carried as a name (``"mm"``, ``"in"``, ...) so reports can state it.  ``None`` means
the file did not say: reports then write "model units" and DXF files declare
unitless drawings (``$INSUNITS = 0``).

>>> canonical_units("Millimeters"), canonical_units("INCH"), canonical_units("µm")
('mm', 'in', 'um')
>>> dxf_insunits("mm"), dxf_insunits("in"), dxf_insunits(None)
(4, 1, 0)
>>> unit_label(None)
'model units'
"""

from __future__ import annotations

from geomkit.errors import InvalidInputError

__all__ = ["UNITS", "canonical_units", "unit_label", "dxf_insunits"]

UNITS = {  # name: (DXF $INSUNITS code, aliases)
    "in": (1, ("inch", "inches", '"')),
    "ft": (2, ("foot", "feet")),
    "mi": (3, ("mile", "miles")),
    "mm": (4, ("millimeter", "millimeters", "millimetre", "millimetres")),
    "cm": (5, ("centimeter", "centimeters", "centimetre", "centimetres")),
    "m": (6, ("meter", "meters", "metre", "metres")),
    "km": (7, ("kilometer", "kilometers", "kilometre", "kilometres")),
    "uin": (8, ("microinch", "microinches", "µin")),
    "mil": (9, ("mils", "thou")),
    "um": (13, ("µm", "μm", "micron", "microns", "micrometer", "micrometers",
                "micrometre", "micrometres")),
}
"""Known length units: canonical name -> (DXF ``$INSUNITS`` code, aliases)."""

_ALIASES = {a.lower(): name for name, (_, al) in UNITS.items() for a in (name,) + al}


def canonical_units(text: str) -> str:
    """The canonical name of a length unit (case and common spellings ignored).

    Raises
    ------
    InvalidInputError
        Not a known length unit (the message lists them).
    """
    key = str(text).strip().lower()
    if key in _ALIASES:
        return _ALIASES[key]
    raise InvalidInputError(f"unknown length unit {text!r}; use one of "
                            f"{', '.join(UNITS)}", "units")


def unit_label(units: str | None) -> str:
    """``"mm"``, or ``"model units"`` when unknown (None or blank)."""
    return units.strip() if units and units.strip() else "model units"


def dxf_insunits(units: str | None) -> int:
    """The DXF ``$INSUNITS`` code of ``units`` (0, unitless, when unknown)."""
    if not units:
        return 0
    try:
        return UNITS[canonical_units(units)][0]
    except InvalidInputError:
        return 0
