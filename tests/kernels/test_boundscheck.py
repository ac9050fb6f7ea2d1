"""The search and projection kernels run once with numba's bounds checking.

The kernels read through borrowed views (:mod:`geomkit._kernels.numba_ext.borrow`) that keep
their shapes, so ``NUMBA_BOUNDSCHECK=1`` turns an index past a buffer's end into an
``IndexError`` instead of a read of memory the kernel does not own.  This test runs
``tests/query/test_voxel_brute.py`` (point and triangle searches over awkward grids,
``min_distance``, the projection's candidate search) in a child process with the
JIT kernels (``GEOMKIT_NO_AOT=1``: the ahead-of-time module is built without the
checks) compiled with bounds checks into a cache of its own, so the checked code
never meets the suite's cache.
"""

from __future__ import annotations

import os
import subprocess
import sys

from helpers.paths import ROOT, TESTS

CHILD = TESTS / "query" / "test_voxel_brute.py"
TIMEOUT = 900


def test_search_kernels_with_bounds_checking(tmp_path):
    assert CHILD.is_file(), f"{CHILD} moved: update CHILD"
    env = dict(os.environ, NUMBA_BOUNDSCHECK="1", GEOMKIT_NO_AOT="1",
               NUMBA_CACHE_DIR=str(tmp_path / "numba-cache"))
    r = subprocess.run([sys.executable, "-m", "pytest", "-q", "-x", "-p", "no:cacheprovider",
                        str(CHILD)], cwd=ROOT, env=env,
                       capture_output=True, text=True, timeout=TIMEOUT)
    tail = "\n".join((r.stdout + r.stderr).splitlines()[-30:])
    assert r.returncode == 0, f"with NUMBA_BOUNDSCHECK=1:\n{tail}"
    assert " passed" in r.stdout and "error" not in r.stdout.splitlines()[-1], tail
