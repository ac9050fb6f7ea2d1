"""Faces recognised as features (geomkit.jobs.features) on real NIST parts and on
freeform samples, and the face column of point files."""

from __future__ import annotations

import numpy as np
import pytest

import geomkit
from geomkit.errors import FileFormatError
from geomkit.exchange.text import read_int_column
from geomkit.jobs.features import face_shapes, group_features

from helpers.paths import DATA

CTC01 = DATA / "parts" / "nist_ctc_01_ap242.stp"
FTC06 = DATA / "parts" / "nist_ftc_06_ap242.stp"


@pytest.fixture(scope="module")
def ctc01():
    return geomkit.read_step(CTC01)


def test_planes_holes_shafts_of_ctc01(ctc01):
    faces = [97, 89, 90, 23, 37, 41]
    sh = face_shapes(ctc01.surfaces, faces)
    assert sh[97].kind == "plane"
    np.testing.assert_allclose(sh[97].direction, [0, 0, 1], atol=1e-12)   # outward
    assert sh[89].kind == sh[90].kind == "cylinder" and sh[89].internal   # a bore
    assert sh[23].kind == "cylinder" and not sh[23].internal             # a boss
    feats = group_features(sh, faces, 1000.0)
    kinds = [(f.kind, f.faces) for f in feats]
    assert ("cylinder", [89, 90]) in kinds            # the two halves of one bore
    assert feats[[f.faces for f in feats].index([89, 90])].diameter == pytest.approx(35.0)
    # the slot's two opposed planes stay two features (a width is made by the job)
    assert ("plane", [37]) in kinds and ("plane", [41]) in kinds


def test_spheres_and_freeform():
    part = geomkit.read_step(FTC06)
    sh = face_shapes(part.surfaces, [6, 7, 62, 79])
    feats = group_features(sh, [6, 7, 62, 79], 1000.0)
    assert [f.faces for f in feats] == [[6, 7], [62, 79]]
    assert all(f.kind == "sphere" for f in feats)
    assert feats[0].diameter == pytest.approx(31.75)
    free = face_shapes(geomkit.samples.load("freeform_1"), [0])
    assert free[0].kind == "freeform"
    tor = face_shapes(geomkit.samples.load("torus"), [0])
    assert tor[0].kind == "freeform"          # a torus is none of the fitted kinds


def test_read_int_column(tmp_path):
    p = tmp_path / "a.csv"
    p.write_text("x,y,z,face\n0,0,0,3\n1,0,0,4\n# note\n2,0,0,-1\n")
    assert read_int_column(p, "face").tolist() == [3, 4, -1]
    assert read_int_column(p, "id") is None
    q = tmp_path / "b.csv"
    q.write_text("0,0,0\n1,1,1\n")
    assert read_int_column(q, "face") is None
    r = tmp_path / "c.xyz"
    r.write_text("x y z face\n0 0 0 2\n1 0 0 2.5\n")
    with pytest.raises(FileFormatError, match="line 3"):
        read_int_column(r, "face")
    ply = tmp_path / "d.ply"
    ply.write_text("ply\n")
    assert read_int_column(ply, "face") is None       # not a text point file
