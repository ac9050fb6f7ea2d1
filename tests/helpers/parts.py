"""The real parts of ``tests/data/parts`` as the tessellation tests take them."""

from __future__ import annotations

import warnings

import numpy as np

from helpers.paths import DATA


def part_surfaces(name: str):
    """``(surfaces, size)``: the surfaces of part ``name`` (read without the cache) and
    the diagonal of their control nets' box (the tests' tolerances are fractions of it)."""
    from geomkit.cad.step import read_step

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        S = read_step(DATA / "parts" / name, cache=False).surfaces
    B = np.array([s.bounds for s in S])
    return S, float(np.linalg.norm(B[:, 1].max(0) - B[:, 0].min(0)))
