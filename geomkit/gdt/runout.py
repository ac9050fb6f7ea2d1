"""Circular and total runout about a datum axis (ISO 1101:2017 18.15-18.16, as
understood; ASME Y14.5-2018 section 12).

The part turns about the datum axis; an indicator reads, radially, the distance of
each point from the axis (``direction="radial"``) or, axially, its coordinate
along the axis (``"axial"``, a face normal to the axis).  Circular runout is the
largest full indicator movement over the sections (each section is one circle:
one axial position for radial runout, one radius for axial runout); total runout
the movement over every point at once.
"""

from __future__ import annotations

import numpy as np

from geomkit.errors import InvalidInputError
from geomkit.gdt._common import (Characteristic, check_choice, check_direction,
                                 check_points, check_tol, reject, size_of, extremes)
from geomkit.gdt.datums import DatumFrame
from geomkit.validate import as_float_array

__all__ = ["circular_runout", "total_runout"]

#: Fewest points a section of circular runout needs.
MIN_SECTION_POINTS = 3


def _axis(axis):
    if isinstance(axis, DatumFrame):
        if not axis.datums:
            raise InvalidInputError("the frame holds no datums", "axis")
        return axis.origin, axis.axes[2], axis.labels
    try:
        o, a = axis
    except (TypeError, ValueError):
        raise InvalidInputError("expected a DatumFrame or (point, direction)",
                                "axis") from None
    return as_float_array(o, "axis[0]", shape=(3,)), check_direction(a, "axis[1]"), ()


def _readings(P, o, a, direction):
    V = P - o
    t = V @ a
    r = np.linalg.norm(reject(V, a), axis=1)
    return (r, t) if direction == "radial" else (t, r)


def circular_runout(points, axis, tol, sections=None, width=None,
                    direction="radial") -> Characteristic:
    """Circular runout: the largest indicator spread within one section.

    Parameters
    ----------
    points : (n, 3) float
        Points on the toleranced surface, part coordinates.
    axis : DatumFrame or ((3,), (3,))
        The datum axis: the frame's z axis through its origin (the primary
        cylinder's axis, or the secondary's after a primary plane), or a point and a
        direction.
    tol : float > 0
    sections : (n,) int, optional
        Section id of each point.
    width : float > 0, optional
        Without ``sections``: sections are bins of this width of the axial
        coordinate (radial runout) or of the radius (axial runout), from the
        smallest value.
    direction : {"radial", "axial"}

    Returns
    -------
    Characteristic
        ``details``: ``per_section`` {id: spread}, ``worst_section``.
    """
    check_choice(direction, ("radial", "axial"), "direction")
    P = check_points(points, MIN_SECTION_POINTS, "circular runout")
    t_ = check_tol(tol)
    o, a, labels = _axis(axis)
    val, pos = _readings(P, o, a, direction)
    if sections is not None:
        ids = np.asarray(sections)
        if ids.shape != (P.shape[0],) or not np.issubdtype(ids.dtype, np.integer):
            raise InvalidInputError(f"expected ({P.shape[0]},) integers, got shape "
                                    f"{ids.shape} of {ids.dtype}", "sections")
    elif width is not None:
        w = check_tol(width, "width")
        ids = np.floor((pos - pos.min()) / w).astype(np.int64)
    else:
        raise InvalidInputError("give sections= (an id per point) or width=", "sections")
    per, worst, best = {}, None, -1.0
    for k in np.unique(ids):
        sel = np.nonzero(ids == k)[0]
        if sel.size < MIN_SECTION_POINTS:
            raise InvalidInputError(f"section {int(k)} has {sel.size} point(s); each "
                                    f"needs at least {MIN_SECTION_POINTS}", "sections")
        s = float(np.ptp(val[sel]))
        per[int(k)] = s
        if s > best:
            best, worst = s, (int(k), sel)
    sel = worst[1]
    dec = sel[extremes(val[sel], size_of(P), best)]
    return Characteristic("circular_runout", best, {"zone": t_, "direction": direction},
                          labels, best <= t_, P.shape[0], dec,
                          {"per_section": per, "worst_section": worst[0],
                           "axis_point": o, "axis_direction": a})


def total_runout(points, axis, tol, direction="radial") -> Characteristic:
    """Total runout: the indicator spread over every point (radial: the radial
    distances from the datum axis; axial: the axial coordinates).

    Parameters
    ----------
    points : (n, 3) float
    axis : DatumFrame or ((3,), (3,))
        As :func:`circular_runout`.
    tol : float > 0
    direction : {"radial", "axial"}
    """
    check_choice(direction, ("radial", "axial"), "direction")
    P = check_points(points, MIN_SECTION_POINTS, "total runout")
    t_ = check_tol(tol)
    o, a, labels = _axis(axis)
    val, _ = _readings(P, o, a, direction)
    s = float(np.ptp(val))
    return Characteristic("total_runout", s, {"zone": t_, "direction": direction}, labels,
                          s <= t_, P.shape[0], extremes(val, size_of(P), s),
                          {"range": (float(val.min()), float(val.max())),
                           "axis_point": o, "axis_direction": a})
