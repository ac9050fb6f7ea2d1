"""surface_distance on continua of minima (every point of a curve or region is a
minimum) and on faces that carry an approximation error.

Oracles: analytic truths (sphere r 10 on the axis of the torus R 20, r 5 in its hole:
5; coaxial quarter cylinders r 10 / 15: 5; concentric spheres r 10 / 20: 10; the plate
with a hole and its copy 3 above: 3; the sphere 3 above the torus's plane on its
axis: sqrt(409) - 15).  Whatever the search does, the returned
interval must contain the truth with zero slack; when it says certified, it must be
at most tol wide.
"""

import math

import numpy as np
import pytest

from geomkit import samples
from geomkit.bench.distance import _moved, _scaled, continuum_cases
from geomkit.query.distance import surface_distance
from geomkit.nurbs.surface import Surface

CASES = {c[0]: c[1:] for c in continuum_cases()}


@pytest.mark.parametrize("name", sorted(CASES))
def test_continuum_interval_contains_truth(name):
    a, b, truth = CASES[name]
    r = surface_distance(a, b, tol=1e-9, max_pairs=20_000)
    assert r.lower <= truth <= r.upper                      # zero slack
    assert r.lower <= r.distance <= r.upper
    if r.certified:
        assert r.upper - r.lower <= 1e-9
        assert abs(r.distance - truth) <= 1e-9
    else:
        assert r.stats["stop"] == "max_pairs"


CERTIFIED = ("torus_sphere_axis", "coaxial_cylinders", "concentric_spheres",
             "parallel_trimmed_planes", "torus_sphere_axis_offset")


@pytest.mark.parametrize("name", CERTIFIED)
@pytest.mark.parametrize("tol", [1e-6, 1e-9])
def test_continuum_certified(name, tol):
    """The curved separators (sphere centre, axis line) are exact on these surfaces, or
    exact along the circle of minima once the torus is split across its tube only:
    certified with a small work cap."""
    a, b, truth = CASES[name]
    for x, y in ((a, b), (b, a)):                             # both orders
        r = surface_distance(x, y, tol=tol, max_pairs=2000)
        assert r.certified and r.upper - r.lower <= tol, (r.lower, r.upper, r.stats)
        assert r.lower <= truth <= r.upper                    # zero slack
        assert abs(r.distance - truth) <= tol
        assert r.stats["pairs_examined"] <= (50 if name != "torus_sphere_axis_offset"
                                             else 1000)


@pytest.mark.parametrize("max_pairs", [1, 30, 100])
def test_budget_out_stays_honest(max_pairs):
    """Sphere on the torus axis 3 above its plane (a circle of minima that needs
    splits across the tube): when the budget runs out the answer says so, and the
    interval still holds the truth."""
    a, b, truth = CASES["torus_sphere_axis_offset"]
    r = surface_distance(a, b, tol=1e-9, max_pairs=max_pairs)
    assert not r.certified and r.stats["stop"] == "max_pairs"
    assert r.lower <= truth <= r.upper
    assert r.upper - truth <= 1e-12 + 1e-9                   # the upper side is sharp


@pytest.mark.parametrize("name", ["torus_sphere_axis", "concentric_spheres"])
def test_tol_below_rounding_floor_stops_early(name):
    """A tol below the rounding floor (2 * HULL_ROUNDING * scene size, which both ends of
    the interval carry) cannot be certified: the answer says so after a bounded search
    instead of spending the whole budget (200,000 pairs, 0.3-0.5 s before), and its
    interval still holds the truth, at most twice the floor wide."""
    a, b, truth = CASES[name]
    r = surface_distance(a, b, tol=1e-15)
    floor = r.stats["rounding_floor"]
    assert 1e-15 < floor < 1e-11
    assert not r.certified and r.stats["stop"] == "certified"
    assert r.stats["pairs_examined"] < 20_000
    assert r.lower <= truth <= r.upper and r.upper - r.lower <= 2 * floor
    r9 = surface_distance(a, b, tol=1e-9)                   # above the floor: certified
    assert r9.certified and r9.lower <= truth <= r9.upper


@pytest.mark.parametrize("d", [1e-12, 1e-10, 1e-7, 0.3, 3.0])
@pytest.mark.parametrize("direction", [(1.0, 0.0, 0.0), (0.3, -0.5, 0.8)])
def test_nearly_concentric_separators_stay_sound(d, direction):
    """A separator chosen from the geometry is only nearly exact when the centres are
    off by d: the interval must still hold the analytic truth with zero slack
    (sphere r 10 moved by d inside the sphere r 20: 10 - d; inside the torus's hole:
    the distance from its centre to the core circle minus 15)."""
    sph = samples.load("sphere")[0]
    tor = samples.load("torus")[0]
    off = d * np.asarray(direction) / np.linalg.norm(direction)
    moved = _moved(sph, off)
    t_tor = math.hypot(20.0 - math.hypot(off[0], off[1]), off[2]) - 15.0
    for x, y, truth in ((moved, _scaled(sph, 2.0, 2.0, 2.0), 10.0 - d),
                        (_scaled(sph, 2.0, 2.0, 2.0), moved, 10.0 - d),
                        (moved, tor, t_tor)):
        r = surface_distance(x, y, tol=1e-9, max_pairs=20_000)
        assert r.lower <= truth <= r.upper, (d, direction, r.lower, r.upper, truth)
        if r.certified:
            assert r.upper - r.lower <= 1e-9
