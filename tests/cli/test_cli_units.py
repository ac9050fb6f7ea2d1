"""Units carried end to end by the command line: from the file (geomkit-case JSON
``units``; IGES/STEP readers' ``units``) or ``--units``, into the summaries, the
console, CSV headers/columns and the DXF header ($INSUNITS: mm 4, in 1, unknown 0)."""

from __future__ import annotations

import csv
import json
from pathlib import Path

import pytest

from geomkit import FileFormatError, samples
from geomkit.exchange.cases import load_case, save
from geomkit.units import canonical_units, dxf_insunits

from helpers.clihelp import run_main

ezdxf = pytest.importorskip("ezdxf")


def run(capsys, *argv):
    rc, out, err = run_main(capsys, *argv)
    assert rc == 0, err
    return out


@pytest.fixture
def plate_mm(tmp_path):
    p = tmp_path / "plate.json"
    save(p, samples.load("plate_with_hole"), units="millimetres")
    return p


def test_case_json_units_round_trip(tmp_path, plate_mm):
    assert json.loads(plate_mm.read_text())["units"] == "mm"
    assert load_case(plate_mm).units == "mm"
    assert samples.load_case("plate_with_hole").units is None  # not stated: unknown
    bad = tmp_path / "bad.json"
    doc = json.loads(plate_mm.read_text())
    for value, phrase in ((5, "must be a string"), ("furlong", "unknown length unit")):
        doc["units"] = value
        bad.write_text(json.dumps(doc))
        with pytest.raises(FileFormatError, match=phrase):
            load_case(bad)


@pytest.mark.parametrize("text, name, code", [("mm", "mm", 4), ("Inch", "in", 1),
                                               ("m", "m", 6), ("cm", "cm", 5),
                                               ("ft", "ft", 2), ("µm", "um", 13)])
def test_unit_names_and_dxf_codes(text, name, code):
    assert canonical_units(text) == name and dxf_insunits(name) == code


def _section(capsys, tmp_path, case, *extra):
    out = tmp_path / "cut"
    text = run(capsys, "section", case, "--plane", "1", "0", "0", "-50", "-o", out,
               "--formats", "csv,dxf", *extra)
    rows = list(csv.DictReader(open(out / "section.csv")))
    doc = ezdxf.readfile(out / "section.dxf")
    summary = json.loads((out / "section_summary.json").read_text())
    return text, rows, doc.header["$INSUNITS"], summary


def test_section_states_the_models_units(tmp_path, capsys, plate_mm):
    text, rows, insunits, summary = _section(capsys, tmp_path, plate_mm)
    assert insunits == 4                      # was 6 (metres) for every model
    assert rows and {r["units"] for r in rows} == {"mm"}
    assert summary["units"] == "mm" and "units: mm" in text
    assert float(rows[0]["x"]) == pytest.approx(50.0)   # coordinates never rescaled


def test_units_override_and_unknown_units(tmp_path, capsys, plate_mm):
    _, rows, insunits, summary = _section(capsys, tmp_path, plate_mm, "--units", "in")
    assert insunits == 1 and rows[0]["units"] == "in" and summary["units"] == "in"
    _, rows, insunits, summary = _section(capsys, tmp_path, "plate_with_hole",
                                          "--overwrite")
    assert insunits == 0                      # unitless, not metres
    assert rows[0]["units"] == "model units" and summary["units"] == "model units"


def test_deviation_distance_clearance_state_units(tmp_path, capsys, plate_mm):
    pts = tmp_path / "p.xyz"
    pts.write_text("10 10 0.5\n20 20 -0.25\n")
    text = run(capsys, "deviation", plate_mm, pts, "-o", tmp_path / "dev", "--no-plots")
    assert json.loads((tmp_path / "dev" / "summary.json").read_text())["units"] == "mm"
    assert "units: mm" in text
    text = run(capsys, "distance", plate_mm, pts, "-o", tmp_path / "d.csv", "--units", "cm")
    assert " cm" in text
    assert {r["units"] for r in csv.DictReader(open(tmp_path / "d.csv"))} == {"cm"}
    path = tmp_path / "path.xyz"
    path.write_text("10 10 30\n90 90 30\n")
    run(capsys, "clearance", plate_mm, path, "--stylus", "1,0.5,5", "--no-plots",
        "-o", tmp_path / "cl")
    s = json.loads((tmp_path / "cl" / "clearance_summary.json").read_text())
    assert s["units"] == "mm"
    info = json.loads(run(capsys, "info", plate_mm, "--json"))
    assert info["units"] == "mm"


def test_iges_and_step_reader_units_reach_the_case(monkeypatch, tmp_path):
    """The CLI takes the units the IGES / STEP readers report."""
    import geomkit.cad.iges.reader
    from geomkit.cli._common import _load_input

    class Res:
        surfaces = samples.load("sphere")
        skipped = []
        units = "INCH"

    monkeypatch.setattr(geomkit.cad.iges.reader, "read_iges", lambda *a, **k: Res())
    p = tmp_path / "part.igs"
    p.write_text("")
    assert _load_input(str(p)).units == "in"
    assert _load_input(str(p), units="mm").units == "mm"


def test_impeller_iges_is_in_millimetres():
    examples = pytest.importorskip("pyiges.examples")
    from geomkit.cli._common import _load_input

    assert _load_input(examples.impeller, skip_invalid=True).units == "mm"
