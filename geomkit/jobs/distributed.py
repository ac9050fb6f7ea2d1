"""Deviation chunks as Dask tasks (``dask.distributed``).

* The nominal surfaces are scattered to every worker once (``Client.scatter(...,
  broadcast=True)``); each worker process builds one :class:`~geomkit.Projector` from
  them on its first task and keeps it (a per-process cache keyed by the scattered
  data's key), so the tessellation and voxel grid are built once per worker.
* Chunks of points are tasks (``geomkit-dev-<run>-<chunk index>``), submitted in a
  bounded window (:data:`WINDOW` per worker) so memory stays bounded on the client and
  the workers; results are handed back in chunk order (a reorder buffer keyed by the
  chunk index), so every row is written exactly once and in file order, even when a
  worker dies and the scheduler reruns its tasks (``retries`` for task errors).
* Each task runs :func:`geomkit.jobs.deviation.deviation_chunk`: the values equal the
  single-process run's bit for bit on the same machine type.

Progress: the Dask dashboard (``client.dashboard_link``) shows the tasks; the CLI
also draws its own bar when stderr is a terminal.
"""

from __future__ import annotations

import hashlib
import pickle
import uuid

from geomkit.errors import MissingDependencyError
from geomkit.jobs.deviation import deviation_chunk
from geomkit.query.projection_part import make_projector

__all__ = ["run_chunks", "make_client", "WINDOW", "RETRIES"]

WINDOW = 4
"""Tasks in flight per worker."""
RETRIES = 3
"""Retries of a task that raised (a killed worker's tasks are rerun by the scheduler
without counting against this)."""

_PROJECTORS: dict = {}


def _distributed():
    try:
        import distributed
    except ImportError:
        raise MissingDependencyError("--workers / --scheduler need dask.distributed: "
                                     "pip install geomkit[scale]") from None
    return distributed


def make_client(workers: int | None = None, scheduler: str | None = None):
    """A Client on an existing scheduler, or on a new LocalCluster of ``workers``
    single-threaded worker processes.  Returns ``(client, cluster or None)``."""
    distributed = _distributed()
    if scheduler:
        return distributed.Client(scheduler), None
    cluster = distributed.LocalCluster(n_workers=int(workers), threads_per_worker=1,
                                       processes=True, dashboard_address=None)
    return distributed.Client(cluster), cluster


def _task(surfaces, key, P, N, T, probe_radius, max_distance, offset):
    pr = _PROJECTORS.get(key)
    if pr is None:
        _PROJECTORS.clear()  # one nominal at a time per worker process
        pr = _PROJECTORS[key] = make_projector(surfaces)
    return deviation_chunk(pr, P, N, T, probe_radius, max_distance, offset)


def run_chunks(client, surfaces, chunks, T, probe_radius, max_distance):
    """Yield the deviation columns of each chunk of ``chunks`` (an iterator of
    ``(points, normals)``), in order, computed as tasks on ``client``'s cluster."""
    distributed = _distributed()
    run = uuid.uuid4().hex[:12]
    # a random key per run (hash=False): the same nominal scattered again for the next
    # part of a batch under its content key could be released by the previous run's
    # clean-up while this one uses it ("lost dependencies"); the workers' projector
    # cache is keyed by the content instead
    [sfut] = client.scatter([list(surfaces)], broadcast=True, hash=False)
    content = hashlib.sha1(pickle.dumps(list(surfaces))).hexdigest()
    nworkers = max(1, len(client.scheduler_info().get("workers", {})))
    window = WINDOW * nworkers
    pending = distributed.as_completed()
    done, index, next_out, offset, k = {}, {}, 0, 0, 0
    it = iter(chunks)
    exhausted = False
    try:
        while True:
            while not exhausted and pending.count() < window:
                try:
                    P, N = next(it)
                except StopIteration:
                    exhausted = True
                    break
                f = client.submit(_task, sfut, content, P, N, T, probe_radius,
                                  max_distance, offset, key=f"geomkit-dev-{run}-{k}",
                                  retries=RETRIES, pure=False)
                index[f.key] = k
                pending.add(f)
                offset += P.shape[0]
                k += 1
            if pending.is_empty():
                break
            f = next(pending)
            done[index.pop(f.key)] = f.result()
            f.release()
            while next_out in done:
                yield done.pop(next_out)
                next_out += 1
    finally:
        pending.clear()
