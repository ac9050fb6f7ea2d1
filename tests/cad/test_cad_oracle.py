"""Real CAD models no one here wrote, against Open CASCADE and closed forms.

* Exact rational primitives (geomkit.cad.analytic): cylinder, cone, sphere, torus,
  revolved arc, ruled lines, plane hold their closed forms to 1e-12 x size.
* pyiges' impeller.igs: every face read (== OCC's face count); its 30 surfaces of
  revolution (entity 120, cones) hold their closed form; distances of random points
  near the model equal OCC's BRepExtrema_DistShapeShape within 1e-6, or, where OCC's
  foot is on an edge, within the file's edge gaps (OCC measures to the edges' own 3-D
  curves, which lie up to the model gap off the surfaces); where geomkit is lower, its
  foot is a point of the face; where geomkit is higher, the multi-face search of
  project_points missed a face (projection engine) and the per-face minimum agrees.
* Sections of the impeller at 11 planes over all three axes (and of the STEP-read
  impeller at 2) match OCC's BRepAlgoAPI_Section both ways within tol + model gap, and
  are closed where OCC's wires are (tests/helpers/occ_oracle.py; what it found about OCC's own
  section: docs/section.md).
* The impeller written to STEP by OCC (in the test): every face read, same distances.
* A STEP round trip of OCP-made box, cylinder, cone, sphere, torus and a filleted box.
* sample.igs (points only), an empty file: clear errors.
"""

from __future__ import annotations

import math
import os
from pathlib import Path

import numpy as np
import pytest

import geomkit
from geomkit.cad import analytic
from geomkit.errors import FileFormatError, InvalidInputError
from geomkit.bench.oracles.occ import HAVE_OCP
from geomkit.nurbs.surface import Surface

pyiges = pytest.importorskip("pyiges")
from pyiges import examples  # noqa: E402

from geomkit.cad.iges.reader import read_iges  # noqa: E402

from helpers.occ_oracle import (SECTION_PLANES, STEP_PLANES, _check_section,  # noqa: E402
                                _occ_distances, _occ_faces, _occ_section)

IMPELLER = Path(examples.impeller)
SAMPLE = Path(examples.impeller).with_name("sample.igs")
needs_occ = pytest.mark.skipif(not HAVE_OCP, reason="needs cadquery-ocp")


def _grid(s, n=9):
    (a, b), (c, d) = s.domain
    t = np.linspace(0, 1, n)
    return np.array([[a + (b - a) * x, c + (d - c) * y] for x in t for y in t])


def _surf(args):
    return Surface(*args)


# ------------------------------------------------------------ closed forms
def test_arc_parameter_maps_are_inverse_and_exact():
    for t0, t1 in ((0.0, 2 * math.pi), (0.3, 1.2), (-1.0, 3.5)):
        th = np.linspace(t0, t1, 101)
        s = analytic.angle_to_param(th, t0, t1)
        assert np.abs(analytic.param_to_angle(s, t0, t1) - th).max() < 1e-13
        p, U, Pw = analytic.arc_curve([1, 2, 3], [1, 0, 0], [0, 1, 0], 2.0, t0, t1)
        from geomkit.nurbs.surface import TrimCurve
        from geomkit.nurbs.trimming import evaluate_trim_curve
        c = TrimCurve.create(p, U, Pw[:, :2] / Pw[:, 3:], Pw[:, 3])
        X = evaluate_trim_curve(c, s)[:, 0, :]
        assert np.abs(X - np.column_stack([1 + 2 * np.cos(th), 2 + 2 * np.sin(th)])).max() < 1e-13


@pytest.mark.parametrize("kind", ["cylinder", "cone", "sphere", "torus", "revolved arc",
                                  "ruled", "plane"])
