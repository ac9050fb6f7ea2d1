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
