"""Plane sections (Paper 2, extended) against analytic truths, brute force and OCC."""

from __future__ import annotations

import json

import numpy as np
import pytest

import geomkit
from geomkit import samples
from geomkit.errors import InvalidInputError
from geomkit.section.plane import plane_section


def _sphere():
    return samples.load("sphere")[0]


def _plane_res(sec, X):
    return np.abs(X @ sec.plane[:3] + sec.plane[3])


def _chord_check(sec, X, closed):
    """Segment lengths of a polyline (closed: including the closing segment)."""
    P = np.concatenate([X, X[:1]]) if closed else X
    return np.linalg.norm(np.diff(P, axis=0), axis=1)


# ------------------------------------------------------------- Paper 2 example
def test_paper2_wave_points_within_1e7():
    case = samples.load_case("wave_seed003")
    sec = plane_section(case.surfaces, case.truth["section_plane"], tol=1e-7)
    assert len(sec.curves) == 1 and not sec.closed[0]
    X = sec.curves[0]
    for key in ("0.5,0.5", "0.15,0.35", "0.85,0.65"):
        P = np.array(case.truth["points_on_surface"][key])
        # the truth points are given to 4-5 decimals: compare to the exact S(uv)
        S = case.surfaces[0].evaluate([[float(t) for t in key.split(",")]])[0]
        assert np.linalg.norm(S - P) < 1e-4
        # distance from the exact surface point to the section polyline (segments)
        A, B = X[:-1], X[1:]
        d = B - A
        t = np.clip(np.einsum("ij,ij->i", S - A, d) / np.einsum("ij,ij->i", d, d), 0, 1)
        dist = np.linalg.norm(A + t[:, None] * d - S, axis=1).min()
        # S lies within ~1e-8 of the plane (plane coefficients rounded in the case)
        assert dist <= 1e-7 + abs(S @ sec.plane[:3] + sec.plane[3])
    assert sec.max_residual <= 1e-10
    assert sec.max_chord_error <= 1e-7


# ------------------------------------------------------------- sphere family
def test_sphere_plane_cut_one_loop_radius_8():
    case = samples.load_case("sphere_plane_cut")
    sec = plane_section(case.surfaces[0], case.truth["section_plane"], tol=1e-6)
    assert len(sec.curves) == 1 and sec.closed == [True] and len(sec.points) == 0
    X = sec.curves[0]
    r = np.linalg.norm(X[:, :2], axis=1)
    assert np.abs(r - case.truth["section_circle_radius"]).max() <= 1e-10
    assert np.abs(X[:, 2] - 6).max() <= 1e-10
    assert np.abs(samples.analytic_residual(samples.load_case("sphere").truth["analytic"],
                                            X)).max() <= 1e-10
    # spacing by tolerance: sagitta of each chord on the exact circle <= tol
    seg = _chord_check(sec, X, True)
    sag = 8 - np.sqrt(8 ** 2 - (seg / 2) ** 2)
    assert sag.max() <= 1e-6 and sec.max_chord_error <= 1e-6
    # angles cover the full circle (no gap)
    ang = np.sort(np.arctan2(X[:, 1], X[:, 0]))
    assert np.diff(np.concatenate([ang, ang[:1] + 2 * np.pi])).max() < 0.01


@pytest.mark.parametrize("z", [10.0, -10.0])
def test_sphere_tangent_plane_isolated_point(z):
    sec = plane_section(_sphere(), [0, 0, 1, -z], tol=1e-6)
    assert len(sec.curves) == 0
    assert sec.points.shape == (1, 3)
    assert np.linalg.norm(sec.points[0] - [0, 0, z]) <= 1e-10


def test_sphere_tiny_loop_below_tangent():
    sec = plane_section(_sphere(), [0, 0, 1, -(10 - 1e-7)], tol=1e-6)
    assert len(sec.curves) == 1 and sec.closed == [True] and len(sec.points) == 0
    X = sec.curves[0]
    r_true = np.sqrt(10 ** 2 - (10 - 1e-7) ** 2)
    assert abs(r_true - 1.414e-3) < 1e-6
    assert np.abs(np.linalg.norm(X[:, :2], axis=1) - r_true).max() <= 1e-9
    assert sec.max_residual <= 1e-10


def test_sphere_plane_above_misses():
    sec = plane_section(_sphere(), [0, 0, 1, -(10 + 1e-9)])
    assert len(sec.curves) == 0 and len(sec.points) == 0