def test_analytic_surfaces_hold_their_closed_forms(kind):
    axis_p, axis_d = np.array([1.0, -2.0, 0.5]), np.array([0.0, 0.0, 1.0])
    if kind == "cylinder":
        s = _surf(analytic.revolve(analytic.line_curve([4, -2, 0.5], [4, -2, 7.5]),
                                   axis_p, axis_d, 0, 2 * math.pi))
        f = lambda X: np.hypot(X[:, 0] - 1, X[:, 1] + 2) - 3  # noqa: E731
    elif kind == "cone":
        s = _surf(analytic.revolve(analytic.line_curve([2, -2, 0.5], [5, -2, 6.5]),
                                   axis_p, axis_d, 0.2, 5.0))
        f = lambda X: np.hypot(X[:, 0] - 1, X[:, 1] + 2) - (1 + (X[:, 2] - 0.5) / 2)  # noqa
    elif kind in ("sphere", "torus", "revolved arc"):
        R, r = {"sphere": (0.0, 4.0), "torus": (6.0, 1.5), "revolved arc": (3.0, 2.0)}[kind]
        a0, a1 = {"sphere": (-math.pi / 2, math.pi / 2), "torus": (0, 2 * math.pi),
                  "revolved arc": (-0.4, 1.3)}[kind]
        gen = analytic.arc_curve(axis_p + [R, 0, 0], [1, 0, 0], [0, 0, 1], r, a0, a1)
        s = _surf(analytic.revolve(gen, axis_p, axis_d, 0, 2 * math.pi if kind != "revolved arc"
                                   else 2.0))
        f = lambda X: np.hypot(np.hypot(X[:, 0] - 1, X[:, 1] + 2) - R, X[:, 2] - 0.5) - r  # noqa
    elif kind == "ruled":
        s = _surf(analytic.ruled(analytic.line_curve([0, 0, 0], [1, 0, 0]),
                                 analytic.line_curve([0, 1, 1], [2, 3, 1])))
        uv = _grid(s)
        X = s.evaluate(uv)
        u, v = uv[:, :1], uv[:, 1:]
        ref = (1 - v) * (u * [1, 0, 0]) + v * ([0, 1, 1] + u * [2, 2, 0])
        assert np.abs(X - ref).max() < 1e-12 * s.size
        return
    else:
        s = _surf(analytic.plane_patch([1, 2, 3], [1, 0, 0], [0, 0.6, 0.8], -2, 3, 0, 4))
        f = lambda X: (X - [1, 2, 3]) @ np.cross([1, 0, 0], [0, 0.6, 0.8])  # noqa: E731
    X = s.evaluate(_grid(s, 15))
    assert np.abs(f(X)).max() < 1e-12 * s.size


# ------------------------------------------------------------- IGES files
# the impeller fixture (read_iges of IMPELLER, once per module) is in tests/conftest.py
def test_impeller_revolutions_hold_their_closed_form(impeller):
    """Each 120 face: S(t, s) is the generatrix line point at t rotated by the angle
    param_to_angle(s) about the axis (Rodrigues), to 1e-12 x size."""
    from geomkit.cad.iges.reader import _Reader

    with open(IMPELLER):
        pass
    rd = _Reader(IMPELLER, pyiges.read(str(IMPELLER)))
    checked = 0
    for s, de in zip(impeller.surfaces, impeller.entities):
        r = rd.rec(de)
        pts = int(r[1])
        if rd.type_of(pts) != 120:
            continue
        rec = rd.rec(pts)
        ax = np.array([float(x) for x in rd.rec(int(rec[1]))[1:7]]).reshape(2, 3)
        gl = np.array([float(x) for x in rd.rec(int(rec[2]))[1:7]]).reshape(2, 3)
        sa, ta = float(rec[3]), float(rec[4])
        uv = _grid(s, 7)
        th = analytic.param_to_angle(uv[:, 1], sa, ta)
        k = (ax[1] - ax[0]) / np.linalg.norm(ax[1] - ax[0])
        P = gl[0] + uv[:, :1] * (gl[1] - gl[0]) - ax[0]
        c, sn = np.cos(th)[:, None], np.sin(th)[:, None]
        rot = P * c + np.cross(k, P) * sn + np.outer(P @ k, k) * (1 - c) + ax[0]
        assert np.abs(s.evaluate(uv) - rot).max() < 1e-12 * s.size
        checked += 1
    assert checked == 30


def test_sample_igs_has_no_surface_and_says_so():
    with pytest.raises(FileFormatError, match="no readable surface.*116"):
        read_iges(SAMPLE)


