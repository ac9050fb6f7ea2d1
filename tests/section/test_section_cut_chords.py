"""The chord bound on every segment of a section, chains cut by a trim included.

Every segment of every curve of real parts' mid-plane sections (and the plate with a
hole) is measured against the exact curve between its ends at 64 exact points
(densified along the curve: Newton from UV midpoints, as the trim classification
does), not only at its midpoint as the refinement measures it: within ``tol`` of the
chord."""

from __future__ import annotations

import numpy as np
import pytest
from helpers.sections import mid_plane_sections

import geomkit
from geomkit import samples
from geomkit.cad.occ import HAVE_OCP
from geomkit.section.trace import _Eval


def _seg_dist(P, A, B):
    AB = B - A
    L2 = float(AB @ AB)
    t = np.clip((P - A) @ AB / (L2 if L2 > 0 else 1.0), 0, 1)
    return np.linalg.norm(P - (A + t[:, None] * AB), axis=1)


def _worst(sec):
    """(largest deviation over tol, segments measured) over the section's segments
    whose ends lie on one surface (not joined across a seam)."""
    worst, n = 0.0, 0
    evs = {}
    for X, uv, sid, closed in zip(sec.curves, sec.uv, sec.surface_index, sec.closed):
        idx = list(range(len(X) - 1)) + ([len(X) - 1] if closed and len(X) > 2 else [])
        for i in idx:
            j = (i + 1) % len(X)
            if sid[i] != sid[j]:
                continue
            k = int(sid[i])
            ev = evs.setdefault(k, _Eval(sec.surfaces[k], sec.plane))
            s = sec.surfaces[k]
            scale = abs(sec.plane[3]) + float(np.abs(s.control_points).max())
            zsnap = 64 * np.finfo(float).eps * scale
            a, b = uv[i], uv[j]
            h = float(np.linalg.norm(b - a)) / 64
            if not h > 0:
                continue
            dense = ev.densify(np.array([a, b]), h, 0.25 * zsnap, 40)
            P = ev.points(dense)
            arc = np.linalg.norm(np.diff(P, axis=0), axis=1).sum()
            if arc > 10 * np.linalg.norm(X[j] - X[i]) + sec.tol:
                continue   # ends joined across a seam: the UV segment goes round
            d = _seg_dist(P, X[i], X[j]).max()
            worst = max(worst, d / sec.tol)
            n += 1
    return worst, n


@pytest.mark.parametrize("plane", [[0, 1, 0, -50], [1, 0.3, 0, -60], [1, -1, 0, 0]])
def test_cut_chains_on_the_plate_with_hole(plane):
    s = samples.load("plate_with_hole")[0]
    sec = geomkit.plane_section(s, plane, 1e-3)
    worst, n = _worst(sec)
    assert n and worst <= 1.0


@pytest.mark.occ
@pytest.mark.skipif(not HAVE_OCP, reason="reading STEP needs cadquery-ocp")
@pytest.mark.parametrize("part", ["ug16_io1_ap214.stp", "nx9_face_recognition_ap214.stp",
                                  "nist_ctc_05_ap203.stp", "nist_ftc_06_ap242.stp"])
def test_cut_chains_on_real_parts(part):
    """The parts of the slowest mid-planes (planar faces with holes, cylinders along
    their axes, fillets)."""
    for sec in mid_plane_sections(part):
        worst, n = _worst(sec)
        assert n and worst <= 1.0, (part, worst)
