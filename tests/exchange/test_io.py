"""Reading and writing: geomkit-case/1 and geomdl JSON, round trips, safe writes and
the errors for bad files."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from geomkit import (FileFormatError, GeomkitError, InvalidInputError, InvalidSurfaceError,
                     InvalidTrimError, Surface, load, load_case, samples, save)

from helpers.paths import DATA
from helpers.trims import S2

# copies of the canonical cases with analytic truths (/work/shared/cases), kept in the
# repository so these tests never depend on a path outside it
SHARED = DATA / "cases"
SHARED_FILES = sorted(SHARED.glob("*.json"))


# ------------------------------------------------------------------------ helpers
def assert_same_surface(a: Surface, b: Surface, exact=True, trims=True):
    eq = (np.testing.assert_array_equal if exact else
          lambda x, y: np.testing.assert_allclose(x, y, rtol=1e-15, atol=1e-15))
    assert (a.degree_u, a.degree_v) == (b.degree_u, b.degree_v)
    assert a.shape == b.shape
    eq(a.knots_u, b.knots_u)
    eq(a.knots_v, b.knots_v)
    eq(a.control_points, b.control_points)
    assert a.is_rational == b.is_rational
    if a.is_rational:
        eq(a.weights, b.weights)
    if not trims:
        return
    assert a.name == b.name
    assert len(a.trim) == len(b.trim)
    for la, lb in zip(a.trim, b.trim):
        assert len(la.pieces) == len(lb.pieces)
        for pa, pb in zip(la.pieces, lb.pieces):
            assert pa.degree == pb.degree
            eq(pa.knots, pb.knots)
            eq(pa.control_points, pb.control_points)
            eq(pa.weights, pb.weights)


def files_in(d: Path):
    return sorted(p.name for p in d.iterdir())


def write_json(path: Path, doc) -> Path:
    path.write_text(json.dumps(doc), encoding="utf-8")
    return path


def plate_doc(**surface_over):
    s = {"degree_u": 1, "degree_v": 1, "knots_u": [0, 0, 1, 1], "knots_v": [0, 0, 1, 1],
         "control_points": [[[0, 0, 0], [0, 1, 0]], [[1, 0, 0], [1, 1, 0]]]}
    s.update(surface_over)
    return {"format": "geomkit-case/1", "name": "t", "surfaces": [s]}


def rich_surface():
    """A rational surface with three trim loops of every kind: a polyline, a single
    NURBS curve, and a chain of NURBS pieces of different degrees."""
    rng = np.random.default_rng(8)
    P = rng.normal(size=(5, 4, 3)) * 10
    W = rng.uniform(0.2, 5.0, size=(5, 4))
    U = [0, 0, 0, 0.3, 0.7, 1, 1, 1]
    V = [-1, -1, -1, 1, 2, 2, 2]
    (u0, u1), (v0, v1) = (0.0, 1.0), (-1.0, 2.0)
    outer = [[u0, v0], [u1, v0], [u1, v1], [u0, v1], [u0, v0]]
    circle = {"degree": 2, "knots": [0, 0, 0, .25, .25, .5, .5, .75, .75, 1, 1, 1],
              "control_points": [[.4, 0], [.4, -.2], [.2, -.2], [0.0, -.2], [0.0, 0],
                                 [0.0, .2], [.2, .2], [.4, .2], [.4, 0]],
              "weights": [1, S2, 1, S2, 1, S2, 1, S2, 1]}
    circle["control_points"] = [[x + 0.05, y - 0.5] for x, y in circle["control_points"]]
    chain = [{"degree": 3, "knots": [0, 0, 0, 0, 1, 1, 1, 1],
              "control_points": [[.6, 1.0], [.7, 1.4], [.8, 1.4], [.9, 1.0]],
              "weights": [1, 3.5, 0.25, 1]},
             {"degree": 1, "knots": [0, 0, 0.5, 1, 1],
              "control_points": [[.9, 1.0], [.75, 0.8], [.6, 1.0]]}]
    return Surface(2, 2, U, V, P, W, trim=[outer, circle, chain], name="rich")


# ------------------------------------------------------------- shared case files
@pytest.mark.parametrize("path", SHARED_FILES, ids=[p.stem for p in SHARED_FILES])
def test_shared_case_equals_bundled_sample(path):
    assert path.stem in samples.names(), f"{path.stem} is not a bundled sample"
    got = load(path)
    want = samples.load(path.stem)
    assert len(got) == len(want) > 0
    for a, b in zip(got, want):
        assert_same_surface(a, b)
    ca, cb = load_case(path), samples.load_case(path.stem)
    assert ca.name == cb.name and ca.truth == cb.truth and ca.description == cb.description


def test_every_bundled_sample_is_a_shared_case():
    assert len(SHARED_FILES) == 12
    assert sorted(p.stem for p in SHARED_FILES) == samples.names()


def test_loading_never_modifies_input_files():
    paths = SHARED_FILES + [Path(str(samples.path(n))) for n in samples.names()]
    before = {p: (p.read_bytes(), p.stat().st_mtime_ns, p.stat().st_size) for p in paths}
    dirs = {p.parent: files_in(p.parent) for p in paths}
    for p in paths:
        load(p)
        load_case(str(p))
    for n in samples.names():
        samples.load_case(n)
    for p in paths:
        assert (p.read_bytes(), p.stat().st_mtime_ns, p.stat().st_size) == before[p], p
    for d, names in dirs.items():
        assert files_in(d) == names  # nothing written beside them either


# ------------------------------------------------------------------- round trips
def test_case_round_trip_with_trims(tmp_path):
    s = rich_surface()
    plate = samples.load("plate_with_hole")[0]
    truth = {"area": 1.25, "nested": {"list": [1, 2.5, "x"]}}
    p = save(tmp_path / "out.json", [s, plate], truth=truth, name="roundtrip")
    assert p == tmp_path / "out.json"
    case = load_case(p)
    assert case.name == "roundtrip" and case.truth == truth
    a, b = case.surfaces
    assert_same_surface(a, s)
    assert_same_surface(b, plate)
    assert json.loads(p.read_text())["format"] == "geomkit-case/1"
    # and the reloaded surfaces behave the same
    uv = np.random.default_rng(0).uniform([0, -1], [1, 2], size=(200, 2))
    np.testing.assert_array_equal(a.evaluate(uv), s.evaluate(uv))
    np.testing.assert_array_equal(a.classify_uv(uv), s.classify_uv(uv))
    assert files_in(tmp_path) == ["out.json"]


def test_case_round_trip_is_a_fixed_point(tmp_path):
    s = rich_surface()
    p1 = save(tmp_path / "a.json", s)
    p2 = save(tmp_path / "b.json", load(p1))
    d1, d2 = json.loads(p1.read_text()), json.loads(p2.read_text())
    d1.pop("name"), d2.pop("name")
    assert d1 == d2


def test_single_surface_and_default_name(tmp_path):
    s = samples.load("sphere")[0]
    p = save(tmp_path / "ball.json", s)
    case = load_case(p)
    assert case.name == "ball" and case.truth == {} and len(case.surfaces) == 1
    assert_same_surface(case.surfaces[0], s)


@pytest.mark.parametrize("name", ["sphere", "freeform_1", "torus", "offset_planes",
                                  "heavy_weights"])
def test_geomdl_format_round_trip(tmp_path, name):
    surfs = samples.load(name)
    p = save(tmp_path / f"{name}.json", surfs, format="geomdl")
    doc = json.loads(p.read_text())
    assert doc["shape"]["type"] == "surface" and doc["shape"]["count"] == len(surfs)
    got = load(p)
    assert len(got) == len(surfs)
    for a, b in zip(got, surfs):
        assert_same_surface(a, b, trims=False)
        assert a.trim == ()


def test_geomdl_format_refuses_trims_and_writes_nothing(tmp_path):
    with pytest.raises(InvalidSurfaceError) as e:
        save(tmp_path / "x.json", samples.load("plate_with_hole"), format="geomdl")
    assert e.value.field == "trim" and "geomkit-case/1" in str(e.value)
    assert files_in(tmp_path) == []


@pytest.mark.parametrize("name", ["sphere", "freeform_1", "heavy_weights", "saddle"])
def test_load_file_written_by_geomdl_export_json(tmp_path, name):
    from geomdl import exchange

    s = samples.load(name)[0]
    g = s.to_geomdl()
    path = tmp_path / "geomdl.json"
    exchange.export_json(g, str(path))
    (t,) = load(path)
    assert_same_surface(t, s, exact=False, trims=False)
    # geomdl itself is the oracle for what the file means
    (u0, u1), (v0, v1) = s.domain
    uv = np.random.default_rng(2).uniform([u0, v0], [u1, v1], size=(6, 2))
    want = np.array([g.evaluate_single(tuple(x)) for x in uv])
    np.testing.assert_allclose(t.evaluate(uv), want, rtol=0, atol=1e-10 * s.size)


@pytest.mark.parametrize("name", samples.names())
def test_to_from_geomdl_round_trip(name):
    from geomdl import BSpline, NURBS

    for s in samples.load(name):
        g = s.to_geomdl()
        assert isinstance(g, NURBS.Surface if s.is_rational else BSpline.Surface)
        t = Surface.from_geomdl(g)
        assert_same_surface(t, s, exact=False, trims=False)
        assert t.trim == ()
        uv = np.array([[s.domain[0][0], s.domain[1][0]],
                       [np.mean(s.domain[0]), np.mean(s.domain[1])],
                       [s.domain[0][1], s.domain[1][1]]])
        want = np.array([g.evaluate_single(tuple(x)) for x in uv])
        np.testing.assert_allclose(s.evaluate(uv), want, rtol=0, atol=1e-10 * s.size)


def test_from_geomdl_refuses_other_objects():
    from geomdl import BSpline

    for obj in (object(), BSpline.Curve(), {"degree_u": 2}):
        with pytest.raises(InvalidInputError) as e:
            Surface.from_geomdl(obj)
        assert e.value.field == "geomdl" and "not a geomdl surface" in str(e.value)


# ---------------------------------------------------------------- safe writing
def test_save_refuses_to_overwrite(tmp_path):
    p = save(tmp_path / "c.json", samples.load("sphere"))
    before = (p.read_bytes(), p.stat().st_mtime_ns)
    for fmt in ("geomkit-case/1", "geomdl"):
        with pytest.raises(FileExistsError) as e:
            save(p, samples.load("saddle"), format=fmt)
        assert "overwrite=True" in str(e.value)
    assert (p.read_bytes(), p.stat().st_mtime_ns) == before
    assert files_in(tmp_path) == ["c.json"]
    save(p, samples.load("saddle"), overwrite=True)
    assert p.read_bytes() != before[0]
    assert_same_surface(load(p)[0], samples.load("saddle")[0])
    assert files_in(tmp_path) == ["c.json"]


def test_save_never_leaves_temp_files(tmp_path):
    target = tmp_path / "t.json"
    save(target, samples.load("torus"))
    save(target, samples.load("torus"), format="geomdl", overwrite=True)
    save(tmp_path / "sub" / "dir" / "u.json", samples.load("torus"))  # parents created
    assert files_in(tmp_path) == ["sub", "t.json"]
    assert files_in(tmp_path / "sub" / "dir") == ["u.json"]
    original = target.read_bytes()
    # a failure while writing (truth is not JSON-serialisable): the old file survives,
    # the temporary is removed
    with pytest.raises((TypeError, GeomkitError)):
        save(target, samples.load("sphere"), truth={"bad": object()}, overwrite=True)
    assert target.read_bytes() == original
    with pytest.raises((TypeError, GeomkitError)):
        save(tmp_path / "new.json", samples.load("sphere"), truth={"bad": {1, 2}})
    # replacing a directory fails, leaves the directory alone and no temporary behind
    (tmp_path / "adir.json").mkdir()
    with pytest.raises(OSError):
        save(tmp_path / "adir.json", samples.load("sphere"), overwrite=True)
    assert (tmp_path / "adir.json").is_dir()
    assert files_in(tmp_path) == ["adir.json", "sub", "t.json"]
    assert target.read_bytes() == original


@pytest.mark.parametrize("bad", [[], [1], "sphere", [samples.load("sphere")[0], 3], {},
                                 None,
                                 5])
def test_save_refuses_non_surfaces(tmp_path, bad):
    with pytest.raises(InvalidInputError) as e:
        save(tmp_path / "x.json", bad)
    # the argument, or the element of a list that is not a Surface
    assert e.value.field == "surfaces" + (f"[{len(bad) - 1}]" if isinstance(bad, list) and bad
                                          else "")
    assert files_in(tmp_path) == []


def test_save_refuses_unknown_format(tmp_path):
    with pytest.raises(InvalidInputError) as e:
        save(tmp_path / "x.json", samples.load("sphere"), format="step")
    assert e.value.field == "format" and "'step'" in str(e.value)
    assert files_in(tmp_path) == []


# ----------------------------------------------------------------- load errors
def expect_load_error(path, cls, *phrases):
    with pytest.raises(cls) as e:
        load(path)
    assert type(e.value) is cls and isinstance(e.value, GeomkitError)
    msg = str(e.value)
    assert str(path) in msg, msg  # the message names the file
    for ph in phrases:
        assert ph in msg, f"{ph!r} not in {msg!r}"
    return e.value


def test_load_missing_file(tmp_path):
    expect_load_error(tmp_path / "nope.json", FileFormatError, "no such file")
    expect_load_error(str(tmp_path / "nope.json"), FileFormatError, "no such file")


def test_load_directory(tmp_path):
    expect_load_error(tmp_path, FileFormatError, "is a directory")


def test_load_invalid_json_reports_line_and_column(tmp_path):
    text = '{\n  "format": "geomkit-case/1",\n  "surfaces": [1, 2,,]\n}\n'
    with pytest.raises(json.JSONDecodeError) as ref:
        json.loads(text)
    p = tmp_path / "bad.json"
    p.write_text(text)
    e = expect_load_error(p, FileFormatError, "invalid JSON",
                          f"line {ref.value.lineno}, column {ref.value.colno}")
    assert ref.value.lineno == 3
    assert e.__cause__ is None and e.__suppress_context__  # no chained traceback noise


@pytest.mark.parametrize("content", [b"", b"\xff\xfe\x00garbage", b"not json at all"],
                         ids=["empty", "binary", "text"])
def test_load_non_json(tmp_path, content):
    p = tmp_path / "x.json"
    p.write_bytes(content)
    expect_load_error(p, FileFormatError)


def test_load_unknown_format(tmp_path):
    p = write_json(tmp_path / "x.json", {"format": "foo/9", "surfaces": []})
    expect_load_error(p, FileFormatError, "unknown format 'foo/9'")


@pytest.mark.parametrize("doc, phrase", [
    ({"format": "geomkit-case/1"}, "no 'surfaces'"),
    ({"name": "x"}, "no 'surfaces'"),
    ({"surfaces": []}, "non-empty list"),
    ({"surfaces": {"a": 1}}, "non-empty list"),
    ([1, 2], "JSON object"),
    ("text", "JSON object"),
    ({"surfaces": [5]}, "surfaces[0]: expected an object"),
], ids=["no_surfaces", "no_surfaces_no_format", "empty", "not_a_list", "top_list",
        "top_string", "surface_not_object"])
def test_load_bad_structure(tmp_path, doc, phrase):
    p = write_json(tmp_path / "x.json", doc)
    expect_load_error(p, FileFormatError, phrase)


@pytest.mark.parametrize("missing", ["degree_u", "degree_v", "knots_u", "knots_v",
                                     "control_points"])
def test_load_missing_surface_field(tmp_path, missing):
    doc = plate_doc()
    doc["surfaces"].append(dict(doc["surfaces"][0]))
    del doc["surfaces"][1][missing]
    p = write_json(tmp_path / "x.json", doc)
    expect_load_error(p, FileFormatError, "surfaces[1]", missing)


def test_load_missing_several_fields(tmp_path):
    doc = plate_doc()
    del doc["surfaces"][0]["knots_u"], doc["surfaces"][0]["degree_v"]
    p = write_json(tmp_path / "x.json", doc)
    expect_load_error(p, FileFormatError, "surfaces[0]", "degree_v", "knots_u")


@pytest.mark.parametrize("over, cls, field, phrase", [
    (dict(knots_u=[0, 0, 1]), InvalidSurfaceError, "surfaces[0].knots_u", "n + p + 1"),
    (dict(weights=[[1, 1], [1, 0]]), InvalidSurfaceError, "surfaces[0].weights", "> 0"),
    (dict(degree_v="one"), InvalidSurfaceError, "surfaces[0].degree_v", "integer"),
    (dict(control_points=[[[0, 0], [0, 1]], [[1, 0], [1, 1]]]), InvalidSurfaceError,
     "surfaces[0].control_points", "expected shape"),
    (dict(trim=[[[0, 0], [1, 0], [1, 1], [0, 1], [0, 0]], [[.2, .2], [.4, .2], [.3, .4]]]),
     InvalidTrimError, "surfaces[0].trim[1]", "loop is open"),
    (dict(trim=[[{"degree": 2, "knots": [0, 0, 0, 1, 1, 1],
                  "control_points": [[.2, .2], [.5, .9], [.8, .2]], "weights": [1, -1, 1]},
                 [[.8, .2], [.2, .2]]]]),
     InvalidTrimError, "surfaces[0].trim[0][0].weights", "> 0"),
], ids=["knots", "weights", "degree", "cp_shape", "open_trim", "trim_piece_weight"])
def test_load_invalid_surface_prefixes_field_path(tmp_path, over, cls, field, phrase):
    p = write_json(tmp_path / "x.json", plate_doc(**over))
    e = expect_load_error(p, cls, phrase)
    assert e.field == f"{p}: {field}", e.field
    assert str(e).startswith(f"{p}: {field}: ")
    assert str(e).count(field) == 1  # the field path is not repeated in the message


def test_load_invalid_second_surface_names_its_index(tmp_path):
    doc = plate_doc()
    doc["surfaces"].append(dict(doc["surfaces"][0], knots_v=[0, 1, 0, 1]))
    p = write_json(tmp_path / "x.json", doc)
    e = expect_load_error(p, InvalidSurfaceError, "non-decreasing")
    assert e.field.endswith("surfaces[1].knots_v")


def geomdl_doc(**over):
    d = {"type": "spline", "rational": False, "dimension": 3, "degree_u": 1, "degree_v": 1,
         "knotvector_u": [0, 0, 1, 1], "knotvector_v": [0, 0, 1, 1], "size_u": 2,
         "size_v": 2, "control_points": {"points": [[0, 0, 0], [0, 1, 0], [1, 0, 0],
                                                    [1, 1, 0]]}}
    d.update(over)
    return {"shape": {"type": "surface", "count": 1, "data": [d]}}


def test_geomdl_doc_helper_is_valid(tmp_path):
    (s,) = load(write_json(tmp_path / "g.json", geomdl_doc()))
    np.testing.assert_array_equal(s.evaluate([1, 0]), [1, 0, 0])
    np.testing.assert_array_equal(s.evaluate([0, 1]), [0, 1, 0])  # v varies fastest


@pytest.mark.parametrize("doc, cls, phrase", [
    ({"shape": {"type": "curve", "data": []}}, FileFormatError, "only 'surface'"),
    (geomdl_doc(knotvector_v=None), InvalidSurfaceError, "shape.data[0].knots_v"),
    ({"shape": {"type": "surface", "data": [{"size_u": 2}]}}, FileFormatError,
     "missing field"),
    (geomdl_doc(size_u=3), FileFormatError, "expected 6 points"),
    (geomdl_doc(control_points={"points": [[0, 0, 0]] * 4, "weights": [1, 1, 1, -1]}),
     InvalidSurfaceError, "shape.data[0].weights"),
    (geomdl_doc(knotvector_u=[0, 1, 1]), InvalidSurfaceError, "shape.data[0].knots_u"),
    (geomdl_doc(control_points=[[0, 0, 0]] * 4), FileFormatError, "shape.data[0]"),
    (geomdl_doc(control_points={"points": [[0, 0, 0]] * 4, "weights": 7}), FileFormatError,
     "shape.data[0]"),
    (geomdl_doc(control_points={"points": [[0, 0, 0]] * 4, "weights": [[1, 2], 7]}),
     FileFormatError, "shape.data[0]"),
    ({"shape": {"type": "surface", "data": [5]}}, FileFormatError, "shape.data[0]"),
], ids=["curve", "null_knots", "missing_fields", "size_mismatch", "bad_weight",
        "bad_knots", "points_not_object", "weights_not_list", "ragged_weights",
        "data_item_int"])
def test_load_bad_geomdl_files(tmp_path, doc, cls, phrase):
    p = write_json(tmp_path / "g.json", doc)
    expect_load_error(p, cls, phrase)


@pytest.mark.parametrize("doc", [{"shape": 5}, {"shape": []},
                                 {"shape": {"type": "surface", "data": 5}},
                                 {"shape": "surface"}],
                         ids=["int", "list", "data_int", "str"])
def test_load_malformed_geomdl_shape(tmp_path, doc):
    p = write_json(tmp_path / "g.json", doc)
    expect_load_error(p, FileFormatError)


def test_load_unusable_path_is_a_file_format_error(tmp_path):
    expect_load_error(tmp_path / ("x" * 300 + ".json"), FileFormatError)


# ------------------------------------------------- geomkit.load on CAD files
def test_load_reads_iges_by_suffix_and_lists_skipped_faces(tmp_path):
    """``geomkit.load`` / ``load_case`` read an IGES file through ``read_iges`` (same
    surfaces, same refusal), instead of failing on it as invalid JSON."""
    from geomkit import load, load_case, read_iges

    from helpers.igeswrite import de, write_iges

    path = tmp_path / "Part.IGES"
    ellipse = [(104, [1 / a ** 2, 0.0, 1 / b ** 2, 0.0, 0.0, -1.0, z, a * np.cos(0.3),
                      b * np.sin(0.3), a * np.cos(2.0), b * np.sin(2.0)], 1)
               for a, b, z in ((4, 2, 0.0), (2, 1.5, 5.0))]
    write_iges(path, ellipse + [(118, [de(0), de(1), 0, 1], 0),  # arc-length rulings: refused
                                (110, [0.0, 0.0, 9.0, 1.0, 0.0, 9.0]),
                                (110, [0.0, 1.0, 9.0, 1.0, 1.0, 9.0]),
                                (118, [de(3), de(4), 0, 1], 0)])
    before = path.read_bytes()
    with pytest.raises(FileFormatError, match="118@5"):
        load(path)
    case = load_case(path, skip_unsupported=True)
    ref = read_iges(path, skip_unsupported=True)
    assert case.name == "Part" and case.units == "mm"
    assert [s.name for s in case.surfaces] == [s.name for s in ref.surfaces] == ["118@11"]
    assert np.array_equal(case.surfaces[0].control_points, ref.surfaces[0].control_points)
    assert [str(x) for x in case.skipped] == [str(x) for x in ref.skipped]
    assert [s.name for s in load(path, skip_unsupported=True)] == ["118@11"]
    assert path.read_bytes() == before                       # the input is untouched


def test_load_reads_step_by_suffix(tmp_path):
    pytest.importorskip("OCP")
    from OCP.BRepPrimAPI import BRepPrimAPI_MakeCylinder
    from OCP.STEPControl import STEPControl_AsIs, STEPControl_Writer

    from geomkit import load, load_case, read_step

    w = STEPControl_Writer()
    w.Transfer(BRepPrimAPI_MakeCylinder(3, 7).Shape(), STEPControl_AsIs)
    path = tmp_path / "cyl.stp"
    w.Write(str(path))
    surfs = load(path)
    ref = read_step(path)
    assert [s.name for s in surfs] == [s.name for s in ref.surfaces] and len(surfs) == 3
    for a, b in zip(surfs, ref.surfaces):
        assert np.array_equal(a.control_points, b.control_points)
    case = load_case(str(path))
    assert case.units == "mm" and case.skipped == [] and case.name == "cyl"


def test_load_names_a_missing_cad_file(tmp_path):
    with pytest.raises(FileFormatError, match="nope.igs"):
        load(tmp_path / "nope.igs")