def test_empty_files_are_a_clear_error(tmp_path):
    from geomkit.cad.step import read_step

    for name, fn in (("e.igs", read_iges), ("e.step", read_step)):
        f = tmp_path / name
        f.write_text("")
        with pytest.raises(InvalidInputError, match=f"{name}: empty file"):
            fn(f)


def test_unsupported_entities_are_an_error_unless_skipped(tmp_path):
    """An IGES file with a standalone 192 (an unbounded right circular cylindrical
    surface, no face to read) next to the impeller's faces."""
    from geomkit.cad.iges.reader import Skipped

    lines = IMPELLER.read_text(encoding="latin-1").splitlines()
    d = [ln for ln in lines if ln[72:73] == "D"]
    p = [ln for ln in lines if ln[72:73] == "P"]
    s = [ln for ln in lines if ln[72:73] in ("S", "G")]
    nd, np_ = len(d) + 1, len(p) + 1
    d += [f"{192:8d}{np_:8d}{0:8d}{0:8d}{0:8d}{'':24}{'00000000':>8}D{nd:7d}",
          f"{192:8d}{0:8d}{0:8d}{1:8d}{0:8d}{'':24}{0:8d}D{nd + 1:7d}"]
    p += [f"{'192,1,1,2.;':<64}{nd:8d}P{np_:7d}"]
    f = tmp_path / "with_offset.igs"
    f.write_text("\n".join(s + d + p + [f"S{1:7d}G{5:7d}D{len(d):7d}P{len(p):7d}"
                                        f"{'':40}T{1:7d}"]) + "\n", encoding="latin-1")
    with pytest.raises(FileFormatError, match=r"1 face\(s\) cannot be read: 192@"):
        read_iges(f)
    r = read_iges(f, skip_unsupported=True)
    assert len(r.surfaces) == 277 and len(r.skipped) == 1
    assert isinstance(r.skipped[0], Skipped) and r.skipped[0].id == f"192@{nd}"
    assert "cylindrical" in r.skipped[0].reason


# ------------------------------------------------------------ OCC oracle
def _points_near(surfaces, n, seed):
    rng = np.random.default_rng(seed)
    out = []
    while len(out) < n:
        s = surfaces[rng.integers(len(surfaces))]
        uv = _grid(s, 2)[:1] * 0 + [[s.domain[0][0] + rng.random() * np.ptp(s.domain[0]),
                                     s.domain[1][0] + rng.random() * np.ptp(s.domain[1])]]
        out.append(s.evaluate(uv)[0] + rng.normal(size=3) * 1.0)
    return np.array(out)


def _per_face_min(surfaces, pts):
    """Distance as the minimum over single-face projections (independent of the
    multi-face candidate search)."""
    best = np.full(len(pts), np.inf)
    for s in surfaces:
        best = np.minimum(best, geomkit.project_points(s, pts).distance)
    return best


def _compare(surfaces, shape, pts, gap):
    pr = geomkit.project_points(surfaces, pts)
    dg = pr.distance
    do, on_edge = _occ_distances(shape, pts, dg)
    diff = dg - do
    ok = np.abs(diff) <= 1e-6
    # OCC's foot on an edge: its 3-D edge curve lies up to the model gap off the faces
    ok |= on_edge & (np.abs(diff) <= gap)
    bad = np.nonzero(~ok)[0]
    return dg, do, diff, ok, bad, pr


@pytest.fixture(scope="module")
def occ_impeller():
    if not HAVE_OCP:
        pytest.skip("needs cadquery-ocp")
    from OCP.IGESControl import IGESControl_Reader

    rd = IGESControl_Reader()
    rd.ReadFile(str(IMPELLER))
    rd.TransferRoots()
    return rd.OneShape()


