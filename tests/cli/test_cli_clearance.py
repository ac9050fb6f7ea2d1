"""`geomkit clearance` end to end (subprocess): bundled torus, the impeller IGES, bad
inputs.  The impeller answer is checked against project_points (a different engine:
voxel candidates + Newton feet) on densely sampled tip positions."""

from __future__ import annotations

import csv
import json
from pathlib import Path

import numpy as np
import pytest

import geomkit

from helpers.clihelp import assert_one_line_error, cli, digest


def write_path(p: Path, P):
    p.write_text("x,y,z\n" + "".join(",".join(repr(float(c)) for c in q) + "\n" for q in P))
    return p


def test_cli_clearance_torus_pass_and_fail(tmp_path):
    ok = write_path(tmp_path / "ok.csv", [[-30, 0, 10], [30, 0, 10], [30, 0, 3]])
    r = cli("clearance", "torus", ok, "--stylus", "1,0.5,20,2,30", "--margin", "3.9",
            "-o", tmp_path / "rep", "--json")
    assert r.returncode == 0, r.stderr
    s = json.loads(r.stdout)
    assert s["passed"] and s["segments"] == 2
    assert abs(s["min_clearance"] - 4.0) < 1e-6 and s["min_clearance_lower_bound"] <= 4.0
    names = sorted(p.name for p in (tmp_path / "rep").iterdir())
    assert names == ["clearance.csv", "clearance.png", "clearance_summary.json"]
    rows = list(csv.DictReader(open(tmp_path / "rep" / "clearance.csv")))
    assert len(rows) == 2 and rows[0]["component"] == "tip" and rows[0]["passed"] == "1"

    bad = write_path(tmp_path / "plunge.csv", [[20, 0, 10], [20, 0, 0]])
    stylus = tmp_path / "stylus.json"
    stylus.write_text(json.dumps({"tip_radius": 1, "shaft_radius": 0.5, "shaft_length": 20}))
    before = digest(bad, stylus)
    r = cli("clearance", "torus", bad, "--stylus", stylus, "-o", tmp_path / "rep2")
    assert r.returncode == 1, r.stderr  # a failing check: exit 1, not an error
    assert "FAIL" in r.stdout and "first contact at parameter 0.4000000" in r.stdout
    s = json.loads((tmp_path / "rep2" / "clearance_summary.json").read_text())
    assert s["first_contact"]["segment"] == 0
    assert abs(s["first_contact"]["parameter"] - 0.4) < 1e-8
    assert digest(bad, stylus) == before
    # a rerun refuses to overwrite the report
    r = cli("clearance", "torus", bad, "--stylus", stylus, "-o", tmp_path / "rep2")
    assert_one_line_error(r, "exists", "--overwrite")


def test_cli_clearance_probing_moves(tmp_path):
    """Travel over the torus, then a plunge meant to touch (--probing -1): the run passes
    on the travel moves, the plunge reports its first contact (tip, at 0.4 of the move:
    tip sphere of radius 1 from z = 10 to z = 0 over the tube top at z = 5 + ... 4 + 1)."""
    P = write_path(tmp_path / "p.csv", [[-30, 0, 10], [20, 0, 10], [20, 0, 0]])
    r = cli("clearance", "torus", P, "--stylus", "1,0.5,20", "--margin", "2",
            "--probing", "-1", "-o", tmp_path / "rep")
    assert r.returncode == 0, r.stdout + r.stderr
    assert "1 travel move(s): PASS" in r.stdout
    assert "probing move 1: first contact at parameter 0.4000000" in r.stdout
    s = json.loads((tmp_path / "rep" / "clearance_summary.json").read_text())
    assert s["travel_passed"] and not s["passed"] and s["travel_worst_move"] == 0
    assert s["probing_moves"][0]["move"] == 1
    assert abs(s["probing_moves"][0]["first_contact"] - 0.4) < 1e-8
    # without --probing the same path fails (exit 1), as before
    r = cli("clearance", "torus", P, "--stylus", "1,0.5,20", "--margin", "2",
            "-o", tmp_path / "rep2", "--no-plots")
    assert r.returncode == 1 and "FAIL" in r.stdout
    r = cli("clearance", "torus", P, "--stylus", "1,0.5,20", "--probing", "2",
            "-o", tmp_path / "rep3")
    assert_one_line_error(r, "--probing", "out of range")
    assert not (tmp_path / "rep3").exists()


