"""Bad-input edges of the command line (in process): one line and exit 2, the output
target checked before any work, no folder created or left behind by a failed run, no
temporary file name in a message, no NaN statistics from an empty match."""

from __future__ import annotations

from pathlib import Path

import pytest

import geomkit

from helpers.clihelp import run_main as run, write_rows


def one_line(rc, out, err, *phrases):
    assert rc == 2, (rc, out, err)
    assert err.startswith("geomkit: error: ") and err.count("\n") == 1, err
    assert "Traceback" not in err and ".tmp" not in err
    for ph in phrases:
        assert ph in err, (ph, err)


@pytest.fixture
def far(tmp_path):
    """Two points 5 above plate_with_hole (z = 0)."""
    return write_rows(tmp_path / "far.xyz", [[10, 10, 5], [20, 20, 5]])


def test_mesh_to_an_unknown_format_fails_before_tessellating(tmp_path, capsys,
                                                             monkeypatch):
    def boom(*a, **k):
        raise AssertionError("tessellated before checking the output")

    monkeypatch.setattr(geomkit, "tessellate", boom)
    rc, out, err = run(capsys, "mesh", "sphere", "--tol", "0.1", "-o", tmp_path / "x.step")
    one_line(rc, out, err, "x.step", ".stl")
    assert list(tmp_path.iterdir()) == []


@pytest.mark.skipif(not Path("/proc/self").is_dir(), reason="needs Linux /proc")
def test_mesh_into_an_unwritable_folder_names_no_temporary_file(capsys, monkeypatch):
    monkeypatch.setattr(geomkit, "tessellate", lambda *a, **k: 1 / 0)
    rc, out, err = run(capsys, "mesh", "sphere", "--tol", "0.1", "-o", "/proc/t.stl")
    one_line(rc, out, err, "/proc", "cannot write")


@pytest.mark.parametrize("job", ["mesh", "distance"])
def test_a_file_target_in_a_missing_folder_is_an_error(tmp_path, capsys, far, job):
    target = tmp_path / "no" / "dir" / "t.stl"
    argv = (["mesh", "sphere", "--tol", "0.5", "-o", target] if job == "mesh" else
            ["distance", "plate_with_hole", far, "-o", target.with_suffix(".csv")])
    rc, out, err = run(capsys, *argv)
    one_line(rc, out, err, "no such folder")
    assert not (tmp_path / "no").exists()


def test_failed_validations_leave_no_output_folder(tmp_path, capsys, far):
    one = write_rows(tmp_path / "one.xyz", [[0, 0, 30]])
    path = write_rows(tmp_path / "path.xyz", [[0, 0, 30], [10, 0, 30]])
    out = tmp_path / "rep"
    cases = [
        (("deviation", "plate_with_hole", far, "--tolerance", "nan"), "--tolerance"),
        (("deviation", "plate_with_hole", far, "--tolerance", "0"), "--tolerance"),
        (("deviation", "plate_with_hole", far, "--tolerance", "0.1", "0.1"), "--tolerance"),
        (("clearance", "torus", one, "--stylus", "1,0.5,5"), "at least 2"),
        (("clearance", "torus", path, "--stylus", "1,0.5,5", "--axis", "0", "0", "0"),
         "axis"),
        (("section", "torus", "--plane", "0", "0", "0", "1"), "plane"),
    ]
    for argv, phrase in cases:
        rc, o, err = run(capsys, *argv, "-o", out / "deep")
        one_line(rc, o, err, phrase)
        assert not out.exists(), f"{argv} left {out}"


def test_deviation_with_nothing_within_max_distance_is_an_error(tmp_path, capsys, far):
    out = tmp_path / "rep"
    rc, o, err = run(capsys, "deviation", "plate_with_hole", far, "--max-distance", "1",
                     "-o", out)
    one_line(rc, o, err, "--max-distance", "none of the 2 point(s) is within 1")
    assert not out.exists()
    # and when they are within it, the same run reports real statistics
    rc, o, err = run(capsys, "deviation", "plate_with_hole", far, "--max-distance", "6",
                     "-o", out, "--no-plots")
    assert rc == 0, err
    assert "2 matched" in o and "nan" not in o.lower()


def test_distance_with_nothing_matched_says_so(capsys, far):
    rc, o, err = run(capsys, "distance", "plate_with_hole", far, "--max-distance", "1")
    assert rc == 0 and err == ""
    assert "none matched within --max-distance 1" in o and "nan" not in o.lower()


def test_empty_iges_file_is_one_line_exit_2(tmp_path, capsys):
    pytest.importorskip("pyiges")
    p = tmp_path / "empty.igs"
    p.write_bytes(b"")
    rc, out, err = run(capsys, "info", p)
    one_line(rc, out, err, "empty.igs")
    assert p.read_bytes() == b""
