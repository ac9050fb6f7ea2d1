"""Surfaces for the tests: the bundled samples, parameter sets, geomdl as the
independent reference evaluator and hypothesis strategies of random surfaces.

* :func:`all_surfaces` — every surface of every bundled sample case;
  :func:`surface_params` the same as pytest params, :func:`sample_surface` one of them.
* :func:`random_surfaces` — a hypothesis strategy of valid random B-spline / NURBS
  surfaces (:func:`knot_vectors` draws their knots); :func:`describe` prints a
  reproducer of a failing example.
* :func:`geomdl_eval`, :func:`geomdl_derivs` — the same surface evaluated by geomdl
  (the independent reference implementation).
* :func:`uv_samples` — parameter sets that include the domain corners, edges and the
  knot values, plus random points; :func:`distinct_knots` the knot values.
* :func:`scale` — the length scale used for relative tolerances.
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import strategies as st
from hypothesis.extra import numpy as hnp

import geomkit
from geomkit import samples

# ---------------------------------------------------------------- samples
_ALL = None


def all_surfaces():
    """[(case_name, index, Surface)] over every surface of every bundled sample."""
    global _ALL
    if _ALL is None:
        _ALL = [(name, i, s) for name in samples.names()
                for i, s in enumerate(samples.load_case(name).surfaces)]
    return list(_ALL)


def surface_params():
    """``all_surfaces()`` as pytest params with readable ids ``case[i]``."""
    return [pytest.param(name, i, s, id=f"{name}[{i}]") for name, i, s in all_surfaces()]


def sample_surface(name, index=0):
    """One surface of a bundled case (fresh object)."""
    return samples.load_case(name).surfaces[index]


def scale(surface) -> float:
    """Length scale for relative tolerances: ``surface.size``, but never below the
    magnitude of the control points (rounding errors scale with |P|, not with the
    extent; for every bundled sample this is exactly ``surface.size``) nor below 1e-300."""
    return max(surface.size, float(np.abs(surface.control_points).max()), 1e-300)


# ---------------------------------------------------------------- parameters
def distinct_knots(surface):
    """(distinct u knots in the domain, distinct v knots in the domain)."""
    (u0, u1), (v0, v1) = surface.domain
    ku = np.unique(surface.knots_u)
    kv = np.unique(surface.knots_v)
    return ku[(ku >= u0) & (ku <= u1)], kv[(kv >= v0) & (kv <= v1)]


def uv_samples(surface, n_random=40, seed=0, with_knots=True):
    """(n, 2) parameters: corners, points on each edge, all knot-value pairs (and knot
    values crossed with random values), and ``n_random`` random interior points."""
    rng = np.random.default_rng(seed)
    (u0, u1), (v0, v1) = surface.domain
    pts = [[u0, v0], [u0, v1], [u1, v0], [u1, v1]]
    t = rng.random(3)
    for a in t:
        ua = u0 + a * (u1 - u0)
        va = v0 + a * (v1 - v0)
        pts += [[ua, v0], [ua, v1], [u0, va], [u1, va]]
    if with_knots:
        ku, kv = distinct_knots(surface)
        pts += [[a, b] for a in ku for b in kv]
        pts += [[a, v0 + rng.random() * (v1 - v0)] for a in ku]
        pts += [[u0 + rng.random() * (u1 - u0), b] for b in kv]
    r = rng.random((n_random, 2))
    pts += np.column_stack([u0 + r[:, 0] * (u1 - u0), v0 + r[:, 1] * (v1 - v0)]).tolist()
    out = np.array(pts, dtype=float)
    # keep every value inside the closed domain despite rounding of a + t (b - a)
    out[:, 0] = np.clip(out[:, 0], u0, u1)
    out[:, 1] = np.clip(out[:, 1], v0, v1)
    return out


# ---------------------------------------------------------------- geomdl
def _to_unit(surface, uv):
    """geomdl normalises knot vectors to [0, 1]: map parameters accordingly."""
    (u0, u1), (v0, v1) = surface.domain
    uv = np.asarray(uv, float)
    if (u0, u1, v0, v1) == (0.0, 1.0, 0.0, 1.0):
        return uv, 1.0, 1.0
    ku, kv = surface.knots_u, surface.knots_v
    out = np.empty_like(uv)
    out[..., 0] = (uv[..., 0] - ku[0]) / (ku[-1] - ku[0])
    out[..., 1] = (uv[..., 1] - kv[0]) / (kv[-1] - kv[0])
    return np.clip(out, 0.0, 1.0), 1.0 / (ku[-1] - ku[0]), 1.0 / (kv[-1] - kv[0])


def geomdl_eval(surface, uv, g=None) -> np.ndarray:
    """geomdl's points for ``uv`` (..., 2) via ``surface.to_geomdl().evaluate_list``."""
    g = surface.to_geomdl() if g is None else g
    uv = np.asarray(uv, float)
    lead = uv.shape[:-1]
    flat, _, _ = _to_unit(surface, uv.reshape(-1, 2))
    res = g.evaluate_list([[float(a), float(b)] for a, b in flat])
    # geomdl silently drops parameters outside [0, 1]: make sure none were dropped
    assert len(res) == flat.shape[0], "geomdl dropped parameters"
    return np.asarray(res, float).reshape(lead + (3,))


