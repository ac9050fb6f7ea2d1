"""Streamed CMM deviation: a scan of any size, chunk by chunk, results written as they
come, statistics computed incrementally (:mod:`geomkit.jobs.stats`).

The per-point values are those of :func:`geomkit.jobs.deviation.deviation` bit for bit:
the same :class:`~geomkit.Projector` chunk projection and the same probe compensation
(:func:`geomkit.jobs.deviation._compensate`).  Memory is bounded by the chunk size (the
projector, one chunk of points and results, and the writer's buffer).

Alignment (``align=True``) is fitted on a bounded, deterministic subsample of the scan
(every k-th point, at most :data:`ALIGN_SAMPLE` points; one extra read pass) and the
transform is then applied to every point; the summary states the sample size.
"""

from __future__ import annotations

import collections
import math
import time

import numpy as np

from geomkit.jobs.deviation import (COLUMNS, _as_tolerance, _check_settings,
                                    align_rigid, deviation_chunk)
from geomkit.jobs.distributed import run_chunks
from geomkit.jobs.stats import DeviationStats
from geomkit.errors import InvalidInputError, MissingDependencyError
from geomkit.query.projection_part import cached_projector
from geomkit.query.results import STATUS_NAMES
from geomkit.exchange.scans import DEFAULT_CHUNK, iter_scan, iter_scan_attrs

__all__ = ["stream_deviation", "COLUMNS", "ALIGN_SAMPLE"]

ALIGN_SAMPLE = 200_000
"""Points at most in the alignment subsample of a streamed scan."""
# ------------------------------------------------------------------ writers
class CSVWriter:
    """Per-point CSV rows appended chunk by chunk (through pyarrow's C++ CSV writer
    when installed, else Python; both round-trip every float exactly).  The header is
    :data:`COLUMNS` and the scan's attributes after them (the first chunk's)."""

    def __init__(self, fh):
        self.fh = fh
        try:
            import pyarrow.csv  # noqa: F401
            self.arrow = True
        except ImportError:
            self.arrow = False
        self.header = False

    def write(self, cols):
        if not self.header:
            self.fh.write((",".join(cols) + "\n").encode())
            self.header = True
        if self.arrow:
            import pyarrow.csv as pc

            t = _arrow_table(cols)
            pc.write_csv(t, self.fh, pc.WriteOptions(include_header=False,
                                                     quoting_style="none"))
            return
        names = [STATUS_NAMES.get(int(s), str(int(s))) for s in cols["status"]]
        f = (lambda x: repr(x) if math.isfinite(x) else "")
        fl = {c: cols[c].tolist() for c in COLUMNS if c not in ("index", "surface",
                                                                 "status", "edge")}
        extra = [c for c in cols if c not in COLUMNS]
        lines = []
        for i in range(cols["index"].size):
            row = [str(int(cols["index"][i]))]
            row += [f(fl[c][i]) for c in COLUMNS[1:12]]
            row.append(str(int(cols["surface"][i])))
            row += [f(fl[c][i]) for c in COLUMNS[13:18]]
            row += [names[i], str(int(cols["edge"][i]))]
            row += [_text(cols[c][i]) for c in extra]
            lines.append(",".join(row))
        self.fh.write(("\n".join(lines) + "\n").encode())

    def close(self):
        pass


def _text(x) -> str:
    x = x.item()
    return repr(x) if isinstance(x, float) else str(x)


def _arrow_table(cols):
    import pyarrow as pa

    arrays = []
    for c in cols:
        a = cols[c]
        if c == "status":
            arrays.append(pa.array(_STATUS_LUT[a.astype(np.int64)]))
        elif a.dtype.kind == "f":
            arrays.append(pa.array(a, mask=~np.isfinite(a)))
        else:
            arrays.append(pa.array(a))
    return pa.table(arrays, names=list(cols))


_STATUS_LUT = np.array([STATUS_NAMES.get(i, str(i)) for i in range(128)], dtype=object)


class ParquetWriter:
    """Per-point rows as Parquet row groups (one per chunk), via pyarrow."""

    def __init__(self, fh):
        pq = pyarrow_parquet()
        self.fh = fh
        self.pq = pq
        self.w = None

    def write(self, cols):
        t = _arrow_table(cols)
        if self.w is None:
            self.w = self.pq.ParquetWriter(self.fh, t.schema)
        self.w.write_table(t)

    def close(self):
        if self.w is not None:
            self.w.close()


def pyarrow_parquet():
    try:
        import pyarrow.parquet as pq
    except ImportError:
        raise MissingDependencyError("--format parquet needs pyarrow: pip install "
                                     "geomkit[scale]") from None
    return pq


WRITERS = {"csv": CSVWriter, "parquet": ParquetWriter}