def test_sphere_tilted_planes_against_analytic_circle():
    rng = np.random.default_rng(3)
    for _ in range(4):
        n = rng.normal(size=3)
        n /= np.linalg.norm(n)
        d = rng.uniform(-9, 9)
        sec = plane_section(_sphere(), (d * n, n), tol=1e-5)
        assert len(sec.curves) == 1 and sec.closed == [True]
        X = sec.curves[0]
        assert np.abs(np.linalg.norm(X, axis=1) - 10).max() <= 1e-10
        assert np.abs(X @ n - d).max() <= 1e-10
        r = np.sqrt(100 - d * d)
        assert np.abs(np.linalg.norm(X - d * n, axis=1) - r).max() <= 1e-10


# ------------------------------------------------------------- singular / state g
def test_saddle_z0_both_lines_meet_at_crossing():
    sec = plane_section(samples.load("saddle"), [0, 0, 1, 0], tol=1e-6)
    X = np.concatenate(sec.curves)
    assert np.abs(X[:, 2]).max() <= 1e-10
    on_line = (np.abs(X[:, 0]) <= 1e-9) | (np.abs(X[:, 1]) <= 1e-9)
    assert on_line.all()
    # brute-force coverage: dense samples of both lines are within tol of the section
    t = np.linspace(-10, 10, 401)
    for line in (np.stack([t, 0 * t, 0 * t], 1), np.stack([0 * t, t, 0 * t], 1)):
        A = np.concatenate([c[:-1] for c in sec.curves])
        B = np.concatenate([c[1:] for c in sec.curves])
        d = B - A
        dd = np.einsum("ij,ij->i", d, d)
        for P in line:
            s = np.clip(((P - A) * d).sum(1) / np.where(dd > 0, dd, 1), 0, 1)
            assert np.linalg.norm(A + s[:, None] * d - P, axis=1).min() <= 1e-6
    # branches meet at the crossing point: at least two curve ends (or points) at 0
    ends = np.array([c[[0, -1]] for c in sec.curves]).reshape(-1, 3)
    pts = np.concatenate([X, ends])
    near = np.linalg.norm(pts, axis=1) <= 1e-6
    assert near.sum() >= 2


def test_crease_plane_through_c0_fold_single_curve():
    s = samples.load("crease")[0]
    sec = plane_section(s, [1, 0, 0, -20], tol=1e-6)
    assert len(sec.curves) == 1                       # not doubled
    X = sec.curves[0]
    assert np.abs(X[:, 0] - 20).max() <= 1e-10
    assert np.ptp(X[:, 2]) == pytest.approx(40, abs=1e-9)   # the whole fold line


def test_plane_along_boundary_edge_and_through_vertex():
    cyl = samples.load("cylinder_quarter")[0]
    sec = plane_section(cyl, [1, 0, 0, -10], tol=1e-6)      # the edge x = 10 (state g)
    assert len(sec.curves) == 1
    X = sec.curves[0]
    assert np.abs(X[:, 0] - 10).max() <= 1e-10 and np.abs(X[:, 1]).max() <= 1e-10
    assert np.ptp(X[:, 2]) == pytest.approx(20, abs=1e-9)
    # plane through a corner vertex only (touches the boundary at one point)
    plate = samples.load("saddle")[0]
    corner = plate.evaluate([[0.0, 0.0]])[0]
    sec = plane_section(plate, (corner, [1, 1, 0]), tol=1e-6)
    allp = np.concatenate(sec.curves + [sec.points]) if sec.curves else sec.points
    assert np.linalg.norm(allp - corner, axis=1).min() <= 1e-10


def test_torus_tangent_circles_are_curves():
    tor = samples.load("torus")[0]
    for z in (5.0, -5.0):
        sec = plane_section(tor, [0, 0, 1, -z], tol=1e-5)
        assert len(sec.curves) == 1 and sec.closed == [True]
        assert np.abs(np.linalg.norm(sec.curves[0][:, :2], axis=1) - 20).max() <= 1e-9
    sec = plane_section(tor, [1, 0, 0, 0], tol=1e-5)        # two circles r=5
    assert len(sec.curves) == 2 and all(sec.closed)


# ------------------------------------------------------------- trims, several surfaces
def test_plate_with_hole_split_by_hole():
    s = samples.load("plate_with_hole")
    sec = plane_section(s, [0, 1, 0, -50], tol=1e-6)
    assert len(sec.curves) == 2
    ends = sorted(float(x) for c in sec.curves for x in c[[0, -1], 0])
    assert ends == pytest.approx([0, 30, 70, 100], abs=1e-9)
    sec = plane_section(s, [0, 1, 0, -80], tol=1e-6)        # misses the hole
    assert len(sec.curves) == 1
    sec = plane_section(s, [1, -1, 0, 0], tol=1e-6)         # diagonal through the hole
    assert len(sec.curves) == 2
    for c in sec.curves:
        r = np.linalg.norm(c[:, :2] - 50, axis=1)
        assert r.min() >= 20 - 1e-9


