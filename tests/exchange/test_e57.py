"""E57 scans (ASTM E2807) through pye57: every scan placed by its pose, invalid points
skipped, read in chunks; intensity and colours kept in the streamed per-point output
(as LAS intensity is); a damaged file is a FileFormatError naming it."""

from __future__ import annotations

import csv
import io
import json

import numpy as np
import pytest

from geomkit import samples
from geomkit.errors import FileFormatError
from geomkit.exchange.points import read_points
from geomkit.exchange.scans import iter_scan, iter_scan_attrs, scan_length
from geomkit.jobs.stream import stream_deviation
from helpers.clihelp import run_main

pye57 = pytest.importorskip("pye57", reason="needs geomkit[scale] (pye57)")


def _scan(P, rng, state=None):
    d = {"cartesianX": P[:, 0].copy(), "cartesianY": P[:, 1].copy(),
         "cartesianZ": P[:, 2].copy(), "intensity": rng.random(len(P)).astype("f"),
         "colorRed": rng.integers(0, 256, len(P)).astype("B"),
         "colorGreen": rng.integers(0, 256, len(P)).astype("B"),
         "colorBlue": rng.integers(0, 256, len(P)).astype("B")}
    if state is not None:
        d["cartesianInvalidState"] = state
    return d


@pytest.fixture(scope="module")
def e57(tmp_path_factory):
    d = tmp_path_factory.mktemp("e57")
    rng = np.random.default_rng(7)
    P = rng.normal(size=(700, 3)) * 10
    a, b = _scan(P, rng), _scan(P[:300], rng, np.where(np.arange(300) % 7 == 3, 2, 0)
                                .astype("b"))
    th = 0.8  # the second scan's pose: a turn about z by th and a shift
    q = np.array([np.cos(th / 2), 0, 0, np.sin(th / 2)])
    f = pye57.E57(str(d / "two.e57"), mode="w")
    f.write_scan_raw(a)
    f.write_scan_raw(b, rotation=q, translation=np.array([100.0, -5.0, 2.0]))
    f.close()
    R = np.array([[np.cos(th), -np.sin(th), 0], [np.sin(th), np.cos(th), 0], [0, 0, 1]])
    keep = np.arange(300) % 7 != 3
    X = np.vstack([np.column_stack([a[c] for c in ("cartesianX", "cartesianY",
                                                   "cartesianZ")]),
                   np.column_stack([b[c] for c in ("cartesianX", "cartesianY",
                                                   "cartesianZ")])[keep] @ R.T
                   + [100.0, -5.0, 2.0]])
    I = np.concatenate([a["intensity"], b["intensity"][keep]])
    red = np.concatenate([a["colorRed"], b["colorRed"][keep]])
    return d / "two.e57", X, I, red


def test_scans_placed_by_their_poses_in_chunks(e57):
    path, X, I, red = e57
    assert scan_length(path) == 1000                      # as stored, invalid included
    chunks = list(iter_scan_attrs(path, 128))
    assert max(len(c[0]) for c in chunks) <= 128
    P = np.vstack([c[0] for c in chunks])
    assert P.shape == X.shape == (957, 3)
    # coordinates as the file stores them (pye57 writes them as single floats)
    assert np.abs(P - X).max() < 1e-5 * np.abs(X).max()
    assert np.array_equal(np.concatenate([c[2]["intensity"] for c in chunks]), I)
    assert np.array_equal(np.concatenate([c[2]["red"] for c in chunks]), red)
    assert all(set(c[2]) == {"intensity", "red", "green", "blue"} for c in chunks)
    assert np.array_equal(read_points(path).points, P)
    assert np.array_equal(np.vstack([c[0] for c in iter_scan(path, 1000)]), P)