# ------------------------------------------------------------------ the job
def _align_sample(path, chunk_size):
    """Rows 0, k, 2k, ... of the scan with k (a power of 2) doubled whenever the
    sample would exceed :data:`ALIGN_SAMPLE` points: ``(points, normals, k)``."""
    k, keep_p, keep_n, i0 = 1, None, None, 0
    for P, N in iter_scan(path, chunk_size):
        sel = (np.arange(i0, i0 + P.shape[0]) % k) == 0
        i0 += P.shape[0]
        keep_p = P[sel] if keep_p is None else np.concatenate([keep_p, P[sel]])
        if N is not None:
            keep_n = N[sel] if keep_n is None else np.concatenate([keep_n, N[sel]])
        while keep_p.shape[0] > ALIGN_SAMPLE:  # multiples of k -> multiples of 2k
            k *= 2
            keep_p = keep_p[::2]
            keep_n = None if keep_n is None else keep_n[::2]
    return keep_p, keep_n, k


def stream_deviation(surfaces, scan, out=None, *, fmt: str = "csv",
                     probe_radius: float = 0.0, align: bool = False,
                     max_distance: float | None = None, tolerance=None,
                     chunk_size: int = DEFAULT_CHUNK, client=None, progress=None,
                     require_valid: bool = True) -> dict:
    """Deviation of a scan file streamed chunk by chunk.

    Parameters
    ----------
    surfaces : Surface or list of Surface
    scan : str or Path
        A scan file (:func:`geomkit.exchange.scans.iter_scan` formats).
    out : binary file object, optional
        Per-point rows are written here as they come (``fmt`` "csv" or "parquet").
    probe_radius, align, max_distance, tolerance
        As :func:`geomkit.jobs.deviation.deviation` (alignment on a subsample, see the
        module doc).
    chunk_size : int
        Points per chunk (and per Dask task).
    client : dask.distributed.Client, optional
        Run the chunks as tasks on this cluster (:mod:`geomkit.jobs.distributed`).
    progress : callable(done_points, total or None), optional
    require_valid : bool
        Raise when no point has a deviation (else NaN statistics).

    Returns
    -------
    dict
        The statistics (:class:`~geomkit.jobs.stats.DeviationStats`), settings,
        ``chunks``, ``seconds``, ``alignment`` and ``attributes`` (the scan's per-point
        attributes written after the deviation columns: intensity, colours).
    """
    t0 = time.perf_counter()
    probe_radius, max_distance = _check_settings(probe_radius, max_distance)
    tol = _as_tolerance(tolerance)
    if fmt not in WRITERS:
        raise InvalidInputError(f"expected one of {', '.join(WRITERS)}, got {fmt!r}",
                                "format")
    projector = cached_projector(surfaces, None)
    T, align_info = None, None
    if align:
        Ps, Ns, k = _align_sample(scan, chunk_size)
        md = None if max_distance is None else max_distance + probe_radius
        align_info = align_rigid(projector.surfaces, Ps, Ns, probe_radius, md)
        align_info.update(sample_points=int(Ps.shape[0]), sample_stride=int(k))
        T = align_info["transform"]
    writer = WRITERS[fmt](out) if out is not None else None
    stats = DeviationStats(tol)
    attrs = collections.deque()  # each chunk's scan attributes, in chunk order
    chunks = _keep_attrs(iter_scan_attrs(scan, chunk_size), attrs)
    if client is not None:

        results = run_chunks(client, projector.surfaces, chunks, T, probe_radius,
                             max_distance)
    else:
        results = _local(projector, chunks, T, probe_radius, max_distance)
    nchunks = 0
    names = []
    for cols in results:  # results come in chunk order
        stats.update(cols["deviation"], cols["status"], cols["edge"].astype(bool))
        extra = attrs.popleft()
        names = list(extra)
        if writer is not None:
            writer.write({**cols, **extra})
        nchunks += 1
        if progress is not None:
            progress(stats.n, None)
    if writer is not None:
        writer.close()
    st = stats.result(require_valid=require_valid)
    st.update(probe_radius=probe_radius, max_distance=max_distance,
              tolerance=list(tol) if tol else None, chunks=nchunks, chunk_size=chunk_size,
              streamed=True, workers=_nworkers(client), attributes=names,
              # faces with no candidate (failed to mesh); a cluster's workers build
              # their own projectors, named in their warnings
              faces_failed={int(k): v for k, v in projector.face_errors.items()})
    st["alignment"] = None
    if align_info is not None:
        st["alignment"] = {"transform": np.asarray(T).tolist(),
                           **{k: align_info[k] for k in
                              ("rms_before", "rms_after", "iterations", "rank",
                               "converged", "sample_points", "sample_stride")}}
    st["seconds"] = time.perf_counter() - t0
    return st


def _keep_attrs(chunks, queue):
    """``(points, normals)`` of each chunk, its attributes appended to ``queue``."""
    for P, N, A in chunks:
        queue.append(A)
        yield P, N


def _nworkers(client):
    if client is None:
        return 0
    return len(client.scheduler_info().get("workers", {}))


def _local(projector, chunks, T, probe_radius, max_distance):
    offset = 0
    for P, N in chunks:
        yield deviation_chunk(projector, P, N, T, probe_radius, max_distance, offset)
        offset += P.shape[0]