def test_several_surfaces_joined():
    case = samples.load_case("sphere_pair")
    sec = plane_section(case.surfaces, [0, 1, 0, 0], tol=1e-5)
    assert len(sec.curves) == 2 and all(sec.closed)
    assert sorted(set(int(s) for c in sec.surface_index for s in np.unique(c))) == [0, 1]
    # two halves of a sphere as separate surfaces join into one loop
    sph = _sphere()
    a = geomkit.Surface(sph.degree_u, sph.degree_v, sph.knots_u, sph.knots_v,
                        sph.control_points, sph.weights)
    sec = plane_section([sph, a], [0, 0, 1, -3], tol=1e-6)
    assert len(sec.curves) >= 1 and all(sec.closed)


def test_brute_force_sign_changes_freeform():
    s = samples.load("freeform_1")[0]
    plane = np.array([0.3, 0.2, 1.0, -20.0])
    sec = plane_section(s, plane, tol=1e-6)
    n = plane[:3] / np.linalg.norm(plane[:3])
    # every grid edge with a sign change has a section point within its 3-D length
    g = np.linspace(0, 1, 81)
    U, V = np.meshgrid(g, g, indexing="ij")
    P = s.evaluate(np.stack([U.ravel(), V.ravel()], 1)).reshape(81, 81, 3)
    F = P @ n + plane[3] / np.linalg.norm(plane[:3])
    X = np.concatenate(sec.curves)
    for A, B, fa, fb in ((P[:-1], P[1:], F[:-1], F[1:]),
                         (P[:, :-1], P[:, 1:], F[:, :-1], F[:, 1:])):
        idx = np.nonzero(fa * fb < 0)
        for i, j in zip(*idx):
            m = 0.5 * (A[i, j] + B[i, j])
            L = np.linalg.norm(A[i, j] - B[i, j])
            assert np.linalg.norm(X - m, axis=1).min() <= L
    assert sec.max_residual <= 1e-10


# ------------------------------------------------------------- fit and export
def test_fit_within_tol_and_exports_round_trip(tmp_path):
    case = samples.load_case("sphere_plane_cut")
    sec = plane_section(case.surfaces[0], case.truth["section_plane"], tol=1e-4)
    fits = sec.fit(1e-4)
    assert len(fits) == 1 and fits[0].max_error <= 1e-4
    Y = fits[0].evaluate(np.linspace(0, 1, 500))
    assert np.abs(np.linalg.norm(Y[:, :2], axis=1) - 8).max() <= 2e-4
    # CSV
    from geomkit.section.export import read_csv
    p = sec.to_csv(tmp_path / "s.csv")
    curves, pts = read_csv(p)
    assert np.array_equal(curves[0], sec.curves[0])
    with pytest.raises(FileExistsError):
        sec.to_csv(tmp_path / "s.csv")
    # DXF
    import ezdxf
    p = sec.to_dxf(tmp_path / "s.dxf", fit_tol=1e-4)
    doc = ezdxf.readfile(p)
    polys = doc.modelspace().query("POLYLINE")
    assert len(polys) == 1 and polys[0].is_closed
    P = np.array([tuple(v) for v in polys[0].points()])
    assert np.abs(P - sec.curves[0]).max() <= 1e-12
    spl = doc.modelspace().query("SPLINE")
    assert len(spl) == 1
    assert np.abs(np.array(spl[0].control_points) - fits[0].control_points).max() <= 1e-12
    # geomdl JSON
    from geomdl import exchange
    p = sec.to_json(tmp_path / "s.json")
    c = exchange.import_json(str(p))[0]
    assert np.abs(np.array(c.ctrlpts)[:-1] - sec.curves[0]).max() <= 1e-12
    p = sec.to_json(tmp_path / "f.json", fit_tol=1e-4)
    c = exchange.import_json(str(p))[0]
    c.delta = 0.01
    assert np.abs(np.linalg.norm(np.array(c.evalpts)[:, :2], axis=1) - 8).max() <= 2e-4
    assert json.loads(p.read_text())["shape"]["type"] == "curve"


def test_plot_smoke():
    import matplotlib
    matplotlib.use("Agg")
    sec = plane_section(_sphere(), [0, 0, 1, -10])
    ax = sec.plot()
    assert ax is not None


# ------------------------------------------------------------- validation
@pytest.mark.parametrize("plane, field", [([0, 0, 0, 1], "plane"), ([1, 2], "plane"),
                                          ([0, 0, np.nan, 1], "plane")])
