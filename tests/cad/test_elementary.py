"""geomkit's own exact patches of Open CASCADE's elementary surfaces, and pcurves
carried onto them, against OCC's own evaluation."""

from __future__ import annotations

import math

import numpy as np
import pytest

from geomkit.cad.occ import HAVE_OCP
from geomkit.nurbs.trimming import evaluate_trim_curve
from geomkit.nurbs.surface import TrimCurve

pytestmark = [pytest.mark.occ,
              pytest.mark.skipif(not HAVE_OCP, reason="needs cadquery-ocp")]

TWO_PI = 2 * math.pi


def _frame(direct=True):
    from OCP.gp import gp_Ax3, gp_Dir, gp_Pnt

    z = np.array([0.3, -0.5, 0.8])
    x = np.cross(z, [1.0, 0.0, 0.0])
    ax = gp_Ax3(gp_Pnt(1.5, -2.0, 0.7), gp_Dir(*z), gp_Dir(*x))
    if not direct:
        ax.YReverse()
    return ax


def _surfaces():
    from OCP.Geom import (Geom_ConicalSurface, Geom_CylindricalSurface, Geom_Plane,
                          Geom_RectangularTrimmedSurface, Geom_SphericalSurface,
                          Geom_ToroidalSurface)

    out = []
    for direct in (True, False):
        ax = _frame(direct)
        out += [
            ("plane", Geom_Plane(ax), (-3.0, 4.0, -1.0, 2.5)),
            ("cylinder", Geom_CylindricalSurface(ax, 7.0), (0.3, 4.0, -2.0, 5.0)),
            ("cone", Geom_ConicalSurface(ax, 0.4, 2.0), (1.0, 6.0, -1.0, 3.0)),
            ("sphere", Geom_SphericalSurface(ax, 3.0), (0.0, TWO_PI, -1.2, 1.5)),
            ("torus", Geom_ToroidalSurface(ax, 5.0, 1.5), (0.5, 5.5, 0.0, TWO_PI)),
        ]
        cyl = Geom_CylindricalSurface(ax, 7.0)
        u0 = TWO_PI - 3.5e-9  # the Inventor face: one whole turn, just short of 2 pi
        out.append(("turn", Geom_RectangularTrimmedSurface(cyl, u0, u0 + TWO_PI, 25.25, 29.45),
                    (u0, u0 + TWO_PI, 25.25, 29.45)))
    return out


def _occ(surface, uv):
    from geomkit.cad.occ import xyz

    return np.array([xyz(surface.Value(float(u), float(v))) for u, v in uv])


def _mapped(patch, uv):
    s, fu, fv, _ = patch
    return np.column_stack([uv[:, 0] if fu is None else fu(uv[:, 0]),
                            uv[:, 1] if fv is None else fv(uv[:, 1])])


@pytest.mark.parametrize("k", range(12))
def test_patch_is_occs_surface(k):
    from geomkit.cad.elementary import elementary_patch

    name, g, b = _surfaces()[k]
    patch = elementary_patch(g, b, name)
    s, _, _, err = patch
    rng = np.random.default_rng(k)
    uv = np.column_stack([rng.uniform(b[0], b[1], 200), rng.uniform(b[2], b[3], 200)])
    d = np.linalg.norm(s.evaluate(_mapped(patch, uv)) - _occ(g, uv), axis=1).max()
    assert d <= 1e-12 * 100 and err <= 1e-12 * 100, (name, d, err)
    assert s.domain == ((b[0], b[1]), (b[2], b[3]))


@pytest.mark.parametrize("k", [1, 2, 3, 4, 5])
def test_carried_pcurve_lies_on_occs_image(k):
    """A pcurve that is not an iso-line (a diagonal cubic across the range) is carried
    through the angle maps; its points land where OCC's surface puts the original's,
    within the stated error."""
    from geomkit.cad.elementary import carry_pcurve, elementary_patch

    name, g, b = _surfaces()[k]
    patch = elementary_patch(g, b, name)
    u0, u1, v0, v1 = b
    P = np.array([[u0 + 0.1 * (u1 - u0), v0 + 0.2 * (v1 - v0)],
                  [u0 + 0.6 * (u1 - u0), v0 + 0.1 * (v1 - v0)],
                  [u0 + 0.3 * (u1 - u0), v0 + 0.9 * (v1 - v0)],
                  [u0 + 0.9 * (u1 - u0), v0 + 0.7 * (v1 - v0)]])
    c = TrimCurve.create(3, [0, 0, 0, 0, 1, 1, 1, 1], P)
    m, err = carry_pcurve(c, patch)
    assert err < 1e-7
    t = np.linspace(0.0, 1.0, 101)
    ref = _occ(g, evaluate_trim_curve(c, t)[:, 0, :])   # map_pcurve keeps the parameter
    got = patch[0].evaluate(evaluate_trim_curve(m, t)[:, 0, :])
    assert np.linalg.norm(got - ref, axis=1).max() <= err + 1e-10


def test_iso_lines_are_carried_exactly():
    from geomkit.cad.elementary import carry_pcurve, elementary_patch

    name, g, b = _surfaces()[3]  # sphere: both parameters are angles
    patch = elementary_patch(g, b, name)
    c = TrimCurve.polyline([[0.5, -1.0], [0.5, 1.2]])
    m, err = carry_pcurve(c, patch)
    assert err == patch[3]
    ends = _occ(g, np.array([[0.5, -1.0], [0.5, 1.2]]))
    got = patch[0].evaluate(m.control_points[[0, -1]])
    assert np.abs(got - ends).max() < 1e-12


