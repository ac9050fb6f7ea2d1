"""HTML / PDF reports, units on every writer, plot helpers, file modes.

The browser tests open each HTML report in headless Chromium from file:// with the
network blocked (tests/helpers/browser.py): no JavaScript error, the plotly plots built (SVG
layers, a WebGL canvas for the 3-D views), the 3-D scene's screenshot not blank.  The
PDF's first page is rendered with pdftoppm and must not be blank.  Both skip when the
tool is missing.  With GEOMKIT_DOC_IMAGES=1 the screenshots are also saved, downscaled,
as docs/img/report_*.png (the guides show them).
"""

from __future__ import annotations

import csv
import hashlib
import json
import os
import shutil
import subprocess
from pathlib import Path

import numpy as np
import pytest

import geomkit
from geomkit.report import common as rc
from geomkit import samples
from geomkit.jobs.clearance import Stylus, probe_clearance
from geomkit.jobs.deviation import deviation
from geomkit.outputs import atomic_write
from geomkit.report.files import (clearance_counts, clearance_title, section_figure, write_json,
                            write_deviation_csv)
from geomkit.report.jobs import parse_kinds, report_files, write_reports
from geomkit.section.plane import plane_section

from helpers.browser import chromium, console_errors, external_refs, open_report
from helpers.clihelp import cli
from helpers.paths import ROOT

TOL = (-0.02, 0.02)
STYLUS = Stylus(1.0, 0.5, 20.0)
PATH = np.array([[-20.0, 0, 12], [20.0, 0, 12], [20.0, 0, 7.5], [20.0, 0, 0]])
DOC_IMAGES = os.environ.get("GEOMKIT_DOC_IMAGES") == "1"


