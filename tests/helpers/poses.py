"""Rigid poses for the collision tests."""

from __future__ import annotations

import numpy as np


def pose(t=(0, 0, 0), R=None):
    """The 4x4 pose with rotation ``R`` (identity when None) and translation ``t``."""
    P = np.eye(4)
    if R is not None:
        P[:3, :3] = R
    P[:3, 3] = t
    return P
