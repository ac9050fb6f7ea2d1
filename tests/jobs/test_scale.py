"""Issue 16 (deviation at scale) and issue 18 item 5's point-file items: chunked scan
readers, streamed deviation equal to the in-memory one, incremental statistics against
brute force, folders of scans, the CLI's streamed path.  The Dask tests are in
tests/jobs/test_scale_dask.py."""

import io
import json
import math


import numpy as np
import pytest

import geomkit
from geomkit import samples
from geomkit.jobs.deviation import deviation
from geomkit.jobs.stats import DeviationStats
from geomkit.tolerances import PERCENTILE_REL_ERROR
from geomkit.exchange.points import read_points
from geomkit.exchange.scans import iter_scan, scan_length
from geomkit.jobs.stream import COLUMNS, stream_deviation

from helpers.clihelp import assert_one_line_error, cli


# ------------------------------------------------------------------ issue 18 item 5
@pytest.mark.parametrize("text, points, normals", [
    ("50,5 0,0 50,0\n1,25 2 -3,5\n", [[50.5, 0, 50], [1.25, 2, -3.5]], None),
    ("50,5;0,0;50,0\n", [[50.5, 0, 50]], None),
    ("50,5\t0,0\t50,0\t0\t0\t2\n", [[50.5, 0, 50]], [[0, 0, 1]]),
    ("x;y;z\n1,5;2;3\n", [[1.5, 2, 3]], None),
    ("id,x,y,z\n7,1,2,3\n8,4,5,6\n", [[1, 2, 3], [4, 5, 6]], None),
    ("name x y z\nP1 1 2 3\n", [[1, 2, 3]], None),
    ("x,y,z,nx,ny,nz\n1,2,3,0,0,2\n", [[1, 2, 3]], [[0, 0, 1]]),
    ("Z,id,Y,X\n3,a,2,1\n", [[1, 2, 3]], None),
    ("pt;X;Y;Z;I;J;K\nA;1,5;2;3;0;1;0\n", [[1.5, 2, 3]], [[0, 1, 0]]),
    ("1,2,3\n", [[1, 2, 3]], None),
    ("50,5,0,0,50,0\n", [[50, 5, 0]], [[0, 1, 0]]),  # commas as separators: 6 columns
])
def test_point_file_headers_and_decimal_commas(tmp_path, text, points, normals):
    p = tmp_path / "p.csv"
    p.write_text(text)
    ps = read_points(p)
    assert ps.points.tolist() == points
    assert (ps.normals is None if normals is None else ps.normals.tolist() == normals)


@pytest.mark.parametrize("text, phrase", [
    ("50,5 0,0 50,0\n1.5 2 3\n", "line 2: decimal point"),
    ("id,x,y\n1,2,3\n", "line 1: header"),
    ("x,x,y,z\n1,2,3,4\n", "twice"),
    ("id,x,y,z\n1,2,3\n", "line 2: expected 4 columns"),
    ("name x y z\nP1 1 abc 3\n", "line 2: not a number"),
])
def test_point_file_header_errors(tmp_path, text, phrase):
    p = tmp_path / "p.csv"
    p.write_text(text)
    with pytest.raises(geomkit.FileFormatError, match=phrase):
        read_points(p)


# ------------------------------------------------------------------ scan readers
def write_ply(path, P, N=None, fmt="binary_little_endian", declared=None):
    n = P.shape[0] if declared is None else declared
    props = "xyz" if N is None else ["x", "y", "z", "nx", "ny", "nz"]
    head = ["ply", f"format {fmt} 1.0", "comment geomkit test", f"element vertex {n}"]
    head += [f"property {'float' if k < 3 else 'double'} {q}" for k, q in enumerate(props)]
    head += ["element face 0", "property list uchar int vertex_indices", "end_header"]
    A = P if N is None else np.hstack([P, N])
    with open(path, "wb") as fh:
        fh.write(("\n".join(head) + "\n").encode())
        if fmt == "ascii":
            fh.write("".join(" ".join(repr(float(v)) for v in r) + "\n"
                             for r in A).encode())
        else:
            e = "<" if fmt == "binary_little_endian" else ">"
            rec = np.zeros(A.shape[0], dtype=[(q, e + ("f4" if k < 3 else "f8"))
                                              for k, q in enumerate(props)])
            for k, q in enumerate(props):
                rec[q] = A[:, k]
            fh.write(rec.tobytes())
    return path