def _check_against_occ(surfaces, shape, n, seed, label):
    pts = _points_near(surfaces, n, seed)
    dg, do, diff, ok, bad, pr = _compare(surfaces, shape, pts, EDGE_GAP)
    # geomkit lower than OCC: its foot is a real point of a face, inside its trim
    for i in np.nonzero(diff < -1e-6)[0]:
        s = surfaces[pr.surface[i]]
        assert np.linalg.norm(s.evaluate(pr.uv[i:i + 1])[0] - pr.point[i]) < 1e-9 * s.size
        assert s.classify_uv(pr.uv[i:i + 1])[0] != geomkit.OUTSIDE
    # the rest: the multi-face search missed a nearer face (projection engine, see
    # test_projection_misses_a_nearer_face); the faces themselves agree with OCC
    ref = _per_face_min(surfaces, pts[bad]) if bad.size else np.zeros(0)
    d2 = ref - do[bad]
    still = ~((np.abs(d2) <= 1e-6) | (np.abs(d2) <= EDGE_GAP))
    print(f"\n{label}: {n} points; |geomkit - OCC| <= 1e-6 at "
          f"{int(np.sum(np.abs(diff) <= 1e-6))}; OCC foot on an edge (within the model "
          f"gap {EDGE_GAP:g}) at {int(np.sum(ok & (np.abs(diff) > 1e-6)))}; "
          f"max |diff| there {np.abs(diff[ok]).max():.3g}; projection misses {bad.size} "
          f"(per-face minimum then agrees to {np.abs(d2).max() if d2.size else 0:.3g})")
    if bad.size:  # a reproducer for the projection engineer
        print(f"  first miss: project_points(surfaces, {pts[bad][0].tolist()}) gives "
              f"{dg[bad][0]!r}, the per-face minimum {ref[0]!r}")
    assert not still.any(), (pts[bad][still], d2[still])


FULL = bool(os.environ.get("GEOMKIT_FULL_ORACLE"))
"""``GEOMKIT_FULL_ORACLE=1``: the issue's full sizes (700 + 300 impeller points); by
default a fraction of them.  The section planes are the same either way."""

EDGE_GAP = 1e-2
"""The impeller's edge gaps: its 142 model-space curves (OCC's edges) lie up to ~9e-3
off the surfaces (OCC's edge tolerances say the same)."""


@pytest.mark.occ
@needs_occ
def test_impeller_iges_matches_open_cascade(impeller, occ_impeller):
    assert len(impeller.surfaces) == len(_occ_faces(occ_impeller)) == 277
    _check_against_occ(impeller.surfaces, occ_impeller, 700 if FULL else 100, 1,
                       "impeller IGES")


@pytest.fixture(scope="module")
def impeller_step(occ_impeller, tmp_path_factory):
    """The impeller written to STEP by OCC's STEPControl_Writer, read by geomkit."""
    from OCP.STEPControl import STEPControl_AsIs, STEPControl_Writer

    from geomkit.cad.step import read_step

    f = tmp_path_factory.mktemp("step") / "impeller.step"
    w = STEPControl_Writer()
    w.Transfer(occ_impeller, STEPControl_AsIs)
    w.Write(str(f))
    return read_step(f)


@pytest.mark.occ
@needs_occ
def test_impeller_written_to_step_by_occ(occ_impeller, impeller_step):
    r = impeller_step
    assert len(r.surfaces) == len(_occ_faces(occ_impeller)) == 277 and not r.skipped
    assert r.units == "mm" and r.resolution is not None
    _check_against_occ(r.surfaces, occ_impeller, 300 if FULL else 40, 2, "impeller STEP")


