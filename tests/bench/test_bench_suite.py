"""geomkit.bench.suite: one tiny run (seconds) — schema, measured errors, files."""

from __future__ import annotations

import json
import math

import pytest

from geomkit.bench import suite
from geomkit.bench._common import FIELDS, coal_or_none, occ_or_none

TINY = {
    "evaluation": {"sizes": (200,), "cases": ("sphere",), "repeat": 2},
    "distance": {"cases": ("sphere_pair",), "tols": (1e-3, 1e-9), "repeat": 1},
    "collision": {"pairs": ("sphere-sphere",), "tols": (0.5,), "poses": 6},
}


@pytest.fixture(scope="module")
def tiny(tmp_path_factory):
    out = tmp_path_factory.mktemp("bench")
    res = suite.run_suite(["evaluation", "distance", "collision"], out_dir=out, config=TINY)
    return res, out


def test_schema_and_measured_errors(tiny):
    res, _ = tiny
    rows = res["rows"]
    assert {r["engine"] for r in rows} == {"evaluation", "distance", "collision"}
    # 1 evaluation row, 2 distance rows, collide (median, mean, per pose) +
    # collide_many + min_distance for the one tolerance
    assert len(rows) == 1 + 2 + 5
    for r in rows:
        assert tuple(r) == FIELDS
        assert r["geomkit_seconds"] > 0 and math.isfinite(r["geomkit_seconds"])
        assert r["geomkit_error"] is not None and math.isfinite(r["geomkit_error"])
        assert r["geomkit_error"] >= 0
    ev = [r for r in rows if r["engine"] == "evaluation"][0]
    assert ev["setting"] == 200 and ev["geomkit_error"] < 1e-12      # analytic residual
    for r in rows:
        if r["engine"] == "distance":
            assert r["geomkit_error"] < 1e-8                          # vs the analytic 5.0
    md = [r for r in rows if r["case"].endswith("min_distance")][0]
    # a mesh at tolerance 0.5 is measurably off the exact sphere distance, so the
    # error is measured (not self-reported zero) and of the order of the tolerance
    assert 1e-3 < md["geomkit_error"] < 2.0
    m = res["machine"]
    assert m["cpu_count"] >= 1 and m["numba_threads"] >= 1 and m["numpy"]
    assert set(res["engines"]) == {"evaluation", "distance", "collision"}


def test_occ_reference(tiny):
    pytest.importorskip("OCP")
    assert occ_or_none() is not None
    for r in tiny[0]["rows"]:
        if r["engine"] in ("evaluation", "distance"):
            assert r["reference_name"].startswith("OCC")
            assert r["reference_seconds"] > 0
            assert math.isfinite(r["reference_error"])
            assert r["speedup"] == pytest.approx(r["reference_seconds"] / r["geomkit_seconds"])


def test_coal_reference(tiny):
    pytest.importorskip("coal")
    assert coal_or_none() is not None
    for r in tiny[0]["rows"]:
        if r["engine"] == "collision":
            assert r["reference_name"].startswith("coal") and r["reference_seconds"] > 0
            assert math.isfinite(r["reference_error"])


