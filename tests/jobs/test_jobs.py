"""The users' jobs: deviation (API and CLI), distance, section export, demo, bad inputs.

Oracles: analytic offsets from the torus (exact signed distances), a known rigid
transform (alignment), and the files themselves (inputs never change).
"""

from __future__ import annotations

import csv
import json
import os
import re

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

import geomkit
from geomkit import samples
from geomkit.jobs.deviation import align_rigid, deviation
from geomkit.exchange.points import read_points

from helpers.clihelp import assert_one_line_error, cli, digest  # noqa: E402
from helpers.paths import ROOT  # noqa: E402


def torus_points(n=400, seed=1, lo=-2.0, hi=2.0):
    tor = samples.load("torus")[0]
    rng = np.random.default_rng(seed)
    (u0, u1), (v0, v1) = tor.domain
    uv = np.column_stack([rng.uniform(u0, u1, n), rng.uniform(v0, v1, n)])
    return tor, tor.evaluate(uv), tor.normals(uv), rng.uniform(lo, hi, n)


def write_xyz(path, P, N=None):
    with open(path, "w") as fh:
        fh.write("x,y,z" + (",i,j,k" if N is not None else "") + "\n")
        for k, p in enumerate(P):
            row = list(p) + (list(N[k]) if N is not None else [])
            fh.write(",".join(repr(float(x)) for x in row) + "\n")
    return path


# ------------------------------------------------------------------ the API
def test_torus_offsets_are_recovered_exactly():
    tor, S, N, off = torus_points()
    rep = deviation(tor, S + off[:, None] * N, tolerance=(-1, 1))
    assert np.all(rep.status == geomkit.query.results.INTERIOR)
    assert np.max(np.abs(rep.deviation - off)) < 1e-9
    assert rep.stats["within"] == int(np.count_nonzero(np.abs(off) <= 1))
    assert rep.stats["over"] == int(np.count_nonzero(off > 1))
    assert rep.stats["under"] == int(np.count_nonzero(off < -1))
    assert rep.stats["rms"] == pytest.approx(np.sqrt(np.mean(off ** 2)), abs=1e-9)
    assert rep.stats["std"] == pytest.approx(np.std(off), abs=1e-9)


@pytest.mark.parametrize("side", [1.0, -1.0])
def test_probe_radius_compensation_with_measured_normals(side):
    tor, S, N, off = torus_points(seed=2, lo=-1.0, hi=1.0)
    r = 1.5
    # ball centres on the side the measured normals point to
    C = S + (off + side * r)[:, None] * N
    rep = deviation(tor, C, normals=side * N, probe_radius=r)
    assert np.max(np.abs(rep.deviation - off)) < 1e-9


def test_probe_radius_without_normals_takes_the_normal_side():
    tor, S, N, off = torus_points(seed=3, lo=-1.0, hi=1.0)
    rep = deviation(tor, S + (off + 2.0)[:, None] * N, probe_radius=2.0)
    assert np.max(np.abs(rep.deviation - off)) < 1e-9


def test_alignment_recovers_a_known_rigid_transform():
    ff = samples.load("freeform_1")[0]
    g = np.linspace(0.05, 0.95, 15)
    uu, vv = np.meshgrid(g, g)
    S = ff.evaluate(np.column_stack([uu.ravel(), vv.ravel()]))
    T = np.eye(4)
    T[:3, :3] = Rotation.from_rotvec([0.02, -0.01, 0.03]).as_matrix()
    T[:3, 3] = (1.0, -0.5, 0.7)
    Ti = np.linalg.inv(T)
    moved = S @ Ti[:3, :3].T + Ti[:3, 3]
    a = align_rigid(ff, moved)
    assert a["converged"] and a["rank"] == 6
    assert np.abs(a["transform"] - T).max() < 1e-9
    assert a["rms_before"] > 0.1 and a["rms_after"] < 1e-9
    rep = deviation(ff, moved, align=True, tolerance=0.01 * np.array([-1, 1]))
    assert np.nanmax(np.abs(rep.deviation)) < 1e-9
    assert rep.stats["alignment"]["rms_after"] < 1e-9
    assert rep.stats["pct_within"] == 100.0