@pytest.mark.occ
@needs_occ
def test_step_round_trip_of_occ_primitives(tmp_path):
    """Box, cylinder, cone, sphere, torus, filleted box: OCC's face count, each face's
    points on its closed form, and OCC's distances."""
    from OCP.BRepFilletAPI import BRepFilletAPI_MakeFillet
    from OCP.BRepPrimAPI import (BRepPrimAPI_MakeBox, BRepPrimAPI_MakeCone,
                                 BRepPrimAPI_MakeCylinder, BRepPrimAPI_MakeSphere,
                                 BRepPrimAPI_MakeTorus)
    from OCP.STEPControl import STEPControl_AsIs, STEPControl_Writer
    from OCP.TopAbs import TopAbs_EDGE
    from OCP.TopExp import TopExp_Explorer

    from geomkit.cad.occ import cast_shape
    from geomkit.cad.step import read_step

    box = BRepPrimAPI_MakeBox(10, 20, 30).Shape()
    fil = BRepFilletAPI_MakeFillet(box)
    fil.Add(2.0, cast_shape("Edge", TopExp_Explorer(box, TopAbs_EDGE).Current()))
    shapes = {"box": (box, lambda X: np.min(np.abs(np.column_stack(
                  [X, X - [10, 20, 30]])), axis=1)),
              "cylinder": (BRepPrimAPI_MakeCylinder(3, 7).Shape(), lambda X: np.minimum(
                  np.abs(np.hypot(X[:, 0], X[:, 1]) - 3),
                  np.minimum(np.abs(X[:, 2]), np.abs(X[:, 2] - 7)))),
              "cone": (BRepPrimAPI_MakeCone(3, 1, 5).Shape(), lambda X: np.minimum(
                  np.abs(np.hypot(X[:, 0], X[:, 1]) - (3 - 0.4 * X[:, 2])),
                  np.minimum(np.abs(X[:, 2]), np.abs(X[:, 2] - 5)))),
              "sphere": (BRepPrimAPI_MakeSphere(4).Shape(),
                         lambda X: np.abs(np.linalg.norm(X, axis=1) - 4)),
              "torus": (BRepPrimAPI_MakeTorus(5, 1.5).Shape(), lambda X: np.abs(
                  np.hypot(np.hypot(X[:, 0], X[:, 1]) - 5, X[:, 2]) - 1.5)),
              "fillet": (fil.Shape(), None)}
    rng = np.random.default_rng(3)
    for name, (shape, closed_form) in shapes.items():
        w = STEPControl_Writer()
        w.Transfer(shape, STEPControl_AsIs)
        w.Write(str(tmp_path / f"{name}.step"))
        r = read_step(tmp_path / f"{name}.step")
        assert len(r.surfaces) == len(_occ_faces(shape)), name
        assert not r.skipped and r.units == "mm"
        size = max(s.size for s in r.surfaces)
        if closed_form is not None:
            for s in r.surfaces:
                X = s.evaluate(_grid(s, 9))
                assert closed_form(X).max() < 1e-12 * size, (name, s.name)
        pts = _points_near(r.surfaces, 20, int(rng.integers(1000)))
        dg = geomkit.project_points(r.surfaces, pts).distance
        do, _ = _occ_distances(shape, pts, dg)
        assert np.abs(dg - do).max() < 1e-6, name


@pytest.fixture(scope="module")
def impeller_gap(impeller):
    from geomkit.cad.gaps import model_gap

    gap = model_gap(impeller.surfaces)
    assert 1e-3 < gap < 2e-2  # the file's edges: OCC's edge tolerances say ~1e-2
    return gap


@pytest.mark.occ
@needs_occ
@pytest.mark.parametrize("axis,c", SECTION_PLANES,
                         ids=[f"{'xyz'[a]}={c}" for a, c in SECTION_PLANES])
def test_impeller_sections_match_open_cascade(impeller, occ_impeller, impeller_gap, axis, c):
    """x = 5.9 was a failure (an OCC point 0.164 from every geomkit curve): OCC's IGES
    translation gives the 0.30-long edge shared by faces 144@3571 and the sliver
    144@8731 (from (5.778, -7.610, -29.160) to (5.905, -7.496, -29.412)) a tolerance of
    0.152, and BRepAlgoAPI_Section returns that whole edge, whose points lie up to 0.122
    off the plane, as a section edge.  geomkit's curves there are right."""
    _check_section(impeller.surfaces, impeller_gap, occ_impeller,
                   _occ_section(occ_impeller, axis, c), axis, c, "impeller IGES")


