"""Virtual measurement (geomkit.jobs.sample.sample_faces, geomkit sample): points on
their exact trimmed faces with outward normals, and every planted error recovered by
deviation / GD&T / alignment."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

import geomkit
from geomkit import samples
from geomkit.cli import main
from geomkit.errors import InvalidInputError
from geomkit.jobs.sample import SampledPoints, sample_faces
from geomkit.nurbs.trimming import INSIDE

from helpers.paths import DATA

STEP_PART = DATA / "parts" / "nist_ftc_06_ap242.stp"


def _surfs(name):
    return samples.load_case(name).surfaces


def _size(surfs):
    lo = np.min([s.bounds[0] for s in surfs], axis=0)
    hi = np.max([s.bounds[1] for s in surfs], axis=0)
    return float(np.linalg.norm(hi - lo))


def _check_on_faces(surfs, r: SampledPoints, tol_rel=1e-9):
    """Every point on its face (exact evaluation, projection foot on the same face),
    inside its trim, with a unit normal equal to +-Surface.normals."""
    size = _size(surfs)
    pr = geomkit.project_points(surfs, r.points)
    assert np.all(pr.distance < tol_rel * size), pr.distance.max()
    assert np.array_equal(pr.surface, r.face)
    np.testing.assert_array_equal(r.points, r.nominal)
    for f in np.unique(r.face):
        k = r.face == f
        s = surfs[f]
        np.testing.assert_allclose(s.evaluate(r.uv[k]), r.nominal[k], rtol=0, atol=1e-12 * size)
        assert np.all(s.classify_uv(r.uv[k]) == INSIDE)
        ns = s.normals(r.uv[k])
        dots = np.einsum("ij,ij->i", ns, r.normals[k])
        assert np.allclose(np.abs(dots), 1, atol=1e-12)
        assert np.all(np.sign(dots) == np.sign(dots[0]))  # one side per face
        flipped = r.orientation[int(f)] == "flipped"
        assert (dots[0] < 0) == flipped
    np.testing.assert_allclose(np.linalg.norm(r.normals, axis=1), 1, atol=1e-12)


def _sign(surfs, r):
    """+1 where the sample's normal is S_u x S_v (deviation's sign convention)."""
    out = np.empty(len(r))
    for f in np.unique(r.face):
        k = r.face == f
        out[k] = np.sign(np.einsum("ij,ij->i", surfs[f].normals(r.uv[k]), r.normals[k]))
    return out


# ------------------------------------------------------------------ where, normals
def test_plate_points_on_face_inside_trim_and_spread():
    surfs = _surfs("plate_with_hole")
    r = sample_faces(surfs, 400, seed=3)
    assert len(r) == 400 and r.counts == {0: 400} and r.short == {}
    _check_on_faces(surfs, r)
    assert np.all(r.planted == 0) and np.all(r.noise == 0)
    # none in the hole (radius 20 about the plate's centre), spread over the plate:
    # every 20 x 20 cell of the 100 x 100 plate outside the hole holds some points
    c = (surfs[0].bounds[0] + surfs[0].bounds[1]) / 2
    assert np.linalg.norm(r.points[:, :2] - c[:2], axis=1).min() > 20 - 1e-6
    lo = surfs[0].bounds[0]
    cell = np.floor((r.points[:, :2] - lo[:2]) / 20).astype(int)
    occupied = {tuple(x) for x in cell}
    assert len(occupied) >= 21  # 25 cells, the hole covers the middle one (and cuts 4)
    # not clustered: the nearest-neighbour distances are all of one scale
    d = np.linalg.norm(r.points[:, None] - r.points[None], axis=2)
    np.fill_diagonal(d, np.inf)
    assert d.min(axis=1).min() > 0.05 * np.sqrt(100 * 100 / 400)


def test_sphere_normals_outward_and_area_weighted():
    surfs = _surfs("sphere")
    r = sample_faces(surfs, 2000, seed=1)
    _check_on_faces(surfs, r)
    assert r.orientation == {0: "outward"} or r.orientation == {0: "flipped"}
    assert np.all(np.einsum("ij,ij->i", r.normals, r.points) > 0)  # outward
    # area-uniform on a sphere: z is uniform (Archimedes), the poles are not crowded
    h, _ = np.histogram(r.points[:, 2], bins=10, range=(-10, 10))
    assert h.min() > 0.8 * 200 and h.max() < 1.2 * 200


def test_step_part_all_faces_outward():
    case = geomkit.read_step(STEP_PART)
    surfs = case.surfaces
    r = sample_faces(case, 5, seed=0)
    assert len(r.counts) == len(surfs)
    assert all(v == 5 for v in r.counts.values()) and not r.short
    assert len(r) == 5 * len(surfs)
    _check_on_faces(surfs, r, tol_rel=1e-9)
    assert not r.summary()["undecided_faces"]
    # outward everywhere: the mesh's volume with the faces turned as decided is
    # positive and does not change when the part moves (a closed, consistently
    # oriented boundary)
    m = geomkit.tessellate(surfs, 1e-4 * _size(surfs))
    sign = np.array([-1.0 if r.orientation[f] == "flipped" else 1.0
                     for f in range(len(surfs))])
    vols = []
    for shift in (np.zeros(3), np.array([300.0, -200.0, 150.0])):
        tri = m.vertices[m.faces] + shift
        v = np.einsum("ij,ij->i", tri[:, 0], np.cross(tri[:, 1], tri[:, 2])) / 6
        vols.append(float((np.bincount(m.face_surface, v, len(surfs)) * sign).sum()))
    assert vols[0] > 0
    assert abs(vols[1] - vols[0]) < 1e-4 * vols[0]


def test_selected_faces_and_counts():
    case = geomkit.read_step(STEP_PART)
    r = sample_faces(case, 7, faces=[3, 1, 3, 40], seed=2, orient="surface")
    assert r.counts == {3: 7, 1: 7, 40: 7}
    assert sorted(np.unique(r.face).tolist()) == [1, 3, 40]
    assert set(r.orientation.values()) == {"surface"}


def test_tiny_trimmed_region_draws_more_and_reports_short():
    s0 = _surfs("plate_with_hole")[0]
    (u0, u1), (v0, v1) = s0.domain
    # a small square (1e-4 of the domain's area) and a thin sliver
    a, w = u0 + 0.3 * (u1 - u0), 0.01 * (u1 - u0)
    square = [[a, a], [a + w, a], [a + w, a + w], [a, a + w], [a, a]]
    s = geomkit.Surface(s0.degree_u, s0.degree_v, s0.knots_u, s0.knots_v,
                        s0.control_points, trim=[square])
    r = sample_faces(s, 50, seed=0)
    assert r.counts == {0: 50}
    _check_on_faces([s], r)
    eps = 1e-7 * (v1 - v0)  # a sliver of area ~1e-7 of its box: 2^20 candidates miss it
    sliver = [[u0 + 0.1, v0 + 0.1], [u1 - 0.1, v1 - 0.1], [u1 - 0.1, v1 - 0.1 + eps],
              [u0 + 0.1, v0 + 0.1]]
    s2 = geomkit.Surface(s0.degree_u, s0.degree_v, s0.knots_u, s0.knots_v,
                         s0.control_points, trim=[sliver])
    with pytest.warns(UserWarning, match="fewer than 10 points"):
        r2 = sample_faces(s2, 10, seed=0)
    assert r2.short == {0: r2.counts[0]} and r2.counts[0] < 10
    assert r2.summary()["short_faces"] == {0: r2.counts[0]}


# ------------------------------------------------------------------------ noise
def test_noise_statistics_and_reproducibility():
    surfs = _surfs("plate_with_hole")
    sigma = 0.01
    r = sample_faces(surfs, 20000, noise=sigma, seed=7)
    assert abs(np.std(r.planted) / sigma - 1) < 0.03
    assert abs(np.mean(r.planted)) < 4 * sigma / np.sqrt(20000)
    np.testing.assert_allclose(r.planted, r.noise, atol=1e-15)
    # deviation reads the planted values back (plate: S_u x S_v kept)
    rep = geomkit.deviation(surfs, r.points, r.normals)
    np.testing.assert_allclose(rep.deviation, r.planted * _sign(surfs, r), atol=1e-9)
    again = sample_faces(surfs, 20000, noise=sigma, seed=7)
    np.testing.assert_array_equal(again.points, r.points)
    other = sample_faces(surfs, 20000, noise=sigma, seed=8)
    assert not np.array_equal(other.points, r.points)
    assert abs(r.summary()["noise_std"] / sigma - 1) < 0.03


# ------------------------------------------------------------------ form errors
def test_bump_on_plane_gives_flatness_h():
    surfs = _surfs("plate_with_hole")
    size, h = _size(surfs), 0.05
    base = sample_faces(surfs, 1500, seed=4)
    centre = base.nominal[np.argmin(np.abs(base.nominal[:, 0] - 15))]  # a sampled point
    bump = {"kind": "bump", "center": tuple(centre), "radius": 12.0, "height": h}
    r = sample_faces(surfs, 1500, seed=4, form_errors={0: [bump]})
    np.testing.assert_array_equal(r.nominal, base.nominal)  # same places
    ch = geomkit.gdt.flatness(r.points, tol=0.1)
    assert abs(ch.measured - h) < 1e-6 * size
    assert abs(r.planted.max() - h) < 1e-12 and r.planted.min() == 0
    d = np.linalg.norm(r.nominal - centre, axis=1)
    assert np.all(r.planted[d >= 12.0] == 0) and np.all(r.planted[d < 11.9] > 0)


def test_offset_and_translate_give_mean_deviation():
    case = geomkit.read_step(STEP_PART)
    surfs = case.surfaces
    d = 0.02
    r = sample_faces(case, 5, seed=1,
                     form_errors={10: [{"kind": "offset", "distance": d}]})
    rep = geomkit.deviation(surfs, r.points, r.normals)
    k = r.face == 10
    sgn = _sign(surfs, r)
    assert abs(np.mean(rep.deviation[k] * sgn[k]) - d) < 1e-9
    assert np.all(np.abs(rep.deviation[~k]) < 1e-9)
    np.testing.assert_allclose(r.planted[k], d, atol=1e-12)
    # a translate vector on the plate: the deviation is its normal component
    plate = _surfs("plate_with_hole")
    t = np.array([0.3, -0.2, 0.01])
    r2 = sample_faces(plate, 200, seed=1,
                      form_errors={0: [{"kind": "offset", "translate": tuple(t)}]})
    rep2 = geomkit.deviation(plate, r2.points, r2.normals)
    ok = ~rep2.edge
    np.testing.assert_allclose(rep2.deviation[ok], r2.planted[ok] * _sign(plate, r2)[ok],
                               atol=1e-9)
    np.testing.assert_allclose(r2.planted, t @ r2.normals[0], atol=1e-12)


def test_tilt_rotates_the_face_about_its_centroid():
    surfs = _surfs("plate_with_hole")
    a = 1e-3
    r = sample_faces(surfs, 500, seed=2,
                     form_errors={0: [{"kind": "tilt", "axis": (1, 0, 0), "angle": a}]})
    X = r.points - r.points.mean(axis=0)
    n = np.linalg.svd(X)[2][2]
    angle = np.arccos(abs(n[2]))
    assert abs(angle - a) < 1e-9
    # about the face's centroid: its height does not move
    assert abs(r.points[:, 2].mean() - r.nominal[:, 2].mean()) < 1e-9
    ch = geomkit.gdt.flatness(r.points, tol=1.0)
    assert ch.measured < 1e-9 * _size(surfs)


def test_scale_grows_a_cylinder_radially():
    surfs = _surfs("cylinder_quarter")  # r = 10, axis z
    f = 1.01
    spec = {"kind": "scale", "factor": f, "axis": (0, 0, 1), "center": (0, 0, 0)}
    r = sample_faces(surfs, 300, seed=5, form_errors={0: [spec]})
    radius = np.linalg.norm(r.points[:, :2], axis=1)
    np.testing.assert_allclose(radius, 10 * f, atol=1e-9)
    np.testing.assert_allclose(np.abs(r.planted), 0.1, atol=1e-9)
    rep = geomkit.deviation(surfs, r.points, r.normals)
    np.testing.assert_allclose(rep.deviation, r.planted * _sign(surfs, r), atol=1e-9)
    # with the default centre (the face's centroid, off the axis) the points move
    # differently: the centre matters
    r2 = sample_faces(surfs, 300, seed=5,
                      form_errors={0: [{"kind": "scale", "factor": f, "axis": (0, 0, 1)}]})
    assert not np.allclose(r2.points, r.points)


def test_sphere_scale_without_axis_and_sphericity():
    surfs = _surfs("sphere")
    r = sample_faces(surfs, 500, seed=1, noise=0.0,
                     form_errors={0: [{"kind": "scale", "factor": 1.002,
                                       "center": (0, 0, 0)}]})
    np.testing.assert_allclose(np.linalg.norm(r.points, axis=1), 10.02, atol=1e-9)
    np.testing.assert_allclose(r.planted, 0.02, atol=1e-9)  # outward normals


def test_transform_is_recovered_by_align_rigid():
    surfs = _surfs("freeform_1")
    T = np.eye(4)
    T[:3, :3] = Rotation.from_rotvec([0.004, -0.003, 0.002]).as_matrix()
    T[:3, 3] = [0.3, -0.2, 0.25]
    r = sample_faces(surfs, 400, seed=6, transform=T)
    np.testing.assert_allclose(r.points, r.nominal @ T[:3, :3].T + T[:3, 3], atol=1e-12)
    fit = geomkit.align_rigid(surfs, r.points)
    A = np.asarray(fit["transform"])
    assert np.abs(A @ T - np.eye(4)).max() < 1e-9
    np.testing.assert_array_equal(r.transform, T)
    assert r.summary()["transform"] == T.tolist()


# ------------------------------------------------------------------------- CSV
def test_to_csv_reads_back(tmp_path):
    from geomkit.exchange.points import read_points

    surfs = _surfs("sphere")
    r = sample_faces(surfs, 40, seed=1, noise=0.01)
    path = r.to_csv(tmp_path / "p.csv")
    assert path.read_text().splitlines()[0] == "x,y,z,i,j,k,face,u,v"
    pts = read_points(path)
    np.testing.assert_array_equal(pts.points, r.points)
    np.testing.assert_allclose(pts.normals, r.normals, rtol=0, atol=1e-15)
    with pytest.raises(FileExistsError):
        r.to_csv(path)
    r.to_csv(path, overwrite=True)


# -------------------------------------------------------------------- bad input
@pytest.mark.parametrize("kwargs, field", [
    ({"per_face": 0}, "per_face"),
    ({"per_face": 2.5}, "per_face"),
    ({"noise": -0.1}, "noise"),
    ({"noise": float("nan")}, "noise"),
    ({"margin": -1}, "margin"),
    ({"seed": -1}, "seed"),
    ({"faces": [1]}, "faces"),
    ({"faces": [-1]}, "faces"),
    ({"form_errors": {0: [{"kind": "dent", "height": 1}]}}, r"form_errors\[0\]\[0\].kind"),
    ({"form_errors": {3: [{"kind": "offset", "distance": 1}]}}, "form_errors"),
    ({"form_errors": {0: [{"kind": "bump", "center": (0, 0, 0), "height": 1}]}},
     r"form_errors\[0\]\[0\]"),
    ({"form_errors": {0: [{"kind": "bump", "center": (0, 0, 0), "radius": -1,
                           "height": 1}]}}, "radius"),
    ({"form_errors": {0: [{"kind": "offset"}]}}, r"form_errors\[0\]\[0\]"),
    ({"form_errors": {0: [{"kind": "tilt", "axis": (0, 0, 0), "angle": 1}]}}, "axis"),
    ({"transform": np.diag([2.0, 1, 1, 1])}, "transform"),
    ({"transform": np.eye(3)}, "transform"),
    ({"orient": "inward"}, "orient"),
])
def test_bad_input_names_the_field(kwargs, field):
    args = {"per_face": 5, **kwargs}
    per_face = args.pop("per_face")
    with pytest.raises(InvalidInputError, match=field):
        sample_faces(_surfs("sphere"), per_face, **args)


# -------------------------------------------------------------------------- CLI
def test_cli_sample_then_deviation_reads_back(tmp_path, capsys, monkeypatch):
    import json

    monkeypatch.chdir(tmp_path)
    assert main(["sample", "sphere", "--per-face", "60", "--seed", "2"]) == 0
    out = capsys.readouterr().out
    assert out.count("\n") == 1 and "sphere-points.csv: 60 points on 1 face(s)" in out
    csv = tmp_path / "sphere-points.csv"
    assert csv.read_text().splitlines()[0] == "x,y,z,i,j,k,face,u,v"
    assert main(["deviation", "sphere", str(csv), "-o", "dev", "--no-plots"]) == 0
    summary = json.loads((tmp_path / "dev" / "summary.json").read_text())
    assert summary["valid"] == 60
    assert max(abs(summary["min"]), abs(summary["max"])) < 1e-9
    capsys.readouterr()
    assert main(["sample", "sphere", "--per-face", "10", "--noise", "0.01", "--faces", "0",
                 "-o", "n.csv", "--json"]) == 0
    info = json.loads(capsys.readouterr().out)
    assert info["points"] == 10 and info["output"] == "n.csv" and info["noise"] == 0.01


def test_cli_step_part(tmp_path, capsys):
    out = tmp_path / "ftc.csv"
    assert main(["sample", str(STEP_PART), "--per-face", "2", "--faces", "0,5,9",
                 "-o", str(out)]) == 0
    lines = out.read_text().splitlines()
    assert len(lines) == 7
    assert sorted({int(x.split(",")[6]) for x in lines[1:]}) == [0, 5, 9]
    assert "mm" in capsys.readouterr().out


def test_cli_keeps_existing_output_without_overwrite(tmp_path, capsys):
    out = tmp_path / "p.csv"
    out.write_text("keep\n")
    assert main(["sample", "sphere", "--per-face", "5", "-o", str(out)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "--overwrite" in err
    assert out.read_text() == "keep\n"
    assert main(["sample", "sphere", "--per-face", "5", "-o", str(out), "--overwrite"]) == 0
    assert out.read_text().startswith("x,y,z,i,j,k,face,u,v")


@pytest.mark.parametrize("argv, words", [
    (["--per-face", "0"], "--per-face"),
    (["--per-face", "x"], "--per-face"),
    (["--per-face", "5", "--noise", "-1"], "--noise"),
    (["--per-face", "5", "--faces", "3"], "--faces"),
    (["--per-face", "5", "--faces", "a,b"], "--faces"),
    (["--per-face", "5", "-o", "no/such/folder/p.csv"], "no such folder"),
])
def test_cli_bad_input_one_line_exit_2(tmp_path, capsys, monkeypatch, argv, words):
    monkeypatch.chdir(tmp_path)
    assert main(["sample", "sphere", *argv]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith("geomkit: error:") and words in err
    assert not list(tmp_path.iterdir())


def test_cli_never_writes_over_an_input(tmp_path, capsys):
    part = tmp_path / "part.json"
    geomkit.save(part, _surfs("sphere"))
    before = part.read_bytes()
    assert main(["sample", str(part), "--per-face", "5", "-o", str(part),
                 "--overwrite"]) == 2
    assert part.read_bytes() == before
