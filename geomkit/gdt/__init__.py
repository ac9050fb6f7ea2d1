"""GD&T on measured points: datum reference frames and ISO 1101 / ASME Y14.5
characteristics (form, orientation, location, profile, runout).

Every characteristic is a function of measured (n, 3) points returning a
:class:`Characteristic`; datum frames come from :func:`datum_frame`.  Conventions,
standard clauses and limits: ``docs/guide_gdt.md``.
"""

from __future__ import annotations

from geomkit.gdt._common import Characteristic
from geomkit.gdt.datums import (Datum, DatumFeature, DatumFrame, align_to_cad,
                                datum_frame, frame_from_axes)
from geomkit.gdt.form import circularity, cylindricity, flatness, sphericity, straightness
from geomkit.gdt.location import float_pattern, mmc_bonus, position
from geomkit.gdt.orientation import angularity, parallelism, perpendicularity
from geomkit.gdt.profile import profile_line, profile_surface
from geomkit.gdt.runout import circular_runout, total_runout

__all__ = ["Characteristic", "Datum", "DatumFeature", "DatumFrame", "datum_frame",
           "frame_from_axes", "align_to_cad",
           "flatness", "straightness", "circularity", "cylindricity", "sphericity",
           "parallelism", "perpendicularity", "angularity",
           "position", "mmc_bonus", "float_pattern",
           "profile_surface", "profile_line",
           "circular_runout", "total_runout"]