@pytest.mark.occ
@needs_occ
def test_impeller_step_sections_match_open_cascade(impeller_step, occ_impeller):
    """The impeller written to STEP by OCC and read by geomkit: its sections match
    OCC's sections of the shape it was written from."""
    from geomkit.cad.gaps import model_gap

    from OCP.BRep import BRep_Tool
    from OCP.TopAbs import TopAbs_EDGE
    from OCP.TopExp import TopExp_Explorer

    from geomkit.cad.occ import cast_shape

    # OCC's pcurves in the STEP file follow its tolerant edges: the faces' boundaries
    # are up to ~0.12 apart there, as OCC's own edge tolerances (up to 0.16) say
    gap = model_gap(impeller_step.surfaces)
    ex, occ_tol = TopExp_Explorer(occ_impeller, TopAbs_EDGE), 0.0
    while ex.More():
        occ_tol = max(occ_tol, BRep_Tool.Tolerance_s(cast_shape("Edge", ex.Current())))
        ex.Next()
    print(f"\nSTEP model gap {gap:.3g}, OCC's largest edge tolerance {occ_tol:.3g}")
    assert gap <= occ_tol
    for axis, c in STEP_PLANES:
        _check_section(impeller_step.surfaces, gap, occ_impeller,
                       _occ_section(occ_impeller, axis, c), axis, c, "impeller STEP")


def test_section_joins_across_a_model_gap_and_reports_it():
    from geomkit.cad.gaps import model_gap

    a = Surface(*analytic.plane_patch([0, 0, 0], [1, 0, 0], [0, 0, 1], 0, 1, 0, 1))
    b_args = analytic.plane_patch([0, 0, 0], [1, 0, 0], [0, 0, 1], 1.001, 2, 0, 1)
    b = Surface(*b_args, approx_error=1e-7)
    assert abs(model_gap([a, b], per_piece=201) - 1e-3) < 1e-12
    plane = [0, 0, 1, -0.5]
    s0 = geomkit.plane_section([a, b], plane, tol=1e-6)
    assert len(s0.curves) == 2 and s0.max_gap_bridged == 0.0
    s1 = geomkit.plane_section([a, b], plane, tol=1e-6, gap=2e-3)
    assert len(s1.curves) == 1 and abs(s1.max_gap_bridged - 1e-3) < 1e-12
    assert s1.gap == 2e-3 and s1.approx_error == 1e-7
    with pytest.raises(InvalidInputError, match="gap"):
        geomkit.plane_section([a, b], plane, gap=-1)


def test_impeller_collide_single_call_against_generic_path_and_coal(impeller):
    """A model no one here wrote: the impeller's mesh against a pickled copy of
    itself under 60 random poses.  The single-call kernel (objects read unconverted)
    finds the same pairs as the generic traversal, and coal the same flags."""
    import pickle

    from scipy.spatial.transform import Rotation

    from geomkit.collision import collide as gc
    m = geomkit.tessellate(impeller.surfaces, 0.1)
    V, F = np.ascontiguousarray(m.vertices), np.ascontiguousarray(m.faces, np.int64)
    a = gc.Body((V, F))
    b = pickle.loads(pickle.dumps(gc.Body((V, F))))
    rng = np.random.default_rng(1)
    ext = np.ptp(V, 0).max()
    poses = np.tile(np.eye(4), (60, 1, 1))
    poses[:, :3, :3] = Rotation.random(60, random_state=2).as_matrix()
    poses[:, :3, 3] = rng.uniform(-0.8, 0.8, (60, 3)) * ext
    fast = [gc.collide(a, np.eye(4), b, P) for P in poses]
    by_ref, gc._BY_REF = gc._BY_REF, False
    try:
        generic = [gc.collide(a, np.eye(4), b, P) for P in poses]
    finally:
        gc._BY_REF = by_ref
    assert 10 < sum(c.colliding for c in fast) < 55
    for c, g in zip(fast, generic):
        assert c.colliding == g.colliding and np.array_equal(c.pairs, g.pairs)
    coal = pytest.importorskip("coal")
    from geomkit.bench.collision import _coal, _coal_pose
    model = _coal(coal, V, F, coal.BVHModelOBBRSS)
    eye = _coal_pose(coal, np.eye(4))
    for c, P in zip(fast, poses):
        r = coal.CollisionResult()
        coal.collide(model, eye, model, _coal_pose(coal, P), coal.CollisionRequest(), r)
        assert r.isCollision() == c.colliding
