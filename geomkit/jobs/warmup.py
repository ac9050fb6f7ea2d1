"""Compile kernel groups in a background process.

On a fresh install the numba kernels are compiled on first use (then cached on disk,
``cache=True``).  :func:`start_background` compiles the kernels of the given groups in
a separate Python process by calling the public API on tiny built-in inputs, so a
second core compiles while the main process works; when the main process reaches a
kernel that the helper has finished, numba loads it from the cache instead of
compiling it (cache files are written atomically).

Groups:

* ``"projection"``: :func:`geomkit.project_points` / :func:`geomkit.deviation`
  (tessellation, voxel grid, Newton feet);
* ``"section"``: :func:`geomkit.plane_section`;
* ``"distance"``: :func:`geomkit.surface_distance`.

Start the groups the main process needs *last* (it compiles what it needs first
itself); a kernel both processes compile at the same time is compiled twice.
"""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

GROUPS = ("projection", "section", "distance")


def _compile(groups) -> None:
    import numpy as np

    from geomkit import samples
    from geomkit.jobs.deviation import deviation
    from geomkit.query.distance import surface_distance
    from geomkit.section.plane import plane_section

    surf = samples.load("freeform_1")[0]
    for g in groups:
        if g == "projection":
            (u0, u1), (v0, v1) = surf.domain
            uv = np.array([[u0 + 0.3 * (u1 - u0), v0 + 0.6 * (v1 - v0)],
                           [u0 + 0.7 * (u1 - u0), v0 + 0.2 * (v1 - v0)]])
            N = surf.normals(uv)
            deviation(surf, surf.evaluate(uv) + N, N, probe_radius=1.0)
        elif g == "section":
            lo, hi = surf.bounds
            x = 0.5 * (lo[0] + hi[0])
            plane_section(surf, np.array([1.0, 0.0, 0.0, -x]), 1e-4)
        elif g == "distance":
            a, b = samples.load("sphere_pair")
            surface_distance(a, b, tol=1e-6)


def kernels_status() -> str:
    """Whether the kernels run ahead-of-time compiled code or compile on first use
    (:mod:`geomkit._kernels.numba_ext.aot`), and if not, why."""
    from geomkit._kernels.numba_ext import aot as _aot

    return _aot.status


def needed() -> bool:
    """False when the ahead-of-time kernels are in use: nothing is left to compile in
    the background."""
    from geomkit._kernels.numba_ext import aot as _aot

    return not _aot.active()


def start_background(groups) -> subprocess.Popen:
    """Compile the kernels of ``groups`` (names from :data:`GROUPS`) in a separate
    Python process; returns its ``Popen`` (``wait()`` to let it finish).

    A fresh interpreter (``python -c``), not a multiprocessing child: a spawned child
    would re-import the caller's ``__main__`` (a user script without a main guard would
    run again).  Its output is discarded; if it fails, the main process simply compiles
    what it needs itself.
    """
    groups = tuple(groups)
    bad = [g for g in groups if g not in GROUPS]
    if bad:
        raise ValueError(f"unknown kernel group(s) {bad}; expected some of {GROUPS}")
    root = str(Path(__file__).resolve().parents[1])  # the geomkit this process runs
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join([root] + ([env["PYTHONPATH"]]
                                                  if env.get("PYTHONPATH") else []))
    code = f"from geomkit.jobs.warmup import _compile; _compile({list(groups)!r})"
    return subprocess.Popen([sys.executable, "-c", code], env=env,
                            stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL,
                            stderr=subprocess.DEVNULL)
