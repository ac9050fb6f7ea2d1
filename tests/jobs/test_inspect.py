"""geomkit inspect / geomkit.inspect_part on NIST AP242 models: every tolerance of the
file evaluated, a perfect virtual measurement passes everything evaluated (measured
form values at rounding level), a planted error is recovered and flips exactly the
characteristic it was planted on."""

from __future__ import annotations

import json

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

import geomkit
from geomkit.cli import main
from geomkit.jobs.inspect import inspect_part
from geomkit.jobs.sample import sample_faces

from helpers.paths import DATA

CTC01 = DATA / "parts" / "nist_ctc_01_ap242.stp"
FTC06 = DATA / "parts" / "nist_ftc_06_ap242.stp"
CTC01_AP203 = DATA / "parts" / "nist_ctc_01_ap203.stp"


@pytest.fixture(scope="module")
def ctc01():
    part = geomkit.read_step(CTC01)
    return part, geomkit.read_pmi(CTC01)


@pytest.fixture(scope="module")
def ftc06():
    part = geomkit.read_step(FTC06)
    return part, geomkit.read_pmi(FTC06)


def _size(part):
    lo = np.min([s.bounds[0] for s in part.surfaces], axis=0)
    hi = np.max([s.bounds[1] for s in part.surfaces], axis=0)
    return float(np.linalg.norm(hi - lo))


def _pmi_faces(pmi):
    return sorted({f for t in pmi.tolerances for f in t.faces}
                  | {f for d in pmi.datums for f in d.faces})


def _misplacement():
    T = np.eye(4)
    T[:3, :3] = Rotation.from_rotvec([0.01, -0.02, 0.015]).as_matrix()
    T[:3, 3] = [1.5, -2.0, 0.7]
    return T


def _by_id(res):
    return {c.id: c for c in res.characteristics}


def _status(res):
    return {c.id: c.status for c in res.characteristics}


