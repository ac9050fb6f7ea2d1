"""Sections shared by the section tests."""

from __future__ import annotations

import numpy as np

import geomkit
from helpers.paths import DATA


def mid_plane_sections(part: str) -> list:
    """``plane_section`` of the real part ``tests/data/parts/<part>`` at its three
    axis-aligned mid-planes (chord tolerance 1e-4 x its size, joined within the
    file's edge gap)."""
    from geomkit.cad.step import read_step

    case = read_step(DATA / "parts" / part)
    S = case.surfaces
    B = np.array([s.bounds for s in S])
    lo, hi = B[:, 0].min(axis=0), B[:, 1].max(axis=0)
    size = float(np.linalg.norm(hi - lo))
    return [geomkit.plane_section(S, [*np.eye(3)[ax], -0.5 * (lo[ax] + hi[ax])],
                                  1e-4 * size, gap=case.edge_gap or 0.0)
            for ax in range(3)]