def test_files_written_and_not_overwritten(tiny, tmp_path):
    res, out = tiny
    names = {p.name for p in out.iterdir()}
    assert names == set(suite.FILES)                   # no temporary files left behind
    doc = json.loads((out / "bench.json").read_text())
    assert len(doc["rows"]) == len(res["rows"]) and doc["machine"]["cpu_count"] >= 1
    assert (out / "bench.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    md = (out / "bench.md").read_text()
    assert suite.format_table(res["rows"]) in md
    # existing files are kept without overwrite (checked before any work) ...
    before = (out / "bench.json").read_bytes()
    with pytest.raises(FileExistsError):
        suite.run_suite(["evaluation"], out_dir=out, config=TINY)
    assert (out / "bench.json").read_bytes() == before
    # ... and replaced with it
    (tmp_path / "bench.md").write_text("old")
    res2 = suite.run_suite(["evaluation"], out_dir=tmp_path, config=TINY, overwrite=True)
    assert (tmp_path / "bench.md").read_text() != "old"
    assert set(res2["files"]) == set(suite.FILES)


def test_format_table_and_errors():
    row = {k: None for k in FIELDS}
    row.update(engine="x", case="c", setting_name="tol", setting=1e-3, per="call",
               geomkit_seconds=2e-3, geomkit_error=0.0, repeats=1, note="n")
    txt = suite.format_table([row])
    lines = txt.splitlines()
    assert len(lines) == 3 and lines[2].count("|") == lines[0].count("|")
    assert "2 ms" in lines[2] and "tol 1e-03" in lines[2]
    row.update(setting=0.12813)   # a part's tolerance: not rounded to one digit
    assert "tol 0.128 " in suite.format_table([row])
    with pytest.raises(ValueError):
        suite.run_suite(["nope"])


def test_main_writes(tmp_path, capsys, monkeypatch):
    monkeypatch.setitem(suite.CONFIG, "evaluation",
                        ("evaluation", TINY["evaluation"], TINY["evaluation"]))
    assert suite.main(["--engines", "evaluation", "-o", str(tmp_path)]) == 0
    out = capsys.readouterr().out
    assert "| evaluation | sphere |" in out and "wrote" in out
    with pytest.raises(FileExistsError):
        suite.main(["--engines", "evaluation", "-o", str(tmp_path)])
    assert suite.main(["--engines", "evaluation", "-o", str(tmp_path), "--overwrite"]) == 0


def test_missing_references_are_skipped_with_a_note(monkeypatch):
    from geomkit.bench import _common

    monkeypatch.setattr(_common, "occ_or_none", lambda: None)
    monkeypatch.setattr(_common, "coal_or_none", lambda: None)
    res = suite.run_suite(["evaluation", "collision"], config=TINY)
    assert res["files"] == {}
    for r in res["rows"]:
        assert r["reference_name"] is None and r["reference_seconds"] is None
        assert r["speedup"] is None and "reference skipped" in r["note"]
        assert math.isfinite(r["geomkit_error"])
    assert res["engines"]["evaluation"]["notes"] == [_common.MISSING_OCC]
    assert res["engines"]["collision"]["notes"] == [_common.MISSING_COAL]
    assert "| - |" in suite.format_table(res["rows"])


def test_cli_bench_end_to_end(tmp_path):
    from helpers.clihelp import assert_one_line_error, cli

    r = cli("bench", "--engines", "evaluation", "-o", tmp_path / "b", "--json")
    assert r.returncode == 0, r.stderr
    s = json.loads(r.stdout)
    assert s["rows"] and all(row["engine"] == "evaluation" for row in s["rows"])
    assert all(row["geomkit_error"] < 1e-12 for row in s["rows"])
    assert sorted(p.name for p in (tmp_path / "b").iterdir()) == ["bench.json", "bench.md",
                                                                 "bench.png"]
    r = cli("bench", "--engines", "evaluation", "-o", tmp_path / "b")
    assert_one_line_error(r, "exists", "--overwrite")
    r = cli("bench", "--engines", "nope", "-o", tmp_path / "c")
    assert_one_line_error(r, "--engines", "unknown engine")
    assert not (tmp_path / "c").exists()
    (tmp_path / "f").write_text("a file")  # the folder's parent is a file: refused first
    r = cli("bench", "--engines", "evaluation", "-o", tmp_path / "f" / "b")
    assert_one_line_error(r, "cannot write here")


def test_projection_mesh_rows_beside_libigl_and_trimesh():
    """The suite's projection engine carries the mesh-query references (issue 15): one
    row per reference, each with its own time and error against geomkit's exact
    distance."""
    pytest.importorskip("igl")
    pytest.importorskip("rtree")
    from geomkit.bench.projection import mesh_sweep

    rows = mesh_sweep(("plate_with_hole",), n=300, repeat=1, trimesh_n=20)
    names = {r["reference_name"].split(" (")[0] for r in rows}
    assert names == {"libigl point_mesh_squared_distance", "libigl AABB, tree prebuilt",
                     "trimesh closest_point"}
    assert {r["case"] for r in rows} == {"plate_with_hole/scan", "plate_with_hole/box"}
    for r in rows:
        assert r["geomkit_seconds"] > 0 and r["reference_seconds"] > 0
        if r["reference_error"] is not None:  # a 1e-3 mesh: its error is about that
            assert 0 <= r["reference_error"] < 5e-3


def test_collide_mean_row_is_the_mean_of_the_same_calls(tiny):
    """Beside the median row, a mean row over the same timed calls (hence the same
    measured error), for geomkit and the reference."""
    rows = {r["case"]: r for r in tiny[0]["rows"] if r["engine"] == "collision"}
    med, mean = rows["sphere-sphere collide"], rows["sphere-sphere collide mean"]
    assert mean["geomkit_error"] == med["geomkit_error"]
    assert rows["sphere-sphere collide per pose"]["geomkit_error"] == med["geomkit_error"]
    assert 0 < mean["geomkit_seconds"] < 1.0 and 0 < med["geomkit_seconds"] < 1.0
    if med["reference_seconds"] is not None:
        assert mean["reference_seconds"] > 0


def test_collide_per_pose_row_is_a_geometric_mean_of_pose_medians():
    """The per-pose row: each pose's median over the passes, geometric mean over
    the poses (so the ratio of two such rows is the geometric mean of the per-pose
    ratios)."""
    import numpy as np

    from geomkit.bench.collision import _per_pose
    t = np.array([[1.0, 4.0, 9.0], [3.0, 4.0, 1.0], [2.0, 100.0, 9.0]])   # 3 passes x 3 poses
    assert np.isclose(_per_pose(t.ravel().tolist(), 3, 3), (2.0 * 4.0 * 9.0) ** (1 / 3))
    c = np.array([2.0, 8.0, 18.0])        # twice each pose: the ratio is exactly 2
    assert np.isclose(_per_pose(np.tile(c, 3).tolist(), 3, 3) / _per_pose(
        np.tile(c / 2, 3).tolist(), 3, 3), 2.0)


def test_parts_engine_beside_occ():
    """One real part: read, mesh, three sections and projection, each beside OCC in
    the same run; the mesh errors are measured on both meshes by exact projection."""
    pytest.importorskip("OCP")
    from geomkit.bench import parts

    rows = parts.sweep(("ug16_io1_ap214.stp",), repeat=1)
    assert [r["setting_name"] for r in rows] == ["read faces", "read again faces",
                                                 "tessellate tol", "section x",
                                                 "section y", "section z",
                                                 "projector build faces", "project points"]
    for r in rows:
        assert tuple(r) == FIELDS and r["engine"] == "parts"
        assert r["geomkit_seconds"] > 0
        assert r["reference_seconds"] is None if r["setting_name"].startswith("projector") \
            else r["reference_seconds"] > 0
    rows = [rows[0]] + rows[2:]   # the read cache's row checked above
    tess = rows[1]
    assert 0 < tess["geomkit_error"] <= tess["setting"] * (1 + 1e-9)   # the guarantee
    assert tess["reference_error"] > 0                                  # measured, not stated
    for r in rows[2:5]:   # closed curves where OCC closes wires
        assert "vs OCC" in r["note"]
    assert "first query" in rows[5]["note"]
    assert rows[6]["geomkit_error"] < 1e-5                              # OCC's edge tolerance


def test_fit_engine_rows_against_references():
    """``geomkit bench --engines fit``: geomkit's least-squares fits beside
    scikit-spatial / scipy on the same points, each error against the known feature."""
    res = suite.run_suite(["fit"], config={"fit": {"sizes": (400,)}})
    rows = res["rows"]
    assert {r["case"] for r in rows} == {"plane", "line", "circle", "sphere", "cylinder",
                                         "cone"}
    assert all(r["engine"] == "fit" and r["geomkit_error"] < 1e-9 for r in rows)
    refs = {(r["case"], r["reference_name"]) for r in rows}
    assert ("sphere", "scipy least_squares") in refs
    if res["machine"].get("have_occ") is not None and not res["engines"]["fit"]["notes"]:
        assert ("plane", "scikit-spatial") in refs


def test_parts_alternate_takes_the_runs_in_turn():
    """The parts bench times geomkit and OCC in turn (b first every other round), and
    reports each side's median and last result."""
    from geomkit.bench.parts import alternate

    order = []

    def run(name, times):
        it = iter(times)

        def f():
            order.append(name)
            return next(it), len(order)
        return f

    ta, out_a, tb, out_b, n = alternate(run("a", [3.0, 1.0, 2.0, 9.0]),
                                        run("b", [5.0, 4.0, 6.0, 7.0]), 4)
    assert order == ["b", "a", "a", "b", "b", "a", "a", "b"]
    assert (ta, tb, n) == (2.5, 5.5, 4)
    assert out_a == 7 and out_b == 8
