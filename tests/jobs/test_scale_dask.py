"""Issue 16, Dask: chunks as tasks on a LocalCluster of worker processes give the
single-process results byte for byte; a worker killed mid-run costs a rerun, never a
lost or duplicated row.  Tiny inputs and the cheap sphere (each worker process loads
the numba cache once)."""

import io
import json
import os
import signal

import numpy as np
import pytest

distributed = pytest.importorskip("distributed", reason="needs geomkit[scale] (dask)")

from geomkit import samples  # noqa: E402
from geomkit.jobs.stream import stream_deviation  # noqa: E402

from helpers.clihelp import cli  # noqa: E402


@pytest.fixture(scope="module")
def client():
    from geomkit.jobs.distributed import make_client

    c, cluster = make_client(2)
    yield c
    c.close()
    cluster.close()


@pytest.fixture(scope="module")
def scan(tmp_path_factory):
    d = tmp_path_factory.mktemp("dask")
    rng = np.random.default_rng(5)
    u = rng.normal(size=(3000, 3))
    u /= np.linalg.norm(u, axis=1)[:, None]
    P = u * (10 + rng.uniform(-0.05, 0.05, (3000, 1)))
    np.save(d / "s.npy", P)
    return d / "s.npy"


def _run(scan, client=None, progress=None):
    buf = io.BytesIO()
    st = stream_deviation(samples.load("sphere"), scan, buf, chunk_size=100,
                          tolerance=(-0.04, 0.04), probe_radius=0.25, client=client,
                          progress=progress)
    return buf.getvalue(), st


def test_dask_equals_single_process(client, scan):
    ref, st0 = _run(scan)
    got, st = _run(scan, client)
    assert got == ref                          # every byte of every row
    assert st["workers"] == 2 and st["chunks"] == 30
    for k in ("points", "valid", "min", "max", "mean", "rms", "std", "within",
              "percentiles"):
        assert st[k] == st0[k], k


def test_batch_on_workers_goes_on_past_broken_scans(client, scan, tmp_path):
    """An overnight batch over a folder on a Dask cluster: a truncated LAS file and a
    corrupt E57 file are parts with a one-line error in the table; the other parts
    are computed as without a cluster."""
    from geomkit.jobs.batch import batch_deviation

    d = tmp_path / "scans"
    d.mkdir()
    P = np.load(scan)[:500]
    np.save(d / "a_good.npy", P)
    laspy = pytest.importorskip("laspy")
    las = laspy.LasData(laspy.LasHeader(point_format=3, version="1.2"))
    las.x, las.y, las.z = P[:, 0], P[:, 1], P[:, 2]
    las.write(str(d / "b.las"))
    raw = (d / "b.las").read_bytes()
    (d / "b.las").write_bytes(raw[:len(raw) - 700])          # truncated
    (d / "c.e57").write_bytes(b"ASTM-E57" + bytes(range(256)) * 8)  # corrupt
    np.save(d / "d_good.npy", P[::-1])
    kw = dict(tolerance=(-0.04, 0.04), chunk_size=100)
    s = batch_deviation(samples.load("sphere"), d, tmp_path / "out", client=client, **kw)
    rows = {r["part"]: r for r in s["parts"]}
    assert "truncated LAS file" in rows["b"]["error"]
    assert "c.e57: cannot read as E57" in rows["c"]["error"]
    assert not (tmp_path / "out" / "b").exists() and not (tmp_path / "out" / "c").exists()
    assert s["errors"] == 2, {k: r["error"] for k, r in rows.items()}
    assert rows["a_good"]["error"] == "" == rows["d_good"]["error"]
    batch_deviation(samples.load("sphere"), d, tmp_path / "ref", **kw)  # no cluster
    for part in ("a_good", "d_good"):
        assert (tmp_path / "out" / part / "deviation.csv").read_bytes() == \
            (tmp_path / "ref" / part / "deviation.csv").read_bytes()


def test_dask_worker_killed_mid_run(client, scan):
    ref, _ = _run(scan)
    pids = client.run(os.getpid)
    victim = sorted(pids.values())[0]
    state = {"killed": False}

    def progress(done, _total):
        if not state["killed"]:
            os.kill(victim, signal.SIGKILL)
            state["killed"] = True

    got, st = _run(scan, client, progress)
    assert state["killed"]
    assert got == ref                          # no row lost, none duplicated
    idx = [int(r.split(b",")[0]) for r in got.splitlines()[1:]]
    assert idx == list(range(3000))
    client.wait_for_workers(2, timeout=180)    # the nanny restarted it
    assert victim not in client.run(os.getpid).values()


def test_cli_scheduler(client, tmp_path, scan):
    # the CLI on the running cluster (--workers N builds the same Client through
    # geomkit.jobs.distributed.make_client, as the fixture does)
    out = tmp_path / "rep"
    r = cli("deviation", "sphere", scan, "-o", out, "--scheduler",
            client.scheduler.address, "--chunk-size", "1000", "--tolerance", "0.04",
            "--probe-radius", "0.25", timeout=240)
    assert r.returncode == 0, r.stderr
    ref, _ = _run(scan)                        # other chunk size, same rows
    assert (out / "deviation.csv").read_bytes() == ref
    assert json.loads((out / "summary.json").read_text())["workers"] == 2
