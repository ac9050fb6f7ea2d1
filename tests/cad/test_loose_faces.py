"""Loose faces of STEP files (outside the solids) and the ones that duplicate a solid's
face (geomkit.cad.loose), on NIST parts read by geomkit's own reader."""

from __future__ import annotations

import json


import geomkit
from geomkit.cad.loose import duplicate_faces
from geomkit.cli import main

from helpers.paths import DATA

PARTS = DATA / "parts"


def test_ctc05_loose_face_on_the_solid_is_recognised():
    r = geomkit.read_step(PARTS / "nist_ctc_05_ap203.stp")
    assert r.loose == [208] and r.duplicates == {208: [2]}
    # the loose face lies on face 2 (x = 10.375 in), within rounding
    pr = geomkit.project_points([r.surfaces[2]], r.surfaces[208].evaluate([[-1.2, 0.0]]))
    assert pr.distance[0] < 1e-12
    case = geomkit.load_case(PARTS / "nist_ctc_05_ap203.stp")
    assert case.duplicates == {208: [2]}


def test_ftc07_loose_faces_off_the_solid_are_not_duplicates():
    r = geomkit.read_step(PARTS / "nist_ftc_07_ap242.stp")
    assert r.loose == [304, 305] and r.duplicates == {}


def test_solid_only_part_has_no_loose_faces():
    r = geomkit.read_step(PARTS / "nist_ctc_01_ap203.stp")
    assert r.loose == [] and r.duplicates == {}


def test_duplicate_faces_moved_off_is_not_a_duplicate():
    r = geomkit.read_step(PARTS / "nist_ctc_05_ap203.stp")
    s = r.surfaces[208]
    moved = geomkit.Surface(s.degree_u, s.degree_v, s.knots_u, s.knots_v,
                            s.control_points + [0.01, 0.0, 0.0], s.weights,
                            s.trim or None, name="moved")
    surfs = list(r.surfaces[:208]) + [moved]
    assert duplicate_faces(surfs, [208], 1e-6) == {}
    assert duplicate_faces(surfs, [208], 0.02) == {208: [2]}


def test_info_names_the_duplicate(capsys):
    f = str(PARTS / "nist_ctc_05_ap203.stp")
    assert main(["info", f, "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["duplicate_faces"] == {"208": [2]}
    assert main(["info", f]) == 0
    assert "face208: a loose face lying on the solid's face(s) face2" in \
        capsys.readouterr().out


def test_duplicate_shown_by_newton_without_the_projection(monkeypatch):
    """CTC-05's duplicate is shown by Gauss-Newton feet inside face 2's trim alone (the
    exact projection is not needed); points off the face, and a face lying only partly
    on the solid, are left to the projection."""
    import numpy as np

    import geomkit.cad.loose as loose

    r = geomkit.read_step(PARTS / "nist_ctc_05_ap203.stp")
    S = r.surfaces
    tol = 1e-6 * max(s.size for s in S)
    calls = []
    real = loose.project_points
    monkeypatch.setattr(loose, "project_points",
                        lambda *a, **k: calls.append(1) or real(*a, **k))
    assert duplicate_faces(S, [208], tol) == {208: [2]} and not calls
    s = S[208]
    X = s.evaluate([[-1.2, 0.0]])
    assert loose._shown_on([S[2]], X, tol) == [0]
    assert loose._shown_on([S[2]], X + 1e3 * tol, tol) is None
    # half of the face lifted off the solid: some samples shown, not all
    half = loose._samples(s)
    half[::2] += 50 * tol * np.array([1.0, 0.0, 0.0])
    assert loose._shown_on([S[k] for k in range(len(S)) if k != 208], half, tol) is None