def _las(path, P):
    laspy = pytest.importorskip("laspy")
    h = laspy.LasHeader(point_format=0, version="1.2")
    h.scales = np.array([1e-4, 1e-4, 1e-4])
    h.offsets = np.zeros(3)
    las = laspy.LasData(h)
    las.x, las.y, las.z = P[:, 0], P[:, 1], P[:, 2]
    las.write(str(path))
    return path


@pytest.fixture
def cloud():
    rng = np.random.default_rng(3)
    return np.round(rng.uniform(-5, 5, (1000, 3)), 3)


def _read_all(path, chunk):
    parts = list(iter_scan(path, chunk))
    assert all(p.shape[0] <= chunk for p, _ in parts)
    return np.concatenate([p for p, _ in parts]), parts[0][1] is not None


@pytest.mark.parametrize("kind", ["npy", "npy6", "ply", "ply_be", "ply_ascii", "ply_n",
                                  "csv", "las", "laz"])
def test_scan_readers_chunked(tmp_path, cloud, kind):
    P = cloud
    f32 = P.astype(np.float32).astype(np.float64)
    N = np.tile([0.0, 0.0, 2.0], (P.shape[0], 1))
    if kind == "npy":
        path, want = tmp_path / "s.npy", P
        np.save(path, P)
    elif kind == "npy6":
        path, want = tmp_path / "s.npy", P
        np.save(path, np.hstack([P, N]))
    elif kind in ("ply", "ply_be", "ply_ascii"):
        fmt = {"ply": "binary_little_endian", "ply_be": "binary_big_endian",
               "ply_ascii": "ascii"}[kind]
        path, want = write_ply(tmp_path / "s.ply", f32, fmt=fmt), f32
    elif kind == "ply_n":
        path, want = write_ply(tmp_path / "s.ply", f32, N), f32
    elif kind == "csv":
        path, want = tmp_path / "s.xyz", P
        np.savetxt(path, P, header="x y z")
    else:
        pytest.importorskip("lazrs") if kind == "laz" else None
        path, want = _las(tmp_path / f"s.{kind}", P), P
    got, has_n = _read_all(path, 128)
    assert np.allclose(got, want, rtol=0, atol=1e-9 if kind in ("las", "laz") else 0)
    assert has_n == (kind in ("npy6", "ply_n"))
    assert np.allclose(read_points(path).points, want, rtol=0, atol=1e-9)
    if kind != "csv":
        assert scan_length(path) == P.shape[0]