@pytest.mark.parametrize("name, free", [("sphere", 3), ("torus", 1)])
def test_alignment_leaves_free_motions_alone(name, free):
    """A sphere leaves its 3 rotations free, a torus its spin: the fit must not wander
    along them (it diverged to rms 1.7e8 on a shifted sphere) and must recover the
    shift the surface does fix (residual at rounding level)."""
    s = samples.load(name)[0]
    rng = np.random.default_rng(0)
    uv = np.column_stack([rng.uniform(*s.domain[0], 400), rng.uniform(*s.domain[1], 400)])
    P = s.evaluate(uv) + [0.3, -0.2, 0.1]
    a = align_rigid(s, P)
    assert a["converged"] and a["rank"] == 6 - free
    assert a["rms_before"] > 0.1 and a["rms_after"] < 1e-12 * s.size
    T = a["transform"]
    assert np.allclose(T[:3, :3] @ T[:3, :3].T, np.eye(3), atol=1e-12)
    Q = P @ T[:3, :3].T + T[:3, 3]
    assert geomkit.project_points(s, Q).distance.max() < 1e-12 * s.size


def test_edges_and_max_distance_are_flagged():
    ff = samples.load("freeform_1")[0]
    inside = ff.evaluate([[0.5, 0.5]])[0]
    corner = ff.evaluate([[0.0, 0.0]])[0]
    n = ff.normals([[0.5, 0.5]])[0]
    pts = [inside + 0.1 * n, corner - np.array([5.0, 0.0, 5.0]), inside + 50 * n]
    rep = deviation(ff, pts, max_distance=10.0)
    assert rep.deviation[0] == pytest.approx(0.1, abs=1e-12)
    assert rep.edge[1] and not rep.edge[0]
    assert np.isnan(rep.deviation[2]) and rep.status[2] == geomkit.query.results.BEYOND
    assert rep.stats["valid"] == 2 and rep.stats["beyond"] == 1 and rep.stats["edge"] == 1


@pytest.mark.parametrize("kwargs, field", [
    ({"points": np.empty((0, 3))}, "points"),
    ({"points": [[0, 0, np.nan]]}, "points"),
    ({"probe_radius": -1}, "probe_radius"),
    ({"tolerance": (1, -1)}, "tolerance"),
])
def test_deviation_rejects_bad_arguments(kwargs, field):
    tor = samples.load("torus")[0]
    args = dict(points=[[25.0, 0, 0]])
    args.update(kwargs)
    with pytest.raises(geomkit.InvalidInputError, match=field):
        deviation(tor, **args)


# ----------------------------------------------------------------- points I/O
def test_read_points_formats(tmp_path):
    P = np.arange(12.0).reshape(4, 3)
    a = read_points(write_xyz(tmp_path / "a.csv", P))
    assert np.array_equal(a.points, P) and a.normals is None
    (tmp_path / "b.xyz").write_text("# scan\n1 2 3 0 0 2\n4 5 6 0 3 0\n")
    b = read_points(tmp_path / "b.xyz")
    assert b.normals.tolist() == [[0, 0, 1], [0, 1, 0]]
    mesh = geomkit.tessellate(samples.load("sphere")[0], 0.5)
    mesh.export(tmp_path / "s.stl")
    mesh.export(tmp_path / "s.ply")
    for name in ("s.stl", "s.ply"):
        c = read_points(tmp_path / name)
        assert len(c) > 10
        assert np.allclose(np.linalg.norm(c.points, axis=1), 10, atol=0.5)


@pytest.mark.parametrize("text, phrase", [
    ("x,y,z\n1,2,3\n4,5\n", "line 3"),
    ("1,2,3\n4,nan,6\n", "line 2: non-finite"),
    ("1,2,3\n4,abc,6\n", "line 2: not a number"),
    ("# nothing\n", "empty point set"),
    ("", "empty point set"),
    ("a,b,c\n1,2,3\n", "header"),
])
def test_read_points_malformed(tmp_path, text, phrase):
    p = tmp_path / "bad.csv"
    p.write_text(text)
    with pytest.raises(geomkit.FileFormatError, match=phrase):
        read_points(p)


# ------------------------------------------------------------------- the CLI
@pytest.fixture(scope="module")
def torus_scan(tmp_path_factory):
    d = tmp_path_factory.mktemp("scan")
    tor, S, N, off = torus_points(n=300, seed=5, lo=-0.05, hi=0.05)
    r = 1.0
    path = write_xyz(d / "cmm.csv", S + (off + r)[:, None] * N, N)
    return d, path, off


