"""Mesh export and the ``geomkit mesh`` command: formats, no overwrite, clean errors."""

import json

import numpy as np
import pytest
import trimesh

import geomkit
from geomkit import samples
from geomkit.cli import main


@pytest.fixture(scope="module")
def sphere_mesh():
    return geomkit.tessellate(samples.load("sphere"), 0.05)


@pytest.mark.parametrize("ext", ["stl", "ply", "obj"])
def test_export_round_trip(tmp_path, sphere_mesh, ext):
    path = sphere_mesh.export(tmp_path / f"s.{ext}")
    back = trimesh.load(path, process=True)
    assert len(back.faces) == len(sphere_mesh.faces)
    assert back.is_watertight
    # same geometry: every written vertex is a mesh vertex (to float32 for STL)
    d, _ = trimesh.proximity.ProximityQuery(sphere_mesh.to_trimesh()).vertex(back.vertices)
    assert d.max() < 1e-5


def test_export_refuses_to_overwrite(tmp_path, sphere_mesh):
    target = tmp_path / "s.stl"
    target.write_bytes(b"precious")
    with pytest.raises(FileExistsError):
        sphere_mesh.export(target)
    assert target.read_bytes() == b"precious"
    sphere_mesh.export(target, overwrite=True)
    assert target.read_bytes() != b"precious"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["s.stl"]  # no temp files left


def test_export_unknown_format(tmp_path, sphere_mesh):
    with pytest.raises(geomkit.InvalidInputError, match="unknown mesh format"):
        sphere_mesh.export(tmp_path / "s.step")
    assert list(tmp_path.iterdir()) == []


def test_cli_mesh_writes_and_reports(tmp_path, capsys):
    out = tmp_path / "torus.ply"
    assert main(["mesh", "torus", "--tol", "0.05", "-o", str(out), "--json"]) == 0
    info = json.loads(capsys.readouterr().out)
    assert info["max_deviation"] <= 0.05 and info["faces"] > 0
    mesh = trimesh.load(out)
    assert len(mesh.faces) == info["faces"]
    assert mesh.is_watertight
    # area within the chord bound |dA| <= 2 tol kmax A (kmax = 1/r = 1/5)
    truth = samples.load_case("torus").truth["area"]
    assert abs(mesh.area - truth) <= 2 * 0.05 / 5 * truth


def test_cli_mesh_never_overwrites_input_or_output(tmp_path, capsys):
    src = tmp_path / "case.json"
    geomkit.save(src, samples.load("saddle"))
    before = src.read_bytes()
    assert main(["mesh", str(src), "--tol", "0.1", "-o", str(src)]) == 2
    assert src.read_bytes() == before
    out = tmp_path / "o.stl"
    out.write_bytes(b"keep")
    assert main(["mesh", str(src), "--tol", "0.1", "-o", str(out)]) == 2
    assert out.read_bytes() == b"keep"
    err = capsys.readouterr().err
    assert err.count("geomkit: error:") == 2 and "Traceback" not in err


@pytest.mark.parametrize("tol", ["0", "-1", "nan", "abc"])
def test_cli_mesh_bad_tolerance(tmp_path, tol, capsys):
    assert main(["mesh", "sphere", "--tol", tol, "-o", str(tmp_path / "x.stl")]) == 2
    err = capsys.readouterr().err
    assert "--tol" in err and err.count("\n") == 1
    assert list(tmp_path.iterdir()) == []


def test_mesh_face_uv_matches_vertices(sphere_mesh):
    s = samples.load("sphere")[0]
    P = s.evaluate(sphere_mesh.face_uv.reshape(-1, 2)).reshape(-1, 3, 3)
    np.testing.assert_allclose(P, sphere_mesh.vertices[sphere_mesh.faces], atol=1e-9)