def test_cli_clearance_bad_inputs(tmp_path):
    good = write_path(tmp_path / "p.csv", [[-30, 0, 10], [30, 0, 10]])
    one = write_path(tmp_path / "one.csv", [[-30, 0, 10]])
    nan = tmp_path / "nan.csv"
    nan.write_text("0,0,10\n1,nan,10\n")
    screw = tmp_path / "screw.json"
    T = np.eye(4)
    T[:3, :3] = [[0, -1, 0], [1, 0, 0], [0, 0, 1]]
    T[2, 3] = 3.0
    screw.write_text(json.dumps({"poses": [np.eye(4).tolist(), T.tolist()]}))
    badstylus = tmp_path / "s.json"
    badstylus.write_text('{"tip_radius": 1, "shaft_radius": 1}')
    inputs = [good, one, nan, screw, badstylus]
    before = digest(*inputs)
    cases = [
        (("torus", tmp_path / "missing.csv", "--stylus", "1,0.5,20"), ("no such file",)),
        (("torus", good, "--stylus", "1,0.5"), ("--stylus", "3, 5 or 7")),
        (("torus", good, "--stylus", "1,-0.5,20"), ("stylus.shaft_radius",)),
        (("torus", good, "--stylus", badstylus), ("missing", "shaft_length")),
        (("torus", one, "--stylus", "1,0.5,20"), ("at least 2",)),
        (("torus", nan, "--stylus", "1,0.5,20"), ("non-finite",)),
        (("torus", screw, "--stylus", "1,0.5,20"), ("screw",)),
        (("torus", good, "--stylus", "1,0.5,20", "--axis", "0", "0", "0"), ("axis",)),
        (("torus", good, "--stylus", "1,0.5,20", "-o", good / "sub"), ("cannot write",)),
    ]
    for argv, phrases in cases:
        r = cli("clearance", *argv, cwd=tmp_path)
        assert_one_line_error(r, *phrases)
    assert digest(*inputs) == before


pyiges = pytest.importorskip("pyiges")


def test_cli_clearance_on_the_impeller(tmp_path):
    from pyiges import examples

    from geomkit.cad.iges.reader import read_iges

    surfaces = read_iges(examples.impeller, skip_invalid=True).surfaces
    lo = np.min([s.bounds[0] for s in surfaces], axis=0)
    hi = np.max([s.bounds[1] for s in surfaces], axis=0)
    c = 0.5 * (lo + hi)
    # over the top, then down beside the hub; a tiny shaft pointing up keeps the tip the
    # closest piece, so the oracle is the tip centre's distance to the part minus r
    P = np.array([[lo[0] - 5, c[1], hi[2] + 4], [hi[0] + 5, c[1] + 10, hi[2] + 4],
                  [hi[0] + 5, c[1] + 10, lo[2]]])
    path = write_path(tmp_path / "path.csv", P)
    r = cli("clearance", examples.impeller, path, "--stylus", "2,0.1,0.5", "--skip-invalid",
            "-o", tmp_path / "rep", "--json", "--no-plots")
    assert r.returncode in (0, 1), r.stderr
    s = json.loads(r.stdout)
    rows = list(csv.DictReader(open(tmp_path / "rep" / "clearance.csv")))
    for i, row in enumerate(rows):
        t = np.linspace(0.0, 1.0, 1501)[:, None]
        tips = P[i] + t * (P[i + 1] - P[i])
        d = geomkit.project_points(surfaces, tips).distance - 2.0
        upper, lower = float(row["clearance"]), float(row["lower_bound"])
        assert row["component"] == "tip"
        assert lower <= d.min() + 1e-9           # certified below every sampled gap
        step = np.linalg.norm(P[i + 1] - P[i]) / 1500
        assert upper <= d.min() + 1e-9 and upper >= d.min() - step  # attained, near
    assert s["surfaces"] == 277 and s["model"]["complete"]  # every face read (issue 14)