def test_scan_bad_inputs(tmp_path, cloud):
    P = cloud.astype(np.float32).astype(np.float64)
    cases = []
    # truncated binary PLY: the header declares more vertices than the file holds
    cases.append((write_ply(tmp_path / "t.ply", P, declared=1200), "truncated PLY.*1200"))
    a = write_ply(tmp_path / "ta.ply", P[:5], fmt="ascii", declared=9)
    cases.append((a, "truncated PLY"))
    Q = P.copy()
    Q[700, 1] = np.nan
    np.save(tmp_path / "nan.npy", Q)
    cases.append((tmp_path / "nan.npy", "row 700: non-finite"))
    (tmp_path / "text.csv").write_text("1,2,3\n4,five,6\n")
    cases.append((tmp_path / "text.csv", "line 2: not a number"))
    (tmp_path / "nan.csv").write_text("x,y,z\n1,2,3\n1,nan,3\n")
    cases.append((tmp_path / "nan.csv", "line 3: non-finite"))
    np.save(tmp_path / "shape.npy", np.zeros((4, 2)))
    cases.append((tmp_path / "shape.npy", r"shape \(n, 3\)"))
    np.save(tmp_path / "empty.npy", np.zeros((0, 3)))
    cases.append((tmp_path / "empty.npy", "no points"))
    raw = (tmp_path / "nan.npy").read_bytes()
    (tmp_path / "cut.npy").write_bytes(raw[:len(raw) // 2])
    cases.append((tmp_path / "cut.npy", "truncated .npy"))
    # PLY headers the reader fuzz test broke (issue: "element verte x 200" gave a
    # ValueError, a short line an IndexError, a repeated property numpy's error)
    good = write_ply(tmp_path / "g.ply", P[:5]).read_bytes()
    for k, (old, new, phrase) in enumerate([
            (b"element vertex 5", b"element verte x 5", "expected 'element NAME COUNT'"),
            (b"element vertex 5", b"element vertex", "expected 'element NAME COUNT'"),
            (b"property float y", b"property float x", "declared twice"),
            (b"property float y", b"property flot y", "expected 'property TYPE NAME'"),
            (b"format binary_little_endian 1.0", b"format", "no format"),
            (b"comment geomkit test", b"garbage here", "not understood")]):
        assert old in good
        (tmp_path / f"h{k}.ply").write_bytes(good.replace(old, new, 1))
        cases.append((tmp_path / f"h{k}.ply", phrase))
    try:
        import laspy
        h = laspy.LasHeader(point_format=0, version="1.2")
        laspy.LasData(h).write(str(tmp_path / "none.las"))
        cases.append((tmp_path / "none.las", "no points"))
    except ImportError:
        pass
    for path, phrase in cases:
        with pytest.raises(geomkit.FileFormatError, match=phrase) as ei:
            list(iter_scan(path, 256))
        assert str(path) in str(ei.value)


# ------------------------------------------------------------------ statistics
def test_stats_chunked_equal_and_percentiles_bounded():
    rng = np.random.default_rng(7)
    v = np.concatenate([rng.normal(0.01, 0.03, 20000), rng.uniform(-1e-3, 1e-3, 500),
                        [0.0, 0.0, 1e-14, -1e-13]])
    rng.shuffle(v)
    d = v.copy()
    d[::97] = np.nan
    status = np.where(np.isfinite(d), 0, geomkit.query.results.BEYOND).astype(np.int8)
    edge = np.zeros(d.size, bool)
    one = DeviationStats((-0.04, 0.05))
    one.update(d, status, edge)
    many = DeviationStats((-0.04, 0.05))
    for a in range(0, d.size, 333):
        many.update(d[a:a + 333], status[a:a + 333], edge[a:a + 333])
    r1, r2 = one.result(), many.result()
    for k in ("points", "valid", "beyond", "min", "max", "mean", "rms", "within", "over",
              "under", "max_abs", "argmax_abs", "percentiles"):
        assert r1[k] == r2[k], k
    assert math.isclose(r1["std"], r2["std"], rel_tol=1e-12)
    w = d[np.isfinite(d)]
    assert r1["valid"] == w.size
    assert r1["mean"] == math.fsum(w) / w.size            # exactly rounded sums
    assert r1["rms"] == math.sqrt(math.fsum(w * w) / w.size)
    assert r1["within"] == np.count_nonzero((w >= -0.04) & (w <= 0.05))
    assert r1["argmax_abs"] == int(np.nanargmax(np.abs(d)))
    s = np.sort(w)
    for p in (1, 5, 25, 50, 75, 95, 99):
        true = s[int(math.floor(p / 100 * (w.size - 1)))]
        est = r1["percentiles"][f"p{p}"]
        assert abs(est - true) <= PERCENTILE_REL_ERROR * abs(true) * (1 + 1e-9) + 1e-12


def test_stats_no_valid_point_is_an_error():
    acc = DeviationStats()
    acc.update(np.full(4, np.nan), np.full(4, geomkit.query.results.BEYOND, np.int8),
               np.zeros(4, bool))
    with pytest.raises(geomkit.InvalidInputError, match="no valid point"):
        acc.result(require_valid=True)


# ------------------------------------------------------------------ streamed job
@pytest.fixture(scope="module")
def torus_scan(tmp_path_factory):
    d = tmp_path_factory.mktemp("scan")
    rng = np.random.default_rng(11)
    P = rng.uniform(-13, 13, (1500, 3)) * [1, 1, 0.4]
    N = rng.normal(size=P.shape)
    np.save(d / "t.npy", np.hstack([P, N]))
    return d, P, N


def test_stream_equals_in_memory_bit_for_bit(torus_scan):
    d, P, N = torus_scan
    tor = samples.load("torus")
    kw = dict(probe_radius=0.5, tolerance=(-0.3, 0.2), max_distance=2.0)
    rep = deviation(tor, P, N, **kw)
    buf = io.BytesIO()
    st = stream_deviation(tor, d / "t.npy", buf, fmt="parquet", chunk_size=256, **kw)
    pq = pytest.importorskip("pyarrow.parquet")
    t = pq.read_table(io.BytesIO(buf.getvalue()))
    assert t.column_names == list(COLUMNS)
    col = {c: t.column(c).to_numpy(zero_copy_only=False) for c in COLUMNS}
    assert np.array_equal(col["index"], np.arange(len(P)))
    want = {"deviation": rep.deviation, "signed_distance": rep.signed_distance,
            "foot_x": rep.foot[:, 0], "foot_z": rep.foot[:, 2], "u": rep.uv[:, 0],
            "nz": rep.normal[:, 2], "surface": rep.surface}
    for c, w in want.items():
        a = np.where(np.isnan(col[c].astype(float)), np.nan, col[c].astype(float))
        assert np.array_equal(a, np.asarray(w, float), equal_nan=True), c
    names = geomkit.query.results.STATUS_NAMES
    assert list(col["status"]) == [names[int(s)] for s in rep.status]
    assert 0 < st["valid"] < st["points"] == len(P)
    for k in ("valid", "beyond", "edge", "min", "max", "mean", "rms", "within",
              "pct_within", "percentiles", "argmax_abs"):
        assert st[k] == rep.stats[k], k
    assert st["chunks"] == math.ceil(len(P) / 256)


def test_stream_csv_round_trips(torus_scan):
    d, P, N = torus_scan
    tor = samples.load("torus")
    rep = deviation(tor, P[:300], N[:300], probe_radius=0.5)
    np.save(d / "s.npy", np.hstack([P[:300], N[:300]]))
    buf = io.BytesIO()
    stream_deviation(tor, d / "s.npy", buf, probe_radius=0.5, chunk_size=100)
    lines = buf.getvalue().decode().splitlines()
    assert lines[0] == ",".join(COLUMNS) and len(lines) == 301
    dev = [float(r.split(",")[17]) if r.split(",")[17] else np.nan for r in lines[1:]]
    assert np.array_equal(dev, rep.deviation, equal_nan=True)


def test_csv_writer_without_pyarrow_same_values(torus_scan):
    from geomkit.query.projection import Projector
    from geomkit.jobs.stream import CSVWriter, deviation_chunk

    d, P, N = torus_scan
    cols = deviation_chunk(Projector(samples.load("torus")), P[:200], None, None, 0.0,
                           1.0, 0)
    texts = []
    for arrow in (True, False):
        buf = io.BytesIO()
        w = CSVWriter(buf)
        w.arrow = arrow
        w.write(cols)
        texts.append(buf.getvalue().decode().splitlines())
    a, b = texts
    assert a[0] == b[0] and len(a) == len(b) == 201
    for ra, rb in zip(a[1:], b[1:]):
        fa, fb = ra.split(","), rb.split(",")
        assert fa[18:] == fb[18:]
        assert [float(x) if x else None for x in fa[:18]] == \
            [float(x) if x else None for x in fb[:18]]


def test_stream_align_on_subsample(tmp_path):
    ff = samples.load("freeform_1")
    s = ff[0]
    (u0, u1), (v0, v1) = s.domain
    g = np.linspace(0.05, 0.95, 60)
    uv = np.stack(np.meshgrid(u0 + g * (u1 - u0), v0 + g * (v1 - v0)), -1).reshape(-1, 2)
    S = geomkit.evaluate(s, uv)
    from scipy.spatial.transform import Rotation
    R = Rotation.from_rotvec([0.004, -0.003, 0.002]).as_matrix()
    t = np.array([0.05, -0.02, 0.03])
    np.save(tmp_path / "s.npy", S @ R.T + t)
    import geomkit.jobs.stream as St
    old = St.ALIGN_SAMPLE
    St.ALIGN_SAMPLE = 500
    try:
        st = stream_deviation(ff, tmp_path / "s.npy", None, align=True, chunk_size=1000)
    finally:
        St.ALIGN_SAMPLE = old
    a = st["alignment"]
    assert a["sample_points"] <= 500 and a["sample_stride"] == 8  # 3600 -> every 8th
    T = np.asarray(a["transform"])
    assert np.allclose(T[:3, :3] @ R, np.eye(3), atol=1e-8)
    assert st["valid"] == 3600 and st["max_abs"] < 1e-8


# ------------------------------------------------------------------ CLI
def test_cli_streamed_scan_and_bad_inputs(tmp_path, torus_scan):
    d, P, N = torus_scan
    out = tmp_path / "rep"
    r = cli(*["deviation", "torus", str(d / "t.npy"), "-o", str(out), "--tolerance",
                 "0.3", "--max-distance", "2", "--json"])
    assert r.returncode == 0, r.stderr
    s = json.loads(r.stdout)
    assert s["streamed"] and s["points"] == len(P)
    assert sorted(p.name for p in out.iterdir()) == ["deviation.csv", "summary.json"]
    assert json.loads((out / "summary.json").read_text())["valid"] == s["valid"]
    # no valid point: one line, exit 2, no folder left
    far = tmp_path / "far.npy"
    np.save(far, np.full((5, 3), 100.0))
    r = cli(*["deviation", "torus", str(far), "-o", str(tmp_path / "x"),
                 "--max-distance", "1"])
    assert_one_line_error(r, "no valid point")
    assert not (tmp_path / "x").exists()
    bad = write_ply(tmp_path / "bad.ply", P[:10], declared=20)
    r = cli(*["deviation", "torus", str(bad), "-o", str(tmp_path / "y")])
    assert_one_line_error(r, "truncated PLY", str(bad))
    assert not (tmp_path / "y").exists()


def test_cli_folder_batch(tmp_path):
    sph = samples.load("sphere")[0]
    rng = np.random.default_rng(4)
    scans = tmp_path / "scans"
    scans.mkdir()
    uv = rng.uniform(0.05, 0.95, (200, 2))
    S = geomkit.evaluate(sph, uv * [sph.domain[0][1] - sph.domain[0][0],
                                    sph.domain[1][1] - sph.domain[1][0]] +
                         [sph.domain[0][0], sph.domain[1][0]])
    Nn = S / np.linalg.norm(S, axis=1)[:, None]
    np.save(scans / "good.npy", S + 0.01 * Nn)                     # all within 0.02
    np.savetxt(scans / "over.csv", S + 0.05 * Nn, delimiter=",")  # all over
    (scans / "broken.csv").write_text("1,2,3\n4,x,6\n")
    (scans / "notes.md").write_text("not a scan")
    out = tmp_path / "batch"
    r = cli(*["deviation", "sphere", str(scans), "-o", str(out), "--tolerance",
                 "0.02", "--format", "parquet"])
    assert r.returncode == 0, r.stderr
    rows = (out / "parts.csv").read_text().splitlines()
    assert rows[0] == "part,file,points,valid,min,max,mean,rms,pct_within,pass,error"
    by = {r.split(",")[0]: r for r in rows[1:]}
    assert sorted(by) == ["broken", "good", "over"]
    assert by["good"].split(",")[9] == "pass" and by["over"].split(",")[9] == "fail"
    assert "line 2: not a number" in by["broken"]
    assert sorted(p.name for p in (out / "good").iterdir()) == ["deviation.parquet",
                                                                "summary.json"]
    assert not (out / "broken").exists()
    s = json.loads((out / "summary.json").read_text())
    assert (s["passed"], s["failed"], s["errors"]) == (1, 2, 1)
    g = json.loads((out / "good" / "summary.json").read_text())
    assert abs(g["mean"] - 0.01) < 1e-9 and g["pct_within"] == 100.0


def test_workers_without_the_extra(monkeypatch):
    import sys

    from geomkit.jobs.distributed import make_client
    monkeypatch.setitem(sys.modules, "distributed", None)
    with pytest.raises(geomkit.errors.MissingDependencyError,
                       match=r"pip install geomkit\[scale\]"):
        make_client(1)