def _torus_scan(n=24, seed=1):
    """Points at known signed offsets from the torus (R 20, r 5): (points, truth)."""
    rng = np.random.default_rng(seed)
    a, b = np.meshgrid(np.linspace(0, 2 * np.pi, n, endpoint=False),
                       np.linspace(0, 2 * np.pi, n // 2, endpoint=False), indexing="ij")
    a, b = a.ravel(), b.ravel()
    d = 0.004 * rng.standard_normal(a.size)
    d[:5] = [0.05, -0.035, 0.03, 0.025, -0.021]          # a few beyond the band
    rr = 5.0 + d
    P = np.column_stack([(20 + rr * np.cos(b)) * np.cos(a), (20 + rr * np.cos(b)) * np.sin(a),
                         rr * np.sin(b)])
    return P, d


@pytest.fixture(scope="module")
def jobs(tmp_path_factory):
    """The three jobs on the torus and their HTML + PDF reports."""
    surfs = samples.load_case("torus").surfaces
    P, truth = _torus_scan()
    rep = deviation(surfs, P, tolerance=TOL)
    sections = [plane_section(surfs, [0, 0, 1, -z], 1e-3) for z in (0.0, 2.5)]
    res = probe_clearance(surfs, STYLUS, PATH, margin=2.0)
    out = tmp_path_factory.mktemp("reports")
    names = {j: report_files(j, ["html", "pdf"]) for j in ("deviation", "section", "clearance")}
    targets = {n: out / n for v in names.values() for n in v}
    common = dict(units="mm", part="torus", model_note="test note: all faces read")
    write_reports("deviation", ["html", "pdf"], targets, rep=rep, surfaces=surfs, **common)
    write_reports("section", ["html", "pdf"], targets, sections=sections, surfaces=surfs,
                  scan=P, tolerance=TOL, **common)
    write_reports("clearance", ["html", "pdf"], targets, res=res, surfaces=surfs,
                  path_points=PATH, stylus=STYLUS, axis=(0, 0, 1), probing=[2], **common)
    return dict(surfs=surfs, P=P, truth=truth, rep=rep, sections=sections, res=res,
                out=out, targets=targets)


# ------------------------------------------------------------------ file modes
def test_atomic_write_honours_the_umask(tmp_path):
    old = os.umask(0o022)
    try:
        p = atomic_write(tmp_path / "a.txt", lambda fh: fh.write(b"x"))
        assert (p.stat().st_mode & 0o777) == 0o644
        os.umask(0o027)
        p = write_json({"a": 1}, tmp_path / "b.json")
        assert (p.stat().st_mode & 0o777) == 0o640
    finally:
        os.umask(old)
    assert not [f for f in os.listdir(tmp_path) if f.endswith(".tmp")]
    before = (tmp_path / "b.json").read_bytes()
    with pytest.raises(FileExistsError):
        write_json({"a": 2}, tmp_path / "b.json")
    assert (tmp_path / "b.json").read_bytes() == before


def test_report_files_are_0644_and_not_replaced_without_overwrite(jobs):
    from geomkit.outputs import _umask

    for p in jobs["targets"].values():  # written under this process' umask
        assert (p.stat().st_mode & 0o777) == 0o666 & ~_umask(), p
    t = jobs["targets"]
    before = t["deviation_report.html"].read_bytes()
    with pytest.raises(FileExistsError):
        write_reports("deviation", ["html"], t, rep=jobs["rep"], surfaces=jobs["surfs"])
    assert t["deviation_report.html"].read_bytes() == before


# ----------------------------------------------------------------------- units
def test_units_in_csv_json_and_axis_labels(jobs, tmp_path):
    rep = jobs["rep"]
    for units, want in (("mm", "mm"), (None, "model units")):
        p = write_deviation_csv(rep, tmp_path / f"d{want}.csv", units=units)
        rows = list(csv.DictReader(open(p)))
        assert len(rows) == len(rep) and {r["units"] for r in rows} == {want}
        assert float(rows[0]["deviation"]) == pytest.approx(jobs["truth"][0], abs=1e-9)
        doc = json.loads(write_json({"a": 1}, tmp_path / f"s{want}.json", units=units,
                                    model_note="partial").read_text())
        assert doc.get("units") == (units and want) and doc["model_note"] == "partial"
    fig = section_figure(jobs["sections"], units="mm")
    ax = fig.axes[0]
    assert (ax.get_xlabel(), ax.get_ylabel()) == ("x [mm]", "y [mm]")  # plane z = 0
    assert ax.get_aspect() == 1.0


# ------------------------------------------------------------- plot helpers
def test_plane_frame_is_an_isometry_of_the_plane():
    rng = np.random.default_rng(0)
    for plane in ([1, 0, 0, -10], [0, 1, 0, 3], [0, 0, 1, -6], [0.6, 0, 0.8, -3],
                  [1, 2, -2, 5]):
        pl = np.asarray(plane, float) / np.linalg.norm(plane[:3])
        o, e1, e2, _ = rc.plane_frame(pl)
        n = pl[:3]
        assert abs(o @ n + pl[3]) < 1e-12
        G = np.array([e1, e2, n])
        assert np.allclose(G @ G.T, np.eye(3), atol=1e-12)
        X = rng.normal(size=(20, 3)) * 10
        X -= np.outer(X @ n + pl[3], n)                 # points of the plane
        Q = rc.to_plane(X, pl)
        dx = np.linalg.norm(X[:, None] - X[None], axis=2)
        dq = np.linalg.norm(Q[:, None] - Q[None], axis=2)
        assert np.allclose(dx, dq, atol=1e-9)
    assert rc.plane_frame([1, 0, 0, -10])[3] == ("y", "z")
    assert rc.plane_name([0, 0, 1, -6]) == "z = 6"


def test_colour_scale_one_colour_in_the_band_graded_beyond():
    from matplotlib.colors import to_hex

    m = 0.05
    cmap = rc.mpl_cmap(TOL, m)
    at = (lambda v: to_hex(cmap((v + m) / (2 * m))))
    assert {at(v) for v in np.linspace(-0.0199, 0.0199, 25)} == {rc.IN_TOL}
    above = [at(v) for v in (0.021, 0.035, 0.05)]
    below = [at(v) for v in (-0.021, -0.035, -0.05)]
    assert len(set(above)) == 3 and len(set(below)) == 3 and rc.IN_TOL not in above + below


def test_statistics_table_against_the_truth(jobs):
    rep, d = jobs["rep"], jobs["truth"]
    rows = dict(rc.deviation_table(rep))
    s = d.std(ddof=1)
    assert float(rows["sigma (n-1)"]) == pytest.approx(s, rel=1e-5)
    assert float(rows["Cp"]) == pytest.approx(0.04 / (6 * s), rel=1e-3)
    assert float(rows["Cpk"]) == pytest.approx(min(0.02 - d.mean(), d.mean() + 0.02) / (3 * s),
                                               rel=1e-3)
    assert rows["over"].startswith(f"{int(np.sum(d > 0.02))} (")
    assert rows["under"].startswith(f"{int(np.sum(d < -0.02))} (")
    worst = rc.worst_points(rep, 5)
    assert sorted(worst.tolist()) == [0, 1, 2, 3, 4]      # the five planted outliers
    assert worst[0] == 0


def test_clearance_chart_counts_probing_moves_apart(jobs):
    res = jobs["res"]
    assert res.passed.tolist() == [True, False, False]    # travel ok, too close, plunge
    assert np.isfinite(res.first_contact[2]) and not np.isfinite(res.first_contact[1])
    c = clearance_counts(res, probing=[2])
    assert c["travel"] == [0, 1] and c["travel_failed"] == [1] and c["probing"] == [2]
    t = clearance_title(res, probing=[2])
    assert t.startswith("1 of 2 travel moves fail")
    # tip at z = 6 touches the tube top z = 5: s = (7.5 - 6) / 7.5
    assert "first contact at s = 0.2000" in t
    assert clearance_title(res).startswith("2 of 3 moves fail")


def test_parse_kinds():
    assert parse_kinds(["html,pdf", "html"]) == ["html", "pdf"]
    assert parse_kinds(None) == []
    with pytest.raises(geomkit.errors.InvalidInputError, match="unknown report kind"):
        parse_kinds(["xml"])


# ------------------------------------------------------------------------ HTML
def test_html_is_one_self_contained_file(jobs):
    sha = hashlib.sha256(Path(str(samples.path("torus"))).read_bytes()).hexdigest()
    for job in ("deviation", "section", "clearance"):
        text = jobs["targets"][f"{job}_report.html"].read_text(encoding="utf-8")
        assert external_refs(text) == [], job
        assert "<script src" not in text.lower()
        assert "plotly.js v" in text or "plotly.js" in text   # the library is inline
        assert text.count("Plotly.newPlot") >= 1
        assert sha in text and "mm" in text and "test note: all faces read" in text
    dev = jobs["targets"]["deviation_report.html"].read_text(encoding="utf-8")
    for word in ("Cpk", "sigma (n-1)", "Worst 10 points", "[-0.02, 0.02] mm",
                 "max +0.05", "alignment"):
        assert word in dev, word


@pytest.mark.skipif(chromium() is None, reason="no chromium installed (Debian package "
                                               "'chromium')")
@pytest.mark.parametrize("job,gl", [("deviation", 1), ("section", 0), ("clearance", 1)])
def test_html_report_in_headless_chromium(jobs, job, gl, tmp_path):
    from PIL import Image

    r = open_report(jobs["targets"][f"{job}_report.html"], screenshot=tmp_path / "s.png")
    probe = r["probe"]
    assert probe is not None, ("page did not finish loading", r["returncode"], r["stderr"])
    assert probe["errors"] == [], probe["errors"]
    assert console_errors(r["console"]) == []
    assert probe["plots"] >= 1 and probe["svg"] >= 2 * probe["plots"]
    assert sum(x["gl"] for x in probe["rects"]) == gl
    if gl:
        assert probe["webgl"], "no WebGL in this Chromium"
    im = np.asarray(Image.open(r["screenshot"]).convert("RGB")).astype(float)
    rect = probe["rects"][0]
    y0, x0 = int(rect["y"]), int(rect["x"])
    crop = im[y0:y0 + int(rect["h"]), x0:x0 + int(0.8 * rect["w"])]
    q = (crop // 16).astype(int)
    colours = len(np.unique(q[..., 0] * 256 + q[..., 1] * 16 + q[..., 2]))
    # a drawn scene: varied (WebGL off gives std ~10 and ~20 colours here)
    assert crop.size and crop.std() > 15 and colours > 60, (crop.std(), colours)
    if DOC_IMAGES:
        _doc_image(r["screenshot"], f"report_{job}.png")


def _doc_image(src, name, width=880, crop_h=1500):
    from PIL import Image

    im = Image.open(src).convert("RGB")
    im = im.crop((0, 0, im.width, min(im.height, crop_h)))
    im = im.resize((width, round(im.height * width / im.width)), Image.LANCZOS)
    out = ROOT / "docs" / "img" / name
    out.parent.mkdir(exist_ok=True)
    im.quantize(colors=256, method=Image.Quantize.MAXCOVERAGE, dither=Image.Dither.NONE
                ).save(out, optimize=True)
    assert out.stat().st_size < 200_000, (name, out.stat().st_size)


# ------------------------------------------------------------------------- PDF
@pytest.mark.skipif(shutil.which("pdftoppm") is None,
                    reason="no pdftoppm installed (Debian package 'poppler-utils')")
@pytest.mark.parametrize("job,pages", [("deviation", 2), ("section", 2), ("clearance", 1)])
def test_pdf_first_page_renders(jobs, job, pages, tmp_path):
    from PIL import Image

    pdf = jobs["targets"][f"{job}_report.pdf"]
    assert pdf.read_bytes()[:5] == b"%PDF-"
    r = subprocess.run(["pdftoppm", "-r", "60", "-png", str(pdf), str(tmp_path / "p")],
                       capture_output=True, text=True, timeout=120)
    assert r.returncode == 0, r.stderr
    files = sorted(tmp_path.glob("p*.png"))
    assert len(files) == pages
    for f in files:
        im = np.asarray(Image.open(f).convert("L")).astype(float)
        ink = np.mean(im < 200)
        assert im.std() > 10 and ink > 0.01, (f.name, im.std(), ink)
    if DOC_IMAGES and job == "deviation":
        for k, f in enumerate(files):
            _doc_image(f, f"report_deviation_pdf_{k + 1}.png", width=420)


# ------------------------------------------------------------------------- CLI
def test_cli_report_option(tmp_path):
    P, _ = _torus_scan(12)
    pts = tmp_path / "pts.xyz"
    np.savetxt(pts, P)
    old = os.umask(0o022)
    try:
        r = cli("deviation", "torus", pts, "-o", tmp_path / "rep", "--tolerance", "0.02",
                "--report", "html,pdf", "--report", "html")
    finally:
        os.umask(old)
    assert r.returncode == 0, r.stderr
    out = tmp_path / "rep"
    for n in ("deviation_report.html", "deviation_report.pdf", "deviation.csv",
              "summary.json"):
        assert (out / n).stat().st_mode & 0o777 == 0o644, n
    s = json.loads((out / "summary.json").read_text())
    assert str(out / "deviation_report.html") in s["files"]
    before = (out / "deviation_report.html").read_bytes()
    r = cli("deviation", "torus", pts, "-o", out, "--report", "html")
    assert r.returncode == 2 and "exists; pass --overwrite" in r.stderr
    assert (out / "deviation_report.html").read_bytes() == before



def test_cli_report_option_rejects_an_unknown_kind(tmp_path, capsys):
    from geomkit.cli import build_parser

    with pytest.raises(SystemExit) as e:
        build_parser().parse_args(["section", "torus", "--plane", "0", "0", "1", "0",
                                   "--report", "html,xml", "-o", str(tmp_path / "x")])
    assert e.value.code == 2 and "unknown report kind 'xml'" in capsys.readouterr().err
    assert not (tmp_path / "x").exists()


def test_section_whiskers_against_known_offsets(jobs):
    from geomkit.report.html import _whiskers

    P, d = jobs["P"], jobs["truth"]
    inplane = np.abs(P[:, 2]) < 1e-12                   # the b = 0 and b = pi rows
    (foot, tip, dev, scale), _ = _whiskers(jobs["sections"], P[inplane], jobs["surfs"],
                                           band=1e-9)
    assert dev.size == int(inplane.sum()) and scale > 1
    r_foot = np.linalg.norm(foot, axis=1)                # plane z = 0: frame (x, y)
    assert np.allclose(np.sort(np.unique(np.round(r_foot, 9))), [15.0, 25.0], atol=1e-9)
    assert np.allclose(np.sort(dev), np.sort(d[inplane]), atol=1e-9)
    outer = r_foot > 20                                  # outward normal: radius grows
    sgn = np.where(outer, 1.0, -1.0)
    assert np.allclose(np.linalg.norm(tip, axis=1), r_foot + sgn * scale * dev, atol=1e-7)


def test_cli_section_scan_report(tmp_path):
    from geomkit.cli import main

    P, _ = _torus_scan(12)
    pts = tmp_path / "pts.xyz"
    np.savetxt(pts, P)
    out = tmp_path / "cuts"
    assert main(["section", "torus", "--plane", "0", "0", "1", "0", "--formats", "csv",
                 "--scan", str(pts), "-o", str(out)]) == 2
    assert not out.exists()
    assert main(["section", "torus", "--plane", "0", "0", "1", "0", "--formats", "csv",
                 "--tolerance", "0.01", "-o", str(out)]) == 2  # a band needs --scan
    assert main(["section", "torus", "--plane", "0", "0", "1", "0", "--formats", "csv",
                 "--scan", str(pts), "--report", "html", "--tolerance", "0", "-o",
                 str(out)]) == 2
    assert not out.exists()
    assert main(["section", "torus", "--plane", "0", "0", "1", "0", "--formats", "csv",
                 "--scan", str(pts), "--report", "html", "--tolerance", "-0.01", "0.02",
                 "-o", str(out)]) == 0
    text = (out / "section_report.html").read_text(encoding="utf-8")
    assert "whiskers: scan deviation x" in text and "z = 0" in text
    assert "[-0.01, 0.02]" in text  # the band in the header
    summary = json.loads((out / "section_summary.json").read_text())
    assert str(out / "section_report.html") in summary["files"]