def test_streamed_output_keeps_intensity_and_colour(e57):
    path, X, I, red = e57
    buf = io.BytesIO()
    st = stream_deviation(samples.load("sphere"), path, buf, chunk_size=200)
    assert st["points"] == 957 and st["attributes"] == ["intensity", "red", "green",
                                                         "blue"]
    rows = list(csv.DictReader(io.StringIO(buf.getvalue().decode())))
    assert len(rows) == 957 and list(rows[0])[-4:] == ["intensity", "red", "green", "blue"]
    assert np.allclose([float(r["intensity"]) for r in rows], I, rtol=1e-7, atol=0)
    assert [int(r["red"]) for r in rows] == red.tolist()


def test_las_intensity_is_kept(tmp_path):
    laspy = pytest.importorskip("laspy")
    h = laspy.LasHeader(point_format=3, version="1.2")
    h.scales, h.offsets = [1e-4] * 3, [0, 0, 0]
    las = laspy.LasData(h)
    P = np.random.default_rng(2).normal(size=(50, 3)) * 10
    las.x, las.y, las.z = P[:, 0], P[:, 1], P[:, 2]
    las.intensity = np.arange(50, dtype=np.uint16) * 7
    las.red = np.arange(50, dtype=np.uint16)
    las.write(str(tmp_path / "s.las"))
    buf = io.BytesIO()
    st = stream_deviation(samples.load("sphere"), tmp_path / "s.las", buf, chunk_size=16)
    assert st["attributes"] == ["intensity", "red", "green", "blue"]
    rows = list(csv.DictReader(io.StringIO(buf.getvalue().decode())))
    assert [int(r["intensity"]) for r in rows] == list(range(0, 350, 7))


def test_cli_streams_e57_with_json(e57, tmp_path, capsys):
    path = e57[0]
    rc, out, err = run_main(capsys, "deviation", "sphere", path, "-o", tmp_path / "r",
                            "--json")
    assert rc == 0, err
    s = json.loads(out)
    assert s["streamed"] and s["points"] == 957 and "intensity" in s["attributes"]
    head = (tmp_path / "r" / "deviation.csv").read_text().splitlines()[0]
    assert head.endswith(",edge,intensity,red,green,blue")


@pytest.mark.parametrize("cut", [0.5, 0.05])
def test_damaged_e57_is_a_file_format_error(e57, tmp_path, cut):
    data = e57[0].read_bytes()
    bad = tmp_path / "bad.e57"
    bad.write_bytes(data[:int(len(data) * cut)])
    with pytest.raises(FileFormatError, match="bad.e57: cannot read as E57"):
        list(iter_scan(bad))


def test_damaged_las_header_is_refused_before_laspy(tmp_path):
    """A count of variable-length records bigger than the header has room for (a
    fuzz finding: laspy then loops for minutes and allocates gigabytes)."""
    laspy = pytest.importorskip("laspy")
    h = laspy.LasHeader(point_format=3, version="1.2")
    las = laspy.LasData(h)
    las.x = las.y = las.z = np.zeros(5)
    las.write(str(tmp_path / "s.las"))
    raw = bytearray((tmp_path / "s.las").read_bytes())
    raw[100:104] = (331728640).to_bytes(4, "little")
    (tmp_path / "v.las").write_bytes(bytes(raw))
    with pytest.raises(FileFormatError, match="331728640 variable-length records"):
        list(iter_scan(tmp_path / "v.las"))
    raw = bytearray((tmp_path / "s.las").read_bytes())
    raw[107:111] = (10 ** 6).to_bytes(4, "little")
    (tmp_path / "n.las").write_bytes(bytes(raw))
    with pytest.raises(FileFormatError, match="truncated LAS file"):
        list(iter_scan(tmp_path / "n.las"))


def test_a_laz_file_that_aborts_the_decompressor_is_an_error():
    """lazrs aborts the whole process on this file (found by the long fuzz run); LAZ
    is decompressed in a child process, so here it is one FileFormatError, in the API
    and through the command line."""
    pytest.importorskip("laspy")
    from helpers.paths import DATA

    path = DATA / "malformed" / "lazrs_abort.laz"
    with pytest.raises(FileFormatError, match="LAZ decompressor failed .*corrupt"):
        list(iter_scan(path))
    assert scan_length(path) == 60         # the header's count, no decompression here