def test_patch_covers_the_pcurves_control_points():
    """A rational arc pcurve bulges beyond the face's UV bounds through its middle
    control point (EUCLID screw): the patch is widened to hold it, so the arc is kept
    whole instead of its control point being clipped."""
    from geomkit.cad.elementary import elementary_patch

    name, g, b = _surfaces()[0]  # plane
    s = elementary_patch(g, b, name, box=(b[0] - 0.1, b[2], b[1], b[3] + 0.2))[0]
    assert s.domain == ((b[0] - 0.1, b[1]), (b[2], b[3] + 0.2))
    # angles never exceed one turn, a sphere never passes its poles
    name, g, b = _surfaces()[3]
    s = elementary_patch(g, b, name, box=(-0.1, -1.7, TWO_PI + 0.1, 1.6))[0]
    assert s.domain == ((0.0, TWO_PI), (-math.pi / 2, math.pi / 2))


def _bspline_curve():
    from OCP.Geom import Geom_BSplineCurve

    from geomkit.cad.occ import array1_double, array1_int, gp_pnt, ocp_array

    P = [(3.0, 0.0, 0.0), (4.0, 1.0, 1.0), (3.5, 0.5, 2.5), (5.0, -1.0, 3.0), (4.0, 0.0, 4.5)]
    poles = ocp_array("Array1_gp_Pnt")(1, len(P))
    for i, p in enumerate(P):
        poles.SetValue(i + 1, gp_pnt(p))
    w = array1_double([1.0, 0.7, 1.3, 1.0, 0.9])
    return Geom_BSplineCurve(poles, w, array1_double([0.0, 1.5, 4.0]), array1_int([4, 1, 4]), 3)


def _swept():
    from OCP.Geom import Geom_SurfaceOfLinearExtrusion, Geom_SurfaceOfRevolution
    from OCP.gp import gp_Ax1, gp_Dir, gp_Pnt

    c = _bspline_curve()
    return [("extrusion", Geom_SurfaceOfLinearExtrusion(c, gp_Dir(0.2, -0.3, 1.0)),
             (0.5, 3.5, -2.0, 6.0)),
            ("revolution", Geom_SurfaceOfRevolution(c, gp_Ax1(gp_Pnt(0.5, 0.2, 0), gp_Dir(0.1, 0, 1))),
             (0.2, 5.0, 0.3, 3.9))]


@pytest.mark.parametrize("k", [0, 1])
def test_swept_bspline_keeps_the_curve_parameter(k):
    """Extrusion and revolution of a rational B-spline: the patch is OCC's surface,
    and a pcurve across it is carried (only the angle is mapped)."""
    from geomkit.cad.elementary import carry_pcurve, elementary_patch

    name, g, b = _swept()[k]
    patch = elementary_patch(g, b, name)
    s, fu, fv, err = patch
    assert fv is None and (fu is None) == (name == "extrusion")
    rng = np.random.default_rng(k)
    uv = np.column_stack([rng.uniform(b[0], b[1], 200), rng.uniform(b[2], b[3], 200)])
    d = np.linalg.norm(s.evaluate(_mapped(patch, uv)) - _occ(g, uv), axis=1).max()
    assert d <= 1e-11 and err <= 1e-11, (name, d, err)
    u0, u1, v0, v1 = b
    c = TrimCurve.create(2, [0, 0, 0, 1, 1, 1], [[u0 + 0.1, v0 + 0.1], [u1, v0 + 0.5],
                                                 [u0 + 0.4, v1 - 0.1]])
    m, e = carry_pcurve(c, patch)
    t = np.linspace(0.0, 1.0, 51)
    got = s.evaluate(evaluate_trim_curve(m, t)[:, 0, :])
    assert np.linalg.norm(got - _occ(g, evaluate_trim_curve(c, t)[:, 0, :]), axis=1).max() \
        <= e + 1e-10


def test_cone_face_ending_at_its_apex():
    """A cone face whose range ends at the apex (to rounding, NIST CTC-05 / FTC-07):
    widened to its pcurves, it stays on its own side of the apex."""
    from OCP.Geom import Geom_ConicalSurface

    from geomkit.cad.elementary import elementary_patch

    g = Geom_ConicalSurface(_frame(), 0.5, 2.0)
    apex = -2.0 / math.sin(0.5)
    b = (0.0, math.pi, apex - 1e-14, apex + 1.5)
    s = elementary_patch(g, b, "cone", box=(0.0, apex - 0.2, math.pi, apex + 1.6))[0]
    (_, _), (v0, v1) = s.domain
    assert v0 == pytest.approx(apex, abs=1e-12) and v1 == apex + 1.6


def test_other_surfaces_are_left_to_occ():
    from OCP.Geom import Geom_SurfaceOfLinearExtrusion
    from OCP.GC import GC_MakeCircle
    from OCP.gp import gp_Ax2, gp_Dir, gp_Pnt

    from geomkit.cad.elementary import elementary_patch

    circle = GC_MakeCircle(gp_Ax2(gp_Pnt(0, 0, 0), gp_Dir(0, 0, 1)), 2.0).Value()
    ext = Geom_SurfaceOfLinearExtrusion(circle, gp_Dir(0, 0.2, 1))
    assert elementary_patch(ext, (0.0, 1.0, 0.0, 1.0), "x") is None
