"""With ``--json`` stdout is JSON for every run: the result, or ``{"error", "exit_code"}``
when the run fails (bad argument, missing or malformed file); warnings are one
``geomkit: warning:`` line each on stderr and the result's ``warnings`` list."""

from __future__ import annotations

import json
import warnings

import pytest

from geomkit.errors import FaceFailedWarning
from helpers.clihelp import run_main
from helpers.paths import DATA


@pytest.mark.parametrize("argv, phrase", [
    (["info", "missing.stp", "--json"], "no such file"),
    (["deviation", "sphere", "pts.csv", "--json", "--bogus"], "unrecognized arguments"),
    (["mesh", "sphere", "--json"], "required"),
    (["section", "sphere", "--plane", "0", "0", "0", "1", "--json"], "plane"),
])
def test_failed_runs_print_json(capsys, tmp_path, monkeypatch, argv, phrase):
    monkeypatch.chdir(tmp_path)
    rc, out, err = run_main(capsys, *argv)
    assert rc == 2
    doc = json.loads(out)
    assert doc["exit_code"] == 2 and phrase in doc["error"]
    assert err.startswith("geomkit: error: ") and err.count("\n") == 1
    assert phrase in err


def test_a_malformed_step_file_prints_json(capsys, tmp_path):
    text = (DATA / "parts" / "nx9_face_recognition_ap214.stp").read_text(encoding="latin-1")
    bad = tmp_path / "bad.stp"
    i = text.index(";\n#40=")
    bad.write_text(text[:i] + "\n" + text[i + 2:], encoding="latin-1")
    rc, out, err = run_main(capsys, "info", bad, "--json")
    assert rc == 2 and "#39" in json.loads(out)["error"] and "#39" in err


def test_warnings_are_one_line_and_in_the_json(capsys, monkeypatch):
    import geomkit.cli.jobs as jobs

    real = jobs._load_input

    def load(*a, **k):
        warnings.warn("face 3 left out: planted", FaceFailedWarning)
        return real(*a, **k)

    monkeypatch.setattr(jobs, "_load_input", load)
    rc, out, err = run_main(capsys, "info", "sphere", "--json")
    assert rc == 0
    assert json.loads(out)["warnings"] == ["face 3 left out: planted"]
    assert err == "geomkit: warning: face 3 left out: planted\n"
    rc, out, err = run_main(capsys, "info", "sphere")      # the same without --json
    assert rc == 0 and err == "geomkit: warning: face 3 left out: planted\n"
    monkeypatch.setattr(jobs, "_load_input", real)
    rc, out, err = run_main(capsys, "info", "sphere", "--json")
    assert "warnings" not in json.loads(out) and err == ""  # none left from the last run
