"""The ``geomkit`` command line: demo, info, samples, and clean one-line errors."""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import geomkit
from geomkit import samples
from geomkit.cli import main

from helpers.clihelp import run_main as run

PLATE_TRUTH = 8743.362938564083 / 10000.0


def assert_one_line_error(rc, out, err, *phrases):
    assert rc == 2, (rc, out, err)
    assert out == ""
    assert err.startswith("geomkit: error: "), err
    assert err.endswith("\n") and err.count("\n") == 1, f"not one line: {err!r}"
    assert "Traceback" not in err
    for ph in phrases:
        assert ph in err, f"{ph!r} not in {err!r}"


# ------------------------------------------------------------------------ demo
# the demo's deviation / section report is tested in tests/jobs/test_jobs.py


@pytest.mark.parametrize("grid", ["0", "-3"])
def test_demo_rejects_bad_grid(capsys, grid):
    try:
        rc = main(["demo", "--grid", grid])
    except SystemExit as e:  # an argparse usage error is fine too
        rc = e.code
    out, err = capsys.readouterr()
    assert rc == 2 and "Traceback" not in err and err.strip()


# ------------------------------------------------------------------------ info
def test_info_on_a_sample_path(capsys):
    path = str(samples.path("plate_with_hole"))
    rc, out, err = run(capsys, "info", path)
    assert rc == 0 and err == ""
    (line,) = out.strip().splitlines()
    assert line.startswith("plate_with_hole: B-spline degree [1, 1], net [2, 2]")
    assert "domain [[0.0, 1.0], [0.0, 1.0]]" in line and "2 trim loop(s)" in line
    assert "bounds [[0.0, 0.0, 0.0], [100.0, 100.0, 0.0]]" in line


def test_info_json_on_a_multi_surface_sample(capsys):
    rc, out, err = run(capsys, "info", str(samples.path("sphere_plane_cut")), "--json")
    assert rc == 0 and err == ""
    doc = json.loads(out)
    assert doc["name"] == "sphere_plane_cut"
    want = samples.load("sphere_plane_cut")
    assert [s["name"] for s in doc["surfaces"]] == [s.name for s in want]
    for d, s in zip(doc["surfaces"], want):
        assert d["rational"] == s.is_rational
        assert d["degree"] == [s.degree_u, s.degree_v]
        assert d["control_net"] == list(s.shape)
        assert d["domain"] == [list(s.domain[0]), list(s.domain[1])]
        assert d["trim_loops"] == 0
        np.testing.assert_array_equal(d["bounds"], s.bounds)


def test_info_on_a_saved_geomdl_file(capsys, tmp_path):
    p = geomkit.save(tmp_path / "t.json", samples.load("torus"), format="geomdl")
    rc, out, err = run(capsys, "info", str(p))
    assert rc == 0 and out.startswith("-: NURBS degree [2, 2], net [9, 9]")


def test_samples_lists_every_sample(capsys):
    rc, out, err = run(capsys, "samples")
    assert rc == 0 and err == ""
    lines = out.strip().splitlines()
    assert [ln.split()[0] for ln in lines] == samples.names()
    (plate,) = [ln for ln in lines if ln.startswith("plate_with_hole")]
    assert samples.load_case("plate_with_hole").description in plate


# ---------------------------------------------------------------- bad input files
def _bad_files(tmp_path: Path):
    good = {"degree_u": 1, "degree_v": 1, "knots_u": [0, 0, 1, 1], "knots_v": [0, 0, 1, 1],
            "control_points": [[[0, 0, 0], [0, 1, 0]], [[1, 0, 0], [1, 1, 0]]]}
    files = {}

    def put(name, content):
        p = tmp_path / name
        p.write_bytes(content if isinstance(content, bytes) else content.encode())
        files[name] = p

    put("invalid.json", '{"surfaces": [1,,]}')
    put("binary.json", b"\xff\xfe\x00\x01")
    put("unknown_format.json", json.dumps({"format": "step/3", "surfaces": [good]}))
    put("no_surfaces.json", json.dumps({"name": "x"}))
    put("missing_field.json", json.dumps({"surfaces": [{"degree_u": 1}]}))
    put("bad_knots.json", json.dumps({"surfaces": [dict(good, knots_u=[0, 1])]}))
    put("bad_weights.json", json.dumps({"surfaces": [dict(good, weights=[[1, 1], [1, -2]])]}))
    put("open_trim.json", json.dumps({"surfaces": [dict(good, trim=[[[.1, .1], [.9, .1],
                                                                     [.5, .9]]])]}))
    put("nan.json", '{"surfaces": [{"degree_u": 1, "degree_v": 1, "knots_u": [0, 0, 1, 1], '
                    '"knots_v": [0, 0, 1, 1], "control_points": [[[NaN, 0, 0], [0, 1, 0]], '
                    '[[1, 0, 0], [1, 1, 0]]]}]}')
    return files