def test_cli_deviation_end_to_end(torus_scan, tmp_path):
    d, path, off = torus_scan
    before = digest(path, samples.path("torus"))
    out = tmp_path / "rep"
    r = cli("deviation", "torus", path, "--probe-radius", "1", "--tolerance", "-0.03", "0.03",
            "-o", out, "--json")
    assert r.returncode == 0, r.stderr
    summary = json.loads(r.stdout)
    assert summary == json.loads((out / "summary.json").read_text())
    assert sorted(p.name for p in out.iterdir()) == [
        "deviation.csv", "deviation_hist.png", "deviation_map.png", "summary.json"]
    rows = list(csv.DictReader(open(out / "deviation.csv")))
    dev = np.array([float(x["deviation"]) for x in rows])
    assert np.max(np.abs(dev - off)) < 1e-9
    assert summary["within"] == int(np.count_nonzero(np.abs(off) <= 0.03))
    assert summary["pct_within"] + summary["pct_over"] + summary["pct_under"] == \
        pytest.approx(100.0)
    assert (out / "deviation_map.png").read_bytes()[:4] == b"\x89PNG"
    assert digest(path, samples.path("torus")) == before
    # a second run refuses to overwrite, and leaves the report as it was
    rep_before = digest(*sorted(out.iterdir()))
    r2 = cli("deviation", "torus", path, "-o", out)
    assert_one_line_error(r2, "exists", "--overwrite")
    assert digest(*sorted(out.iterdir())) == rep_before
    r3 = cli("deviation", "torus", path, "-o", out, "--overwrite", "--no-plots",
             "--probe-radius", "1", "--align")
    assert r3.returncode == 0, r3.stderr
    assert "alignment: rms" in r3.stdout


def test_cli_distance_and_section(tmp_path, torus_scan):
    d, path, off = torus_scan
    r = cli("distance", "torus", path, "-o", tmp_path / "dist.csv", "--json")
    assert r.returncode == 0, r.stderr
    info = json.loads(r.stdout)
    rows = list(csv.DictReader(open(tmp_path / "dist.csv")))
    dist = np.array([float(x["signed_distance"]) for x in rows])
    assert np.max(np.abs(dist - (off + 1.0))) < 1e-9 and info["matched"] == len(off)
    # a family of sections of the torus: z = const planes give circles
    r = cli("section", "torus", "--plane", "0", "0", "1", "0", "--step", "2", "--count", "3",
            "-o", tmp_path / "cuts", "--json")
    assert r.returncode == 0, r.stderr
    s = json.loads(r.stdout)
    names = sorted(p.name for p in (tmp_path / "cuts").iterdir())
    assert names == sorted([f"section_{k:03d}.{e}" for k in range(3)
                            for e in ("csv", "dxf", "json")]
                           + ["sections.png", "section_summary.json"])
    for k, row in enumerate(s["planes"]):
        assert row["curves"] == 2 and row["closed"] == 2   # two circles at each height
        assert row["plane"][3] == pytest.approx(-2.0 * k)
    from geomkit.section.export import read_csv
    curves, _ = read_csv(tmp_path / "cuts" / "section_001.csv")
    rad = sorted(float(np.mean(np.hypot(c[:, 0], c[:, 1]))) for c in curves)
    h = np.sqrt(25 - 4.0)
    assert rad == pytest.approx([20 - h, 20 + h], abs=1e-3)


