"""Tessellation of extreme rational surfaces: the stated bound holds.

``Mesh.max_deviation <= tol`` is a promise: the measurement behind it (a parametric
gap per sample, or where that exceeds the target the two one-sided distances) must
not overstate a sliver triangle's deviation so far that refinement cannot meet it,
and must never understate it.  Oracles: the independent sampler of
:mod:`naive` (its own projection, its own point-triangle distances) and the case's
stated truth.
"""

from __future__ import annotations

import importlib
import json
import warnings

import numpy as np
import pytest

import geomkit
from geomkit.errors import ToleranceNotMetWarning

from helpers import naive
from helpers.paths import DATA
from helpers.tesshelp import REL


def _tessellate_quiet(surfaces, tol):
    """tessellate, with a ToleranceNotMetWarning turned into a test failure."""
    with warnings.catch_warnings():
        warnings.simplefilter("error", ToleranceNotMetWarning)
        return geomkit.tessellate(surfaces, tol)


def test_sliver_weights_case_meets_its_tolerance():
    """Degree (2, 4), weight ratio ~9e5: the uv-sliver triangles near the heavy edge
    are measured within tol, and the independent sampler agrees."""
    surfaces = geomkit.load(DATA / "sliver_weights.json")
    doc = json.loads((DATA / "sliver_weights.json").read_text())
    tol = doc["truth"]["tessellate_tol"]
    mesh = _tessellate_quiet(surfaces, tol)
    assert mesh.max_deviation <= doc["truth"]["max_deviation_at_most"]
    r = naive.sample_mesh_deviation(mesh, surfaces, exact_above=tol)
    assert r["to_surface"] <= tol * REL, r["worst_to_surface"]
    assert r["to_mesh"] <= tol * REL, r["worst_to_mesh"]


def random_rational(rng, independent=False):
    """A random NURBS surface: degrees 1-3, up to 4 interior knots per direction, a
    relief of 0.3 over the unit square, and weights whose largest / smallest ratio is
    log-uniform up to 1e6.

    The weights are a smooth field (``ratio ** f`` with ``f`` a random bilinear
    function of the control point's indices plus a little jitter), as rational CAD
    surfaces have them.  ``independent=True`` draws every weight on its own instead
    (neighbours differing by the whole ratio): a much harder family, where a bilinear
    patch can need millions of cells; the suite draws it with ratios up to 1e3 and
    ``tools/stress_weights.py`` runs it at 1e6."""
    p, q = int(rng.integers(1, 4)), int(rng.integers(1, 4))
    nu, nv = int(rng.integers(p + 1, p + 5)), int(rng.integers(q + 1, q + 5))

    def knots(n, d):
        inner = np.sort(rng.uniform(0, 1, n - d - 1))
        return np.concatenate([np.zeros(d + 1), inner, np.ones(d + 1)])

    g = np.stack(np.meshgrid(np.linspace(0, 1, nu), np.linspace(0, 1, nv),
                             indexing="ij"), -1)
    P = np.concatenate([g, rng.normal(0, 0.3, (nu, nv, 1))], -1)
    P += rng.normal(0, 0.05, (nu, nv, 3))
    if independent:
        W = np.exp(rng.uniform(0, np.log(10 ** rng.uniform(0, 3)), (nu, nv)))
    else:
        c = rng.uniform(-1, 1, 4)
        f = c[0] + c[1] * g[..., 0] + c[2] * g[..., 1] + c[3] * g[..., 0] * g[..., 1]
        f = f + rng.normal(0, 0.05, f.shape)
        f = (f - f.min()) / max(np.ptp(f), 1e-12)
        W = (10 ** rng.uniform(0, 6)) ** f
    return geomkit.Surface(p, q, knots(nu, p), knots(nv, q), P, W)


N_RANDOM = 200
CHECK_EVERY = 25


def test_random_rational_surfaces_meet_their_tolerance():
    """200 random rational surfaces (smooth weight fields with ratios up to 1e6, and
    every fourth with independent weights up to 1e3), tol from 1e-3 to 1e-2 of the
    size: no triangle above tol; every 25th mesh is checked by the independent
    sampler (the measurement never understates)."""
    rng = np.random.default_rng(2026)
    over = []
    for i in range(N_RANDOM):
        s = random_rational(rng, independent=i % 4 == 3)
        tol = 10 ** rng.uniform(-3, -2) * s.size
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always", ToleranceNotMetWarning)
            mesh = geomkit.tessellate(s, tol)
        if caught or not mesh.max_deviation <= tol:
            over.append((i, mesh.max_deviation / tol))
            continue
        if i % CHECK_EVERY == 0:
            r = naive.sample_mesh_deviation(mesh, [s], n_faces=2000, n_worst=200,
                                            exact_above=tol)
            assert r["to_surface"] <= tol * REL, (i, r["worst_to_surface"])
            assert r["to_mesh"] <= tol * REL, (i, r["worst_to_mesh"])
    assert not over, f"surfaces (index, max_deviation / tol) above tol: {over}"


def test_rounds_that_run_out_warn_and_state_the_measured_value(monkeypatch):
    """If refinement cannot meet tol in its rounds, the mesh says so (a warning and
    the measured face_deviation above tol), never a silent bound it does not hold."""
    tm = importlib.import_module("geomkit.mesh.tessellate")   # the module, not the function
    monkeypatch.setattr(importlib.import_module("geomkit.mesh.cells"), "MAX_ROUNDS", 1)
    monkeypatch.setattr(tm, "GRID_CELLS", 0)        # the adaptive path
    s = geomkit.samples.load("heavy_weights")[0]
    tol = 1e-4 * s.size
    with pytest.warns(ToleranceNotMetWarning, match="above tol"):
        mesh = tm.tessellate(s, tol)
    assert mesh.max_deviation > tol
