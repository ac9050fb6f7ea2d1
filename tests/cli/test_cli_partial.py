"""A job run on part of a model (``--skip-unsupported``) never looks complete: the
summary JSON lists the faces left out, the console says so before any result, and the
report titles carry the note (issue 14, "no silent loss")."""

from __future__ import annotations

import json

import pytest

from geomkit.cli import _common, clearance, jobs, main
from geomkit.cad.iges.reader import Skipped


@pytest.fixture
def partial(monkeypatch):
    """The bundled sphere read as if two faces of its file had been left out."""
    real = _common._load_input

    def load(name, *a, **k):
        case = real(name, *a, **k)
        case.skipped = [Skipped("140@17", "offset surface: unsupported"),
                        Skipped("198@31", "torus: unsupported")]
        return case

    monkeypatch.setattr(jobs, "_load_input", load)
    monkeypatch.setattr(clearance, "_load_input", load)


def test_model_info_whole_and_partial():
    from geomkit.exchange.cases import Case

    info, note = _common._model_info(Case("a", [object()] * 3))
    assert info == {"faces": 3, "faces_left_out": 0, "complete": True} and note is None
    c = Case("a", [object()] * 3, skipped=[Skipped("144@9", "invalid: x")])
    info, note = _common._model_info(c)
    assert info["complete"] is False and info["faces_left_out"] == 1
    assert info["left_out"] == ["144@9: invalid: x"]
    assert note.startswith("PARTIAL MODEL: 1 of 4 faces left out") and "144@9" in note


def test_deviation_on_a_partial_model_says_so_everywhere(tmp_path, capsys, partial):
    pts = tmp_path / "p.xyz"
    pts.write_text("0 0 10.5\n0 10.2 0\n")
    out = tmp_path / "rep"
    rc = main(["deviation", "sphere", str(pts), "-o", str(out), "--report", "html"])
    stdout, err = capsys.readouterr()
    assert rc == 0, err
    assert "PARTIAL MODEL: 2 of 3 faces left out" in stdout
    doc = json.loads((out / "summary.json").read_text())
    assert doc["model"]["complete"] is False
    assert doc["model"]["left_out"] == ["140@17: offset surface: unsupported",
                                        "198@31: torus: unsupported"]
    html = next(out.glob("*.html")).read_text()
    assert "PARTIAL MODEL: 2 of 3 faces left out" in html


def test_clearance_on_a_partial_model_warns_before_the_verdict(tmp_path, capsys, partial):
    path = tmp_path / "path.xyz"
    path.write_text("0 0 20\n5 0 20\n")
    out = tmp_path / "cl"
    rc = main(["clearance", "sphere", str(path), "--stylus", "1,0.5,10", "-o", str(out)])
    stdout, _ = capsys.readouterr()
    assert rc == 0
    lines = stdout.splitlines()
    assert lines[0].startswith("PARTIAL MODEL") and "NOT checked" in lines[0]
    doc = json.loads((out / "clearance_summary.json").read_text())
    assert doc["model"]["faces_left_out"] == 2 and not doc["model"]["complete"]


def test_whole_model_summary_says_complete(tmp_path, capsys):
    pts = tmp_path / "p.xyz"
    pts.write_text("0 0 10.5\n")
    out = tmp_path / "rep"
    assert main(["deviation", "sphere", str(pts), "-o", str(out), "--no-plots"]) == 0
    assert "PARTIAL" not in capsys.readouterr().out
    doc = json.loads((out / "summary.json").read_text())
    assert doc["model"] == {"faces": 1, "faces_left_out": 0, "complete": True}


def test_streamed_deviation_carries_units_and_the_partial_model(tmp_path, capsys, partial,
                                                                monkeypatch):
    import numpy as np

    from geomkit.cli import scale

    monkeypatch.setattr(scale, "_load_input", jobs._load_input)
    pts = tmp_path / "p.npy"
    np.save(pts, np.array([[0, 0, 10.5], [0, 10.2, 0]]))
    out = tmp_path / "st"
    rc = main(["deviation", "sphere", str(pts), "-o", str(out), "--units", "mm"])
    stdout, err = capsys.readouterr()
    assert rc == 0, err
    assert stdout.startswith("PARTIAL MODEL: 2 of 3 faces left out")
    doc = json.loads((out / "summary.json").read_text())
    assert doc["units"] == "mm" and doc["model"]["faces_left_out"] == 2
