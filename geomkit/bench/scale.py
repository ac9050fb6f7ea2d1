"""Deviation at scale: points per second single-process against 1 and 2 Dask workers
(same run, same points, results compared bit for bit), and peak memory against the
number of points of a streamed ``.npy`` scan.

The scan: points around the bundled sphere (radius 10) moved along the radius by a
uniform offset in [-0.05, 0.05], written chunk by chunk into a ``.npy`` file (never
whole in memory).  Each peak-memory run is a fresh subprocess (its VmHWM is
its own peak): ``stream_deviation`` over the file, read chunk by chunk, no per-point
output.

Usage::

    python -m geomkit.bench.scale throughput [--n 200000] [--chunk 16384]
    python -m geomkit.bench.scale memory --n 1e6 1e7 [--dir /tmp]
    python -m geomkit.bench.scale one FILE.npy     # one peak-memory run (subprocess)
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

CASE = "sphere"


def make_scan(path, n, chunk=1 << 20, seed=0):
    """A (n, 3) float64 .npy scan around the sphere, written chunk by chunk."""
    from numpy.lib.format import open_memmap

    A = open_memmap(path, mode="w+", dtype=np.float64, shape=(int(n), 3))
    rng = np.random.default_rng(seed)
    for a in range(0, int(n), chunk):
        m = min(chunk, int(n) - a)
        d = rng.normal(size=(m, 3))
        d /= np.linalg.norm(d, axis=1)[:, None]
        A[a:a + m] = d * (10.0 + rng.uniform(-0.05, 0.05, (m, 1)))
    A.flush()
    del A
    return Path(path)


def peak_rss() -> int:
    """Peak resident memory of this process, bytes: VmHWM (reset by exec; ru_maxrss
    is not -- a child started by a parent holding a large mapping inherits its peak)."""
    try:
        for line in open("/proc/self/status"):
            if line.startswith("VmHWM:"):
                return int(line.split()[1]) * 1024
    except OSError:
        pass
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024


def _surfaces():
    from geomkit import samples
    return samples.load(CASE)


def one(path, chunk):
    """Stream one scan (no output) and print JSON: points, seconds, peak RSS."""
    from geomkit.jobs.stream import stream_deviation

    t0 = time.perf_counter()
    last = [0]

    def progress(done, _total):  # partial numbers on stderr, every ~1e6 points
        if done - last[0] >= 1_000_000:
            last[0] = done
            rss = peak_rss() / 2**20
            print(f"  {done:,d} points in {time.perf_counter() - t0:.0f} s, peak RSS so "
                  f"far {rss:.0f} MiB", file=sys.stderr, flush=True)

    st = stream_deviation(_surfaces(), path, None, tolerance=(-0.04, 0.04),
                          chunk_size=chunk, progress=progress)
    sec = time.perf_counter() - t0
    peak = peak_rss()
    print(json.dumps({"points": st["points"], "seconds": sec,
                      "points_per_second": st["points"] / sec, "peak_rss_bytes": peak,
                      "rms": st["rms"], "pct_within": st["pct_within"]}))


def memory(ns, folder, chunk, keep=False):
    rows = []
    for n in ns:
        p = Path(folder) / f"geomkit-scale-{int(n)}.npy"
        if not p.exists():
            make_scan(p, int(n))
        env = dict(os.environ)
        r = subprocess.run([sys.executable, "-m", "geomkit.bench.scale", "one", str(p),
                            "--chunk", str(chunk)], stdout=subprocess.PIPE, text=True,
                           env=env, check=True)
        row = json.loads(r.stdout.strip().splitlines()[-1])
        rows.append(row)
        print(f"{row['points']:>12,d} points: {row['seconds']:9.1f} s, "
              f"{row['points_per_second']:9.0f} points/s, peak RSS "
              f"{row['peak_rss_bytes'] / 2**20:8.1f} MiB", flush=True)
        if not keep:
            p.unlink()
    return rows


def throughput(n, chunk, folder):
    from geomkit.jobs.distributed import make_client
    from geomkit.jobs.stream import stream_deviation

    p = make_scan(Path(folder) / f"geomkit-scale-tp-{n}.npy", n)
    surfs = _surfaces()
    outs = {}

    def run(label, client=None):
        import io

        import pyarrow.parquet as pq
        buf = io.BytesIO()
        # warm-up: each process's numba cache loaded, projector built
        stream_deviation(surfs, p, None, chunk_size=chunk, client=client)
        t0 = time.perf_counter()
        st = stream_deviation(surfs, p, buf, fmt="parquet", chunk_size=chunk,
                              client=client)
        sec = time.perf_counter() - t0
        t = pq.read_table(io.BytesIO(buf.getvalue()))
        outs[label] = {c: t.column(c).to_numpy(zero_copy_only=False)
                       for c in ("index", "deviation", "foot_x", "foot_y", "foot_z")}
        print(f"{label:22s} {n / sec:10.0f} points/s ({sec:.2f} s, rms {st['rms']:.6g})",
              flush=True)
        return n / sec

    rates = {"single process": run("single process")}
    for w in (1, 2):
        client, cluster = make_client(w)
        try:
            rates[f"dask {w} worker(s)"] = run(f"dask {w} worker(s)", client)
        finally:
            client.close()
            cluster.close()
    ref = outs["single process"]
    for k, o in outs.items():
        same = all(np.array_equal(o[c], ref[c], equal_nan=True) for c in ref)
        print(f"{k:22s} ratio to single {rates[k] / rates['single process']:.2f}, "
              f"bit-for-bit equal: {same}")
    p.unlink()
    return rates


def main(argv=None):
    ap = argparse.ArgumentParser(prog="python -m geomkit.bench.scale")
    sub = ap.add_subparsers(dest="cmd", required=True)
    a = sub.add_parser("throughput")
    a.add_argument("--n", type=float, default=2e5)
    a.add_argument("--chunk", type=int, default=1 << 14)
    a.add_argument("--dir", default="/tmp")
    a = sub.add_parser("memory")
    a.add_argument("--n", type=float, nargs="+", default=[1e6, 1e7])
    a.add_argument("--chunk", type=int, default=1 << 16)
    a.add_argument("--dir", default="/tmp")
    a.add_argument("--keep", action="store_true")
    a = sub.add_parser("one")
    a.add_argument("file")
    a.add_argument("--chunk", type=int, default=1 << 16)
    args = ap.parse_args(argv)
    if args.cmd == "one":
        one(args.file, args.chunk)
    elif args.cmd == "memory":
        memory([int(x) for x in args.n], args.dir, args.chunk, args.keep)
    else:
        throughput(int(args.n), args.chunk, args.dir)


if __name__ == "__main__":
    main()