def geomdl_derivs(surface, u, v, order, g=None) -> np.ndarray:
    """geomdl's ``derivatives(u, v, order)`` as an array (order+1, order+1, 3)
    (``[k, l]`` = d^(k+l) S / du^k dv^l; geomdl fills the full tensor but only the
    entries with k + l <= order are documented).  ``u``, ``v`` may be 1-D arrays, then
    the result is (n, order+1, order+1, 3)."""
    g = surface.to_geomdl() if g is None else g
    uu = np.atleast_1d(np.asarray(u, float))
    vv = np.atleast_1d(np.asarray(v, float))
    flat, su, sv = _to_unit(surface, np.column_stack([uu, vv]))
    out = np.array([g.derivatives(float(a), float(b), order=order) for a, b in flat], float)
    k = np.arange(order + 1)
    out *= (su ** k)[None, :, None, None] * (sv ** k)[None, None, :, None]
    return out[0] if np.ndim(u) == 0 and np.ndim(v) == 0 else out


# ---------------------------------------------------------------- strategies
@st.composite
def knot_vectors(draw, degree, count, unit_domain=True):
    """A clamped knot vector for ``count`` control points of ``degree``: random
    interior knots on a 1/1000 grid (so geomdl's knot normalisation, which rounds to
    18 decimals, reproduces them exactly), some repeated with multiplicity <= degree.
    With ``unit_domain=False`` the vector is mapped to a random domain [a, a + width]."""
    m = count - degree - 1  # number of interior knots
    mults = []
    while sum(mults) < m:
        mults.append(draw(st.integers(1, min(degree, m - sum(mults)))))
    values = sorted(draw(st.lists(st.integers(1, 999), min_size=len(mults),
                                  max_size=len(mults), unique=True)))
    interior = [v / 1000.0 for v, k in zip(values, mults) for _ in range(k)]
    U = np.array([0.0] * (degree + 1) + interior + [1.0] * (degree + 1))
    if not unit_domain:
        a = draw(st.floats(-50.0, 50.0))
        width = draw(st.floats(0.01, 100.0))
        U = a + width * U
    return U


@st.composite
def _random_surfaces(draw, rational, unit_domain):
    p = draw(st.integers(1, 4))
    q = draw(st.integers(1, 4))
    nu = draw(st.integers(p + 1, p + 5))
    nv = draw(st.integers(q + 1, q + 5))
    U = draw(knot_vectors(p, nu, unit_domain))
    V = draw(knot_vectors(q, nv, unit_domain))
    P = draw(hnp.arrays(np.float64, (nu, nv, 3),
                        elements=st.floats(-100.0, 100.0, allow_subnormal=False)))
    w = None
    if rational:
        logw = draw(hnp.arrays(np.float64, (nu, nv),
                               elements=st.floats(np.log(0.05), np.log(20.0))))
        w = np.exp(logw)
    return geomkit.Surface(p, q, U, V, P, w)


def random_surfaces(rational=True, unit_domain=True):
    """Hypothesis strategy of valid random surfaces: degrees 1–4 in each direction,
    control nets (degree+1 .. degree+5) per direction, clamped knot vectors with random
    interior knots (repeats of multiplicity <= degree), control points in
    [-100, 100]^3 and, when ``rational``, weights log-uniform in [0.05, 20]."""
    return _random_surfaces(rational, unit_domain)


def describe(surface) -> str:
    """A reproducer for a failing hypothesis example: ``geomkit.Surface(**...)``."""
    d = dict(degree_u=surface.degree_u, degree_v=surface.degree_v,
             knots_u=surface.knots_u.tolist(), knots_v=surface.knots_v.tolist(),
             control_points=surface.control_points.tolist(),
             weights=None if surface.weights is None else surface.weights.tolist())
    return repr(d)