def _bump_at_sample(part, faces, face, n, seed, height, radius):
    """A bump centred on one of the points the sampler will take on ``face``."""
    s0 = sample_faces(part, n, faces=faces, seed=seed)
    on = s0.nominal[s0.face == face]
    return {face: [{"kind": "bump", "center": tuple(on[len(on) // 2]),
                    "radius": radius, "height": height}]}


# --------------------------------------------------------------------- CTC-01

def test_ctc01_perfect_misplaced_passes_every_characteristic(ctc01):
    part, pmi = ctc01
    s = sample_faces(part, 30, faces=_pmi_faces(pmi), seed=5, transform=_misplacement())
    res = inspect_part(part, pmi, s.points, s.face)
    assert len(res.characteristics) == len(pmi.tolerances) == 6
    assert res.verdict == "pass", [(c.id, c.status, c.reason) for c in
                                   res.characteristics]
    size = _size(part)
    for c in res.characteristics:
        assert c.measured <= 1e-9 * size, (c.id, c.measured)
        assert c.n_points > 0 and c.deciding.size > 0
    assert res.frames["A|B|C"]["free"] == []
    assert res.shown_in == "A|B|C"
    assert np.nanmax(np.abs(res.deviation)) <= 1e-9 * size


def test_ctc01_faces_by_projection_and_other_alignments(ctc01):
    part, pmi = ctc01
    s = sample_faces(part, 12, seed=8)
    for align in ("datums", "bestfit", "none"):
        res = inspect_part(part, pmi, s.points, align=align)
        assert res.assignment["given"] is False
        assert res.assignment["assigned"] == len(s)
        assert res.verdict == "pass", (align, _status(res))
        assert max(c.measured for c in res.characteristics) <= 1e-8 * _size(part)


def test_ctc01_profile_bump_flips_only_that_profile(ctc01):
    part, pmi = ctc01
    fe = _bump_at_sample(part, _pmi_faces(pmi), 22, 30, 5, 2.0, 30.0)
    s = sample_faces(part, 30, faces=_pmi_faces(pmi), seed=5, form_errors=fe)
    res = inspect_part(part, pmi, s.points, s.face)
    st = _status(res)
    assert st.pop("#26") == "fail"
    assert set(st.values()) == {"pass"}
    c = _by_id(res)["#26"]
    want = 2.0 * float(np.abs(s.planted[s.face == 22]).max())   # bilateral: 2 max|d|
    assert abs(c.measured - want) <= 1e-6 * _size(part)
    assert res.verdict == "fail"


def test_ctc01_shifted_slot_flips_only_its_position(ctc01):
    part, pmi = ctc01
    shift = {"kind": "offset", "translate": (0.5, 0.0, 0.0)}
    s = sample_faces(part, 30, faces=_pmi_faces(pmi), seed=5,
                     form_errors={37: [shift], 41: [shift]})
    res = inspect_part(part, pmi, s.points, s.face)
    st = _status(res)
    assert st.pop("#21") == "fail"
    assert set(st.values()) == {"pass"}
    assert abs(_by_id(res)["#21"].measured - 1.0) <= 1e-6 * _size(part)  # 2 x 0.5


def test_ctc01_flatness_of_datum_face_recovered(ctc01):
    part, pmi = ctc01
    # an inward dent on datum A's face: the tangent datum plane stays, flatness grows
    fe = _bump_at_sample(part, _pmi_faces(pmi), 97, 30, 5, -0.3, 60.0)
    s = sample_faces(part, 30, faces=_pmi_faces(pmi), seed=5, form_errors=fe)
    res = inspect_part(part, pmi, s.points, s.face)
    st = _status(res)
    assert st.pop("#57") == "fail"
    assert set(st.values()) == {"pass"}
    pl = s.planted[s.face == 97]
    assert abs(_by_id(res)["#57"].measured - (pl.max() - pl.min())) <= 1e-6 * _size(part)


def test_ctc01_datum_without_points_is_named(ctc01):
    part, pmi = ctc01
    s = sample_faces(part, 20, faces=_pmi_faces(pmi), seed=2)
    keep = s.face != 97
    res = inspect_part(part, pmi, s.points[keep], s.face[keep])
    assert res.verdict == "incomplete"
    for c in res.characteristics:
        assert c.status == "not evaluated"
        if "A" in c.datums:
            assert "datum A" in c.reason and "97" in c.reason
    assert "needs at least" in _by_id(res)["#57"].reason


# --------------------------------------------------------------------- FTC-06

def test_ftc06_perfect_passes_all_it_evaluates(ftc06):
    part, pmi = ftc06
    s = sample_faces(part, 24, faces=_pmi_faces(pmi), seed=4)
    res = inspect_part(part, pmi, s.points, s.face)
    assert len(res.characteristics) == len(pmi.tolerances) == 28
    n = res.counts()
    assert n["fail"] == 0 and n["pass"] >= 22
    assert res.verdict == "incomplete"
    size = _size(part)
    for c in res.characteristics:
        if c.status == "pass":
            assert c.measured <= 1e-9 * size, (c.id, c.measured)
        else:
            assert c.reason      # every one not evaluated says why
    reasons = " ".join(c.reason for c in res.characteristics if c.reason)
    assert "datum targets" in reasons
    # the MMC bonus from the size dimension on the holes' faces
    c113 = _by_id(res)["#113"]
    assert c113.limit > c113.tolerance["value"]


def test_ftc06_shifted_hole_flips_its_position(ftc06):
    part, pmi = ftc06
    shift = {"kind": "offset", "translate": (0.6, 0.0, 0.0)}
    faces = [70, 71]
    s = sample_faces(part, 24, faces=_pmi_faces(pmi), seed=4,
                     form_errors={f: [shift] for f in faces})
    res = inspect_part(part, pmi, s.points, s.face,
                       tolerances=[t for t in pmi.tolerances
                                   if set(t.faces) & set(faces) or t.type == "flatness"])
    st = _status(res)
    assert st.pop("#113") == "fail"
    assert set(st.values()) <= {"pass", "not evaluated"} and "pass" in st.values()
    c = _by_id(res)["#113"]
    assert abs(c.measured - 1.2) <= 1e-6 * _size(part)


# --------------------------------------------------------------------- CLI

def test_cli_inspect_outputs_and_exit_codes(tmp_path, capsys, ctc01):
    part, pmi = ctc01
    s = sample_faces(part, 15, faces=_pmi_faces(pmi), seed=1)
    pts = tmp_path / "pts.csv"
    s.to_csv(pts)
    out = tmp_path / "rep"
    assert main(["inspect", str(CTC01), str(pts), "-o", str(out), "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert doc["verdict"] == "pass" and len(doc["characteristics"]) == 6
    first = doc["characteristics"][0]
    for key in ("id", "type", "faces", "tolerance", "datums", "measured", "pass",
                "points"):
        assert key in first
    assert sorted(p.name for p in out.iterdir()) == ["characteristics.csv",
                                                     "summary.json"]
    rows = (out / "characteristics.csv").read_text().splitlines()
    assert rows[0].startswith("id,type,faces,tolerance") and len(rows) == 7
    # a planted failure: exit 1, the row says fail
    fe = _bump_at_sample(part, _pmi_faces(pmi), 22, 15, 1, 2.0, 30.0)
    bad = sample_faces(part, 15, faces=_pmi_faces(pmi), seed=1, form_errors=fe)
    pts2 = tmp_path / "bad.csv"
    bad.to_csv(pts2)
    assert main(["inspect", str(CTC01), str(pts2), "-o", str(tmp_path / "r2")]) == 1
    text = capsys.readouterr().out
    assert "verdict: FAIL" in text and "#26" in text


def test_cli_inspect_bad_input(tmp_path, capsys):
    pts = tmp_path / "p.csv"
    pts.write_text("x,y,z\n0,0,0\n1,0,0\n0,1,0\n")
    assert main(["inspect", str(CTC01_AP203), str(pts), "-o", str(tmp_path / "a")]) == 2
    assert "no PMI in" in capsys.readouterr().err
    assert not (tmp_path / "a").exists()
    igs = tmp_path / "part.igs"
    igs.write_text("x")
    assert main(["inspect", str(igs), str(pts), "--json"]) == 2
    assert "STEP AP242" in json.loads(capsys.readouterr().out)["error"]
    bad = tmp_path / "bad.csv"
    bad.write_text("x,y,z,face\n0,0,0,1\n1,0,0,one\n")
    assert main(["inspect", str(CTC01), str(bad), "-o", str(tmp_path / "b")]) == 2
    err = capsys.readouterr().err
    assert "line 3" in err and "face" in err
    assert not (tmp_path / "b").exists()


# --------------------------------------------------------------------- FTC-07

FTC07 = DATA / "parts" / "nist_ftc_07_ap242.stp"


def test_ftc07_projected_zones_and_composite_lower_segments():
    part, pmi = geomkit.read_step(FTC07), geomkit.read_pmi(FTC07)
    faces = _pmi_faces(pmi)
    s = sample_faces(part, 16, faces=faces, seed=4)
    res = inspect_part(part, pmi, s.points, s.face)
    assert len(res.characteristics) == len(pmi.tolerances) == 27
    assert res.verdict == "pass", [(c.id, c.reason) for c in res.characteristics
                                   if c.status != "pass"]
    size = _size(part)
    assert max(c.measured for c in res.characteristics) <= 1e-9 * size
    notes = {c.id: " ".join(f.get("note", "") for f in c.features)
             for c in res.characteristics}
    assert "projected zone" in notes["#14025"] and "lower segment" in notes["#14483"]
    # one hole of the four-hole pattern moved 0.02 in: the pattern-locating zone (0.06
    # to A|B|C) still holds it (2 x 0.02), the feature-relating zone (0.015 to A,
    # floating) does not: the zones float by half the shift (2 x 0.01 each)
    shift = {"kind": "offset", "translate": (0.02, 0.0, 0.0)}
    s = sample_faces(part, 16, faces=faces, seed=4,
                     form_errors={253: [shift], 254: [shift]})
    tols = [t for t in pmi.tolerances if t.id in (14472, 14483)]
    res = inspect_part(part, pmi, s.points, s.face, tolerances=tols)
    up, low = _by_id(res)["#14472"], _by_id(res)["#14483"]
    assert up.status == "pass" and abs(up.measured - 0.04) <= 1e-6 * size
    assert low.status == "fail"
    assert 0.02 - 1e-6 * size <= low.measured <= 0.02 / np.cos(np.pi / 64) + 1e-6 * size


def test_faces_left_out_of_the_read_keep_the_pmi_faces_right(ctc01):
    # a read without face 50 (not toleranced) shifts the positions of the faces after
    # it; the PMI's face indices are the file's and are mapped through `entities`
    from dataclasses import replace

    part, pmi = ctc01

    def without(face):
        keep = [i for i in range(len(part.surfaces)) if i != face]
        return replace(part, surfaces=[part.surfaces[i] for i in keep],
                       entities=[part.entities[i] for i in keep])

    cut = without(50)
    s = sample_faces(cut, 20, seed=3)
    res = inspect_part(cut, pmi, s.points, s.face)
    assert res.verdict == "pass"
    assert _by_id(res)["#57"].faces == [97] and _by_id(res)["#57"].surfaces == [96]
    # without datum A's face the characteristics on A are not evaluated, naming it
    cut = without(97)
    s = sample_faces(cut, 20, seed=3)
    res = inspect_part(cut, pmi, s.points, s.face)
    assert res.verdict == "incomplete"
    assert "left out of the read" in _by_id(res)["#57"].reason
    assert "datum A" in _by_id(res)["#56"].reason
    assert _by_id(res)["#22"].status == "not evaluated"