def test_bad_plane(plane, field):
    with pytest.raises(InvalidInputError) as e:
        plane_section(_sphere(), plane)
    assert e.value.field == field


def test_bad_tol_and_surface():
    with pytest.raises(InvalidInputError) as e:
        plane_section(_sphere(), [0, 0, 1, 0], tol=0)
    assert e.value.field == "tol"
    with pytest.raises(InvalidInputError) as e:
        plane_section([_sphere(), "x"], [0, 0, 1, 0])
    assert e.value.field == "surfaces[1]"


def test_coplanar_surface_reported():
    case = samples.load_case("sphere_plane_cut")
    sec = plane_section(case.surfaces, [0, 0, 1, -6], tol=1e-6)
    assert sec.coplanar == [1] and len(sec.curves) == 1


# ------------------------------------------------------------- Open CASCADE oracle
@pytest.mark.occ
def test_against_occ_section():
    occ = pytest.importorskip("geomkit.bench.oracles.occ")
    if not occ.HAVE_OCP:
        pytest.skip("OCP not installed")
    s = samples.load("freeform_1")[0]
    plane = [0.3, 0.2, 1.0, -20.0]
    sec = plane_section(s, plane, tol=1e-5)
    face = occ.make_face(s.degree_u, s.degree_v, s.knots_u, s.knots_v, s.control_points,
                         s.weights)
    polys, _ = occ.section(face, plane, deflection=1e-3)
    assert len(polys) == len(sec.curves)
    X = np.concatenate(sec.curves)
    for P in polys:  # every OCC point is near our exact curve (OCC's own error ~1e-5)
        d = np.array([np.linalg.norm(X - p, axis=1).min() for p in P[:: max(1, len(P) // 50)]])
        assert d.max() <= 0.05


# --------------------------------------------------- joining across a model's gaps
def _sheet(x0, x1, y0=0.0, y1=1.0):
    """A flat face in z = 0 over [x0, x1] x [y0, y1] (exact rational plane patch)."""
    from geomkit.cad import analytic

    return geomkit.Surface(*analytic.plane_patch([0, 0, 0], [1, 0, 0], [0, 1, 0],
                                                 x0, x1, y0, y1))


def test_a_sliver_face_is_joined_between_its_neighbours_not_bridged_over():
    """Faces A | S | B meeting exactly, S 4e-4 wide, gap 2e-3 > that width: the ends
    are joined nearest pair first, so S's piece (its points coincide with A's last and
    B's first) joins between A's and B's: one curve, nothing bridged (listed A, B, S,
    joining the first pair within the gap bridged A -> B over S, 4e-4, and left S's
    piece alone as a second curve)."""
    a, b, s = _sheet(0, 1), _sheet(1.0004, 2), _sheet(1, 1.0004)
    sec = plane_section([a, b, s], [0, 1, 0, -0.5], tol=1e-6, gap=2e-3)
    assert len(sec.curves) == 1 and sec.max_gap_bridged == 0.0   # nothing bridged
    X = sec.curves[0]
    assert np.all(np.abs(X[:, 1:] - [0.5, 0]) < 1e-12)
    assert sorted(X[:, 0])[0] == 0 and sorted(X[:, 0])[-1] == 2


@pytest.mark.parametrize("angle_deg", [30.0, 60.0])
def test_ends_are_joined_across_an_edge_the_plane_crosses_obliquely(angle_deg):
    """Two faces 1e-3 apart across the edge x = 1 (y along it); a plane whose trace on
    them makes the angle a with the edge meets the two sides 1e-3 / sin(a) apart (2e-3
    at 30 degrees, more than the gap 1.5e-3): still one curve, the jump reported."""
    a_ = np.radians(angle_deg)
    n = np.array([np.cos(a_), -np.sin(a_), 0.0])
    plane = np.append(n, -n @ [1, 0.5, 0])
    A, B = _sheet(0, 1), _sheet(1.001, 2)
    jump = 1e-3 / np.sin(a_)
    sec0 = plane_section([A, B], plane, tol=1e-6, gap=0.0)
    assert len(sec0.curves) == 2
    sec = plane_section([A, B], plane, tol=1e-6, gap=1.5e-3)
    assert len(sec.curves) == 1 and not sec.closed[0]
    assert abs(sec.max_gap_bridged - jump) < 1e-12
    # a face farther than the gap from the other's boundary is not joined
    far = plane_section([A, _sheet(1.004, 2)], plane, tol=1e-6, gap=1.5e-3)
    assert len(far.curves) == 2 and far.max_gap_bridged == 0.0
