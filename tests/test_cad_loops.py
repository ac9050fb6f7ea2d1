"""Trim loops from CAD pcurves: chaining pieces listed out of order, reversed, or on
the other side of a closed surface's seam (a torus face of a STEP part in inches came
with one pcurve a period away from its neighbours and was skipped)."""

from __future__ import annotations

import numpy as np
import pytest

from geomkit.cad.loops import Unsupported, chain, close_gaps
from geomkit.types import TrimCurve

TWO_PI = 2 * np.pi


def _loop():
    """A loop on the torus domain u in [a, a + 2 pi] (the face wraps once), v in
    [2 pi, 2.5 pi]: bottom edge, seam up, a notch at the top, top edge, seam down."""
    a = 0.0913
    P = [[1.5, TWO_PI], [a + TWO_PI, TWO_PI], [a + TWO_PI, 2.5 * np.pi],
         [6.27, 6.92], [6.16, 2.5 * np.pi], [a, 2.5 * np.pi], [a, TWO_PI], [1.5, TWO_PI]]
    return [TrimCurve.polyline([p, q]) for p, q in zip(P, P[1:])], a


def test_chain_moves_a_piece_across_the_seam():
    pieces, a = _loop()
    bad = list(pieces)
    bad[2] = TrimCurve.polyline(pieces[2].control_points - [TWO_PI, 0])  # other period
    bad[2], bad[5] = bad[5], bad[2]  # and out of order
    domain = ((a, a + TWO_PI), (TWO_PI, 2.5 * np.pi))
    with pytest.raises(Unsupported, match="apart in UV"):
        close_gaps(bad, domain, "face")
    fixed = chain(bad, TWO_PI, periods=(TWO_PI, 0.0), domain=domain)
    for c, ref in zip(fixed, pieces):
        assert np.allclose(c.control_points, ref.control_points, atol=1e-15)
    out, gaps = close_gaps(fixed, domain, "face")
    assert len(out) == len(pieces) and gaps == []


def test_chain_without_periods_keeps_pieces_in_place():
    pieces, a = _loop()
    bad = list(pieces)
    bad[2] = TrimCurve.polyline(pieces[2].control_points - [TWO_PI, 0])
    fixed = chain(bad, TWO_PI)  # reordered and reversed at most, never moved
    for c in fixed:
        assert any(np.allclose(c.control_points, b.control_points) or
                   np.allclose(c.control_points[::-1], b.control_points) for b in bad)
