"""Trim classification of whole chains (geomkit/_kernels/section_clip.py) against the
plain path: every point of the chain densified and classified.

:func:`geomkit._kernels.section_clip.chain_side` decides from a coarse densification
whether a chain is inside its trimmed face all along, outside all along or cut, and
for a cut chain gives the densified points and their classes.  Each call plane_section
makes is checked against ``_densify`` + ``_not_outside`` (themselves checked against
the loops and ``classify_uv`` point by point in test_section_fast_paths.py): the same
side, and for a cut chain the same points and classes, bit for bit."""

from __future__ import annotations

import numpy as np
import pytest
from helpers.sections import mid_plane_sections

import geomkit
from geomkit import samples
from geomkit._kernels import section_clip as C
from geomkit.cad.occ import HAVE_OCP
from geomkit.section import clip as clip_mod, plane as plane_mod


def _checked(monkeypatch, sides):
    kernel = clip_mod._chain_side

    def both(s, ev, uv, h, zsnap):
        side, dense, inside = kernel(s, ev, uv, h, zsnap)
        ref = clip_mod._densify(ev, uv, h, zsnap)
        ref_in = clip_mod._not_outside(s, ref)
        want = C.INSIDE_ALL if ref_in.all() else C.OUTSIDE_ALL if not ref_in.any() else C.MIXED
        assert side == want
        if side == C.MIXED:
            assert np.array_equal(dense, ref) and np.array_equal(inside, ref_in)
        else:
            assert len(dense) == 0 and len(inside) == 0
        sides.append(side)
        return side, dense, inside

    monkeypatch.setattr(clip_mod, "_chain_side", both)


@pytest.mark.parametrize("plane", [[0, 1, 0, -50], [1, -1, 0, 0], [1, 0.3, 0, -60],
                                   [0, 1, 0, -0.0], [1, 0, 0, -100], [1, 0, 0, -70],
                                   [0.3, 1, 0, -120]])
def test_chain_side_on_the_plate_with_hole(monkeypatch, plane):
    """Planes through the hole, along and near the plate's edges, tangent to the hole."""
    sides = []
    _checked(monkeypatch, sides)
    s = samples.load("plate_with_hole")[0]
    geomkit.plane_section(s, plane, 1e-6)
    assert sides


def test_chain_side_sees_each_case(monkeypatch):
    """The three sides occur on the plate (a chain crossing the hole is cut)."""
    sides = []
    _checked(monkeypatch, sides)
    s = samples.load("plate_with_hole")[0]
    for plane in ([0, 1, 0, -50], [1, 0.3, 0, -60], [0, 1, 0, -10], [1, 0, 0, -5]):
        geomkit.plane_section(s, plane, 1e-6)
    assert C.MIXED in sides and C.INSIDE_ALL in sides


@pytest.mark.occ
@pytest.mark.skipif(not HAVE_OCP, reason="reading STEP needs cadquery-ocp")
@pytest.mark.parametrize("part", ["nist_ftc_07_ap242.stp", "nist_ctc_01_ap242.stp",
                                  "proe_as1_ap203.stp", "nx9_face_recognition_ap214.stp"])
def test_chain_side_on_real_parts(monkeypatch, part):
    """Mid-planes of real parts.  FTC-07 at x: a chain along a face's edge starts on
    the domain's edge, a hair outside the trim (the trim runs 5.5e-4 inside it)."""
    sides = []
    _checked(monkeypatch, sides)
    mid_plane_sections(part)
    assert C.MIXED in sides and C.INSIDE_ALL in sides


@pytest.mark.parametrize("shift", [0.0, 0.02, 0.2])
def test_fine_points_stay_by_their_coarse_segment(shift):
    """A chain given only by two points off the section curve (each projection moves
    up to its segment's length): the cut chain's points lie in the boxes of the coarse
    segments grown by FINE_MARGIN times their length, and their classes are
    classify_uv's, point by point."""
    from geomkit.nurbs.trimming import OUTSIDE
    from geomkit.section.trace import _Eval

    s = samples.load("plate_with_hole")[0]
    plane = plane_mod.as_plane([0, 1, 0, -50])
    ev = _Eval(s, plane)
    (u0, u1), (v0, v1) = s.domain
    h = clip_mod.TRIM_STEP * max(u1 - u0, v1 - v0)
    zsnap = 64 * np.finfo(float).eps * (abs(plane[3]) + np.abs(s.control_points).max())
    for uv in (np.array([[u0, 0.5 * (v0 + v1) + shift], [u1, 0.5 * (v0 + v1) - shift]]),
               np.array([[0.5 * (u0 + u1) - shift, v0], [0.5 * (u0 + u1) + shift, v1]])):
        side, pts, ins = clip_mod._chain_side(s, ev, uv, h, zsnap)
        if side != C.MIXED:
            continue
        coarse = ev.densify(uv, clip_mod.COARSE * h, 0.25 * zsnap, 40)
        a, b = coarse[:-1], coarse[1:]
        m = C.FINE_MARGIN * np.linalg.norm(b - a, axis=1)[:, None]
        lo, hi = np.minimum(a, b) - m, np.maximum(a, b) + m
        held = ((pts[:, None] >= lo[None]) & (pts[:, None] <= hi[None])).all(axis=2).any(axis=1)
        assert held.all()
        assert np.array_equal(ins, s.classify_uv(pts) != OUTSIDE)
