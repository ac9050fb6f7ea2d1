"""Property tests (Hypothesis) of the point readers' round trips: points written by an
independent writer (Python's own float formatting, numpy, laspy, pye57) are read back
by geomkit as written — bit for bit for the float64 formats, within the format's
storage (LAS scale, E57 single floats) otherwise — in any chunking, normals
normalised and kept with their points."""

from __future__ import annotations

import tempfile
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings, strategies as st
from hypothesis.extra.numpy import arrays

from geomkit.exchange.points import read_points
from geomkit.exchange.scans import iter_scan

SETTINGS = dict(deadline=None, max_examples=40,
                suppress_health_check=[HealthCheck.function_scoped_fixture])
coords = st.floats(min_value=-1e6, max_value=1e6, allow_nan=False, width=64)
points = st.integers(1, 40).flatmap(lambda n: arrays(np.float64, (n, 3), elements=coords))


def _chunks(path, chunk):
    parts = list(iter_scan(path, chunk))
    P = np.vstack([p for p, _ in parts])
    N = None if parts[0][1] is None else np.vstack([n for _, n in parts])
    return P, N


# One folder for the module, removed when the test process ends; each example gets its
# own subfolder in it (Hypothesis runs many examples per test).
_ROOT = tempfile.TemporaryDirectory(prefix="geomkit-rt-")


def _tmp():
    return Path(tempfile.mkdtemp(dir=_ROOT.name))


@settings(**SETTINGS)
@given(P=points, sep=st.sampled_from([",", ";", "\t", " ", ", "]),
       header=st.sampled_from([None, "x,y,z", "X Y Z", "id;x;y;z"]),
       ext=st.sampled_from([".csv", ".xyz", ".txt"]), chunk=st.integers(1, 50))
def test_text_round_trip(P, sep, header, ext, chunk):
    d = _tmp()
    lines = []
    if header is not None:
        names = header.replace(",", " ").replace(";", " ").split()
        lines.append(sep.join(names))
    for k, row in enumerate(P):
        vals = [repr(float(v)) for v in row]
        if header == "id;x;y;z":
            vals = [f"p{k}"] + vals
        lines.append(sep.join(vals))
    path = d / f"pts{ext}"
    path.write_text("\n".join(lines) + "\n")
    assert np.array_equal(read_points(path).points, P)
    Q, N = _chunks(path, chunk)
    assert np.array_equal(Q, P) and N is None


@settings(**SETTINGS)
@given(P=points, comma_sep=st.sampled_from([";", "\t", " "]))
def test_decimal_comma_round_trip(P, comma_sep):
    path = _tmp() / "pts.csv"
    fmt = (lambda v: repr(float(v)).replace(".", ",") if "e" not in repr(float(v))
           else f"{v:.17f}".rstrip("0").replace(".", ","))
    path.write_text("".join(comma_sep.join(fmt(v) for v in row) + "\n" for row in P))
    assert np.allclose(read_points(path).points, P, rtol=1e-15, atol=1e-16)


@settings(**SETTINGS)
@given(P=points, normals=arrays(np.float64, (40, 3),
                                elements=st.floats(-1, 1, allow_nan=False)),
       fmt=st.sampled_from(["npy", "ply-ascii", "ply-le", "ply-be", "csv"]),
       chunk=st.integers(1, 50))
def test_points_with_normals_round_trip(P, normals, fmt, chunk):
    N = normals[:len(P)]
    N[np.linalg.norm(N, axis=1) < 1e-3] = [0.0, 0.0, 1.0]
    A = np.hstack([P, N])
    d = _tmp()
    if fmt == "npy":
        path = d / "p.npy"
        np.save(path, A)
    elif fmt == "csv":
        path = d / "p.csv"
        path.write_text("x,y,z,i,j,k\n" + "".join(
            ",".join(repr(float(v)) for v in r) + "\n" for r in A))
    else:
        path = d / "p.ply"
        kind = {"ply-ascii": "ascii", "ply-le": "binary_little_endian",
                "ply-be": "binary_big_endian"}[fmt]
        head = (f"ply\nformat {kind} 1.0\nelement vertex {len(A)}\n"
                + "".join(f"property double {c}\n" for c in ("x", "y", "z", "nx", "ny", "nz"))
                + "end_header\n").encode()
        if kind == "ascii":
            body = "".join(" ".join(repr(float(v)) for v in r) + "\n" for r in A).encode()
        else:
            body = A.astype("<f8" if kind.endswith("little_endian") else ">f8").tobytes()
        path.write_bytes(head + body)
    Q, M = _chunks(path, chunk)
    assert np.array_equal(Q, P)
    assert np.allclose(M, N / np.linalg.norm(N, axis=1)[:, None], rtol=0, atol=1e-15)
    ps = read_points(path)
    assert np.array_equal(ps.points, P) and np.array_equal(ps.normals, M)


@settings(**SETTINGS)
@given(P=arrays(np.float64, st.tuples(st.integers(1, 60), st.just(3)),
                elements=st.floats(-1e4, 1e4, allow_nan=False)),
       chunk=st.integers(1, 64), laz=st.booleans())
def test_las_round_trip_within_its_scale(P, chunk, laz):
    laspy = pytest.importorskip("laspy")
    h = laspy.LasHeader(point_format=3, version="1.2")
    h.scales, h.offsets = [1e-4] * 3, np.floor(P.min(axis=0))
    las = laspy.LasData(h)
    las.x, las.y, las.z = P[:, 0], P[:, 1], P[:, 2]
    path = _tmp() / ("p.laz" if laz else "p.las")
    las.write(str(path))
    Q, N = _chunks(path, chunk)
    assert N is None and Q.shape == P.shape
    assert np.abs(Q - P).max() <= 0.5e-4 * (1 + 1e-9)


@settings(**SETTINGS)
@given(P=arrays(np.float64, st.tuples(st.integers(1, 60), st.just(3)),
                elements=st.floats(-1e4, 1e4, allow_nan=False)),
       chunk=st.integers(1, 64))
def test_e57_round_trip(P, chunk):
    pye57 = pytest.importorskip("pye57")
    path = _tmp() / "p.e57"
    f = pye57.E57(str(path), mode="w")
    f.write_scan_raw({"cartesianX": P[:, 0].copy(), "cartesianY": P[:, 1].copy(),
                      "cartesianZ": P[:, 2].copy()})
    f.close()
    Q, N = _chunks(path, chunk)
    assert N is None and Q.shape == P.shape
    # pye57 stores the coordinates as single floats
    assert np.array_equal(Q, P.astype(np.float32).astype(np.float64)) or \
        np.allclose(Q, P, rtol=2 ** -23, atol=0)
