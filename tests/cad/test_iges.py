"""IGES (pyiges) and STEP (OCP) input: the impeller model against Open CASCADE, and the
CLI on a real model."""

from __future__ import annotations

import hashlib
import json
from pathlib import Path

import numpy as np
import pytest

import geomkit
from geomkit import samples

pyiges = pytest.importorskip("pyiges")
from pyiges import examples  # noqa: E402

from geomkit.bench.oracles.occ import HAVE_OCP  # noqa: E402

from helpers.clihelp import cli  # noqa: E402

IMPELLER = Path(examples.impeller)  # the impeller fixture (tests/conftest.py) reads it


def test_impeller_counts(impeller):
    r = impeller
    assert r.counts[128] == 247 and r.counts[144] == 277
    # every face is read: the 247 on 128 B-splines and the 30 on 120 surfaces of
    # revolution (exact rational NURBS)
    assert len(r.surfaces) == 277 and not r.skipped
    assert r.units == "mm" and r.resolution == 1e-8
    assert all(s.is_trimmed for s in r.surfaces)
    assert r.max_gap < 1e-2


@pytest.mark.occ
@pytest.mark.skipif(not HAVE_OCP, reason="needs cadquery-ocp")
def test_impeller_surfaces_match_open_cascade(impeller):
    from OCP.BRep import BRep_Tool
    from OCP.IGESControl import IGESControl_Reader
    from OCP.TopAbs import TopAbs_FACE
    from OCP.TopExp import TopExp_Explorer

    from geomkit.bench.oracles import occ
    from geomkit.cad.occ import cast_shape

    rd = IGESControl_Reader()
    rd.ReadFile(str(IMPELLER))
    rd.TransferRoots()
    ex = TopExp_Explorer(rd.OneShape(), TopAbs_FACE)
    occ_surfs = []
    while ex.More():
        s = BRep_Tool.Surface_s(cast_shape("Face", ex.Current()))
        occ_surfs.append((s, s.Bounds()))
        ex.Next()
    assert len(occ_surfs) == 277
    worst, matched = 0.0, 0
    for ms in impeller.surfaces:
        (a, b), (c, d) = ms.domain
        t = np.linspace(0, 1, 5)
        uv = np.column_stack([a + (b - a) * t, c + (d - c) * t[::-1]])
        P = ms.evaluate(uv)
        best = np.inf
        for s, (u0, u1, v0, v1) in occ_surfs:
            if max(abs(u0 - a), abs(u1 - b), abs(v0 - c), abs(v1 - d)) > 1e-12 * (1 + b - a):
                continue
            best = min(best, np.abs(P - occ.evaluate(s, uv)).max() / ms.size)
        if np.isfinite(best):
            matched += 1
            worst = max(worst, best)
    # the 247 faces on 128 B-splines are OCC's surfaces exactly (OCC keeps the 30 120
    # revolutions in angle parameters: checked by closed form in test_cad_oracle.py)
    assert matched == 247
    assert worst < 1e-9


def test_cli_deviation_on_the_impeller(impeller, tmp_path):
    # points at known offsets from interior points of three faces
    pts, offs = [], []
    for k in (0, 100, 200):
        s = impeller.surfaces[k]
        (a, b), (c, d) = s.domain
        g = np.linspace(0.3, 0.7, 4)
        uv = np.array([[a + (b - a) * x, c + (d - c) * y] for x in g for y in g])
        uv = uv[s.classify_uv(uv) == geomkit.INSIDE]
        off = np.linspace(-0.01, 0.01, len(uv))
        pts.append(s.evaluate(uv) + off[:, None] * s.normals(uv))
        offs.append(off)
    P = np.concatenate(pts)
    off = np.concatenate(offs)
    f = tmp_path / "cmm.xyz"
    f.write_text("".join(" ".join(repr(float(x)) for x in p) + "\n" for p in P))
    before = hashlib.sha256(IMPELLER.read_bytes()).hexdigest()
    r = cli("deviation", IMPELLER, f, "-o", tmp_path / "rep", "--tolerance", "0.005", "--json",
            "--no-plots")
    assert r.returncode == 0, r.stderr
    s = json.loads(r.stdout)
    assert s["surfaces"] == 277 and s["valid"] == len(P)
    assert "skipped" not in r.stderr
    import csv
    rows = list(csv.DictReader(open(tmp_path / "rep" / "deviation.csv")))
    dev = np.array([float(x["deviation"]) for x in rows])
    # the nearest face may be another one only where faces touch: here interior points
    # of one face, so the offsets come back
    assert np.max(np.abs(np.abs(dev) - np.abs(off))) < 1e-6
    assert hashlib.sha256(IMPELLER.read_bytes()).hexdigest() == before


def test_cli_section_on_the_impeller(tmp_path):
    r = cli("section", IMPELLER, "--plane", "0", "0", "1", "20", "--tol", "1e-3",
            "-o", tmp_path / "cut", "--formats", "csv,json", "--json")
    assert r.returncode == 0, r.stderr
    s = json.loads(r.stdout)
    assert s["planes"][0]["curves"] > 0 and s["planes"][0]["max_residual"] < 1e-8


def test_bad_iges_files(tmp_path):
    bad = tmp_path / "bad.igs"
    bad.write_text("this is not an IGES file\n")
    for path in (bad, tmp_path / "missing.igs"):
        r = cli("info", path)
        assert r.returncode == 2 and r.stderr.startswith("geomkit: error: ")
        assert r.stderr.count("\n") == 1 and "Traceback" not in r.stderr


@pytest.mark.occ
@pytest.mark.skipif(not HAVE_OCP, reason="needs cadquery-ocp")
@pytest.mark.parametrize("name", ["plate_with_hole", "torus"])
def test_step_round_trip(tmp_path, name):
    from OCP.STEPControl import STEPControl_AsIs, STEPControl_Writer

    from geomkit.bench.oracles import occ
    from geomkit.cad.step import read_step

    s = samples.load(name)[0]
    face = occ.make_face(s.degree_u, s.degree_v, s.knots_u, s.knots_v, s.control_points,
                         s.weights, [[c.to_dict() for c in lp.pieces] for lp in s.trim]
                         or None)
    w = STEPControl_Writer()
    w.Transfer(face, STEPControl_AsIs)
    w.Write(str(tmp_path / "f.step"))
    r = read_step(tmp_path / "f.step")
    assert len(r.surfaces) == 1 and not r.skipped
    m = r.surfaces[0]
    assert len(m.trim) == len(s.trim) or (not s.trim and len(m.trim) == 1)
    uv = np.random.default_rng(0).uniform(0, 1, (50, 2))
    assert np.abs(m.evaluate(uv) - s.evaluate(uv)).max() < 1e-9 * s.size
    assert np.array_equal(m.classify_uv(uv) == geomkit.INSIDE, s.classify_uv(uv) ==
                          geomkit.INSIDE)