EXPECTED_PHRASES = {
    "invalid.json": ["invalid JSON", "line 1, column"],
    "binary.json": ["not a text file"],
    "unknown_format.json": ["unknown format 'step/3'"],
    "no_surfaces.json": ["no 'surfaces'"],
    "missing_field.json": ["surfaces[0]", "missing field"],
    "bad_knots.json": ["surfaces[0].knots_u", "n + p + 1"],
    "bad_weights.json": ["surfaces[0].weights", "> 0"],
    "open_trim.json": ["surfaces[0].trim[0]", "loop is open"],
    "nan.json": ["surfaces[0].control_points", "non-finite"],
}


@pytest.mark.parametrize("name", sorted(EXPECTED_PHRASES))
def test_info_bad_file_is_a_one_line_error(capsys, tmp_path, name):
    p = _bad_files(tmp_path)[name]
    before = p.read_bytes()
    rc, out, err = run(capsys, "info", str(p))
    assert_one_line_error(rc, out, err, str(p), *EXPECTED_PHRASES[name])
    assert p.read_bytes() == before


def test_info_missing_file_and_directory(capsys, tmp_path):
    rc, out, err = run(capsys, "info", str(tmp_path / "missing.json"))
    assert_one_line_error(rc, out, err, "no such file", "missing.json")
    rc, out, err = run(capsys, "info", str(tmp_path))
    assert_one_line_error(rc, out, err, "is a directory")


def test_info_malformed_geomdl_file(capsys, tmp_path):
    p = tmp_path / "g.json"
    p.write_text('{"shape": 5}')
    rc, out, err = run(capsys, "info", str(p))
    assert_one_line_error(rc, out, err, str(p))


def test_info_unusable_path(capsys, tmp_path):
    rc, out, err = run(capsys, "info", str(tmp_path / ("x" * 300 + ".json")))
    assert_one_line_error(rc, out, err)


@pytest.mark.parametrize("argv, phrase", [
    ([], "no command given"), (["bogus"], "invalid choice: 'bogus'"),
    (["demo", "--grid", "x"], "demo: argument --grid"), (["info"], "info: the following"),
    (["mesh", "sphere", "--tol", "0", "-o", "x.stl"], "mesh: argument --tol"),
    (["section", "sphere", "--plane", "0", "0", "1"], "section: argument --plane"),
    (["deviation", "sphere", "p.csv", "--probe-radius", "-1"], "--probe-radius"),
    (["deviation", "sphere", "p.csv", "--max-distance", "0"], "--max-distance"),
    (["distance", "sphere", "p.csv", "--max-distance", "0"], "--max-distance"),
    (["clearance", "sphere", "p.csv", "--stylus", "1,1,1", "--margin", "-2"], "--margin"),
    (["clearance", "sphere", "p.csv", "--stylus", "1,1,1", "--tol", "nan"], "--tol"),
    (["section", "sphere", "--plane", "0", "0", "1", "0", "--units", "furlong"], "furlong"),
    (["bench", "--nope"], "unrecognized arguments: --nope")])
def test_usage_errors_are_one_line_exit_2(capsys, tmp_path, monkeypatch, argv, phrase):
    """argparse's own errors too: one line, exit 2, no usage block, nothing written."""
    monkeypatch.chdir(tmp_path)
    rc, out, err = run(capsys, *argv)
    assert_one_line_error(rc, out, err, phrase)
    assert "usage:" not in err
    assert list(tmp_path.iterdir()) == []


def test_help_shows_examples(capsys):
    rc = main(["--help"])
    assert rc == 0
    out, _ = capsys.readouterr()
    assert "geomkit demo" in out and "geomkit info part.json" in out


# ------------------------------------------------------------------ subprocesses
def _run_proc(cmd, cwd):
    env = dict(os.environ, PYTHONWARNINGS="ignore")
    return subprocess.run(cmd, cwd=cwd, env=env, capture_output=True, text=True, timeout=300)


def test_module_entry_point_in_a_subprocess(tmp_path):
    base = [sys.executable, "-m", "geomkit.cli"]
    r = _run_proc(base + ["samples"], tmp_path)
    assert r.returncode == 0, r.stderr
    assert [ln.split()[0] for ln in r.stdout.strip().splitlines()] == samples.names()
    r = _run_proc(base + ["info", "nope.json"], tmp_path)
    assert r.returncode == 2 and r.stdout == ""
    assert r.stderr.startswith("geomkit: error: ") and r.stderr.count("\n") == 1
    assert "no such file" in r.stderr and "Traceback" not in r.stderr


def test_installed_console_script(tmp_path):
    exe = shutil.which("geomkit", path=os.pathsep.join(
        [str(Path(sys.executable).parent), os.environ.get("PATH", "")]))
    if exe is None:
        pytest.skip("the geomkit console script is not installed")
    r = _run_proc([exe, "info", str(samples.path("sphere"))], tmp_path)
    assert r.returncode == 0, r.stderr
    assert r.stdout.startswith("sphere: NURBS degree [2, 2], net [9, 5]")
    r = _run_proc([exe, "info", str(tmp_path)], tmp_path)
    assert r.returncode == 2 and "Traceback" not in r.stderr
    assert r.stderr.startswith("geomkit: error: ")