def test_cli_demo(tmp_path):
    r = cli("demo", "--json", cwd=tmp_path)
    assert r.returncode == 0, r.stderr
    s = json.loads(r.stdout)
    out = tmp_path / "geomkit-demo"
    assert sorted(p.name for p in out.iterdir()) == s["files"]
    assert s["bump"]["found_max"] == pytest.approx(s["bump"]["height"], abs=0.005)
    assert s["bump"]["found_distance"] < 3.0
    assert s["bump"]["max_error_vs_truth"] < 1e-9
    assert s["alignment_check"]["transform_error"] < 1e-9
    assert s["section"]["curves"] == 5
    assert 0 < s["deviation"]["pct_over"] < 10
    c = s["clearance"]
    assert c["certified"] and c["travel_moves"] == 3
    assert c["travel_min_lower_bound"] <= c["travel_min_clearance"]
    # the tip centre at the reported first contact is one tip radius from the surface
    # (checked by project_points, another engine)
    assert abs(c["tip_distance_at_contact"] - 1.0) < 1e-6
    assert c["plunge_contact_component"] == "tip"
    # reruns replace its own reports; each step is printed as it finishes, not at the
    # end: when step 2 starts, step 1's result is on stdout and step 4's report is not
    # written yet
    import subprocess
    import sys

    (out / "clearance.csv").unlink()
    p = subprocess.Popen([sys.executable, "-m", "geomkit", "demo"], cwd=tmp_path,
                         env=dict(os.environ, PYTHONPATH=str(ROOT)),
                         stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    seen = []
    for line in p.stdout:
        seen.append(line)
        if line.startswith("[2/5] alignment"):
            assert not (out / "clearance.csv").exists(), "step 4 ran before step 2 showed"
            break
    rest, err = p.communicate(timeout=600)
    text = "".join(seen) + rest
    assert p.returncode == 0 and err == "", err
    assert any(ln.startswith("bump ") for ln in seen), seen   # step 1's result came first
    steps = [ln.split()[0] for ln in text.splitlines() if ln.startswith("[")]
    assert steps == ["[1/5]", "[2/5]", "[3/5]", "[4/5]", "[5/5]"]
    assert re.search(r"plunge first contact .*\(\d+\.\d s\)$", text, re.M)
    assert re.search(r"^reports .*deviation_report.html.*\(\d+\.\d s\)$", text, re.M)
    assert (out / "clearance.csv").exists()


# -------------------------------------------------------------- bad inputs
def test_cli_bad_inputs_give_one_line_and_change_nothing(tmp_path, torus_scan):
    d, good, _ = torus_scan
    nan = tmp_path / "nan.csv"
    nan.write_text("1,2,3\n4,nan,6\n")
    mal = tmp_path / "mal.csv"
    mal.write_text("1,2,3\n4,5\n")
    empty = tmp_path / "empty.xyz"
    empty.write_text("# no points\n")
    badsurf = tmp_path / "bad.json"
    tor = samples.load("torus")[0].to_dict()
    tor["knots_u"] = tor["knots_u"][::-1]
    badsurf.write_text(json.dumps({"format": "geomkit-case/1", "surfaces": [tor]}))
    ro = tmp_path / "ro"
    ro.mkdir()
    ro.chmod(0o500)
    inputs = [nan, mal, empty, badsurf, good]
    before = digest(*inputs)
    cases = [
        (("deviation", "torus", tmp_path / "missing.csv"), ("no such file",)),
        (("deviation", tmp_path / "missing.json", good), ("no such file",)),
        (("deviation", "torus", mal), ("line 2", "expected 3 columns")),
        (("deviation", "torus", nan), ("line 2", "non-finite")),
        (("deviation", "torus", empty), ("empty point set",)),
        (("deviation", badsurf, good), ("knots_u",)),
        (("deviation", "torus", good, "--tolerance", "1", "-1"), ("--tolerance",)),
        (("distance", "torus", nan), ("non-finite",)),
        (("section", badsurf, "--plane", "0", "0", "1", "0"), ("knots_u",)),
        (("section", "torus", "--plane", "0", "0", "0", "1"), ("plane",)),
        (("section", "torus", "--plane", "0", "0", "1", "0", "--count", "3"), ("--step",)),
    ]
    # a folder that cannot be created (its parent is a file): fails for root too
    cases.append((("deviation", "torus", good, "-o", good / "out"), ("cannot write",)))
    if os.geteuid() != 0:  # root writes anywhere
        cases.append((("deviation", "torus", good, "-o", ro / "out"), ("cannot write",)))
        cases.append((("section", "torus", "--plane", "0", "0", "1", "0", "-o", ro),
                      ("cannot write",)))
    for argv, phrases in cases:
        r = cli(*argv, cwd=tmp_path)
        assert_one_line_error(r, *phrases)
    assert digest(*inputs) == before
    assert list(ro.iterdir()) == []
    ro.chmod(0o700)


def test_cli_output_may_not_replace_an_input(tmp_path):
    P = samples.load("torus")[0].evaluate([[0.1, 0.2], [0.3, 0.4]])
    pts = write_xyz(tmp_path / "deviation.csv", P)
    before = digest(pts)
    r = cli("deviation", "torus", pts, "-o", tmp_path, "--overwrite")
    assert_one_line_error(r, "is an input")
    assert digest(pts) == before


def test_help_lists_the_jobs():
    r = cli("--help")
    assert r.returncode == 0
    for word in ("deviation", "distance", "section", "demo", "geomkit deviation part.igs"):
        assert word in r.stdout
