"""numba policy for every geomkit kernel, set in one place.

* ``cache=True``: compiled code is stored on disk next to the sources, so only the
  first import on a machine pays the compile time.
* ``nogil=True``: kernels release the GIL and can run in threads.
* fastmath allows only contraction (fused multiply-add) and signed-zero freedom: no
  ``nnan``/``ninf`` (NaN checks must keep working) and no reassociation (results stay
  reproducible and as accurate as the reference algorithms).
* ``error_model="numpy"``: a float division by zero gives inf/nan instead of raising
  inside the kernel (no hidden branch per division); kernels guard their own
  degenerate cases and the public functions check results.
* batch kernels are serial :data:`jit` workers over an index range ``[i0, i1)``,
  run in parallel by :func:`prun` on Python threads (they release the GIL).  Numba's
  ``parallel=True`` / ``prange`` (:data:`pjit`) compiles the whole call tree of the
  loop body three more times (parfor kernel, gufunc wrapper, caller), which cost more
  than half of the first-run compile time of the projection kernels.
"""

from __future__ import annotations

import os
import threading
from concurrent.futures import ThreadPoolExecutor

import numba

# The OpenMP layer parks idle threads deeply: every parallel call then pays ~7 ms of
# wake-up, which dominates the many small kernel calls of adaptive refinement
# (measured: tessellating cylinder_quarter took 68 ms with "omp", 4 ms with
# "workqueue").  workqueue does not support launching parallel kernels from several
# Python threads at once; set NUMBA_THREADING_LAYER (e.g. "tbb" or "omp") to choose.
if "NUMBA_THREADING_LAYER" not in os.environ:
    numba.config.THREADING_LAYER = "workqueue"

FASTMATH = {"contract", "nsz"}

jit = numba.njit(cache=True, nogil=True, fastmath=FASTMATH, error_model="numpy")
"""Decorator for serial kernels."""

jit_inline = numba.njit(cache=True, nogil=True, fastmath=FASTMATH, error_model="numpy",
                        inline="always")
"""Decorator for tiny helpers called in hot loops with array arguments: inlined at the
numba IR level, which removes the per-call reference counting of array arguments
(measured: a heap push/pop with array arguments cost ~50 ns as a call)."""


def pjit(func):
    """Decorator for batch kernels parallel over their outer ``prange`` loop."""
    return numba.njit(cache=True, nogil=True, fastmath=FASTMATH, parallel=True,
                      error_model="numpy")(func)


prange = numba.prange

_pool = None
_pool_lock = threading.Lock()
TASKS_PER_THREAD = 4
"""Tasks per thread in :func:`prun` (dynamic balancing of uneven work)."""


def _executor():
    global _pool
    with _pool_lock:
        if _pool is None:
            _pool = ThreadPoolExecutor(max_workers=numba.config.NUMBA_NUM_THREADS,
                                       thread_name_prefix="geomkit")
        return _pool


def prun(worker, n, chunk, *args):
    """Run ``worker(i0, i1, *args)`` over ``[0, n)`` in parallel.

    The range is cut at multiples of ``chunk`` into up to :data:`TASKS_PER_THREAD`
    tasks per thread, taken in turn by ``numba.get_num_threads()`` threads (the
    calling one included); a range of at most one chunk (or a single thread) runs in
    the calling thread.  ``worker`` is a serial (``nogil``) kernel writing only the
    outputs of its own indices, so the result does not depend on the cut.
    """
    n = int(n)
    if n <= 0:
        return
    nch = (n + chunk - 1) // chunk
    nt = min(numba.get_num_threads(), nch)
    if nt <= 1:
        worker(0, n, *args)
        return
    ntask = min(nch, TASKS_PER_THREAD * nt)
    bounds = [min(n, (nch * k // ntask) * chunk) for k in range(ntask + 1)]
    tasks = iter(range(ntask))
    lock = threading.Lock()

    def run():
        while True:
            with lock:
                k = next(tasks, None)
            if k is None:
                return
            worker(bounds[k], bounds[k + 1], *args)

    futures = [_executor().submit(run) for _ in range(nt - 1)]
    try:
        run()  # the calling thread takes tasks too
    finally:
        for f in futures:
            f.result()
