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
* ``parallel=True`` / ``prange`` only on outer batch loops (:data:`pjit`); leaf
  kernels are serial (:data:`jit`).
"""

from __future__ import annotations

import os

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
