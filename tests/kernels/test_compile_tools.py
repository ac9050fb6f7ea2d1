"""The compile-time tools: the plain-argument dispatcher and the compile log reader."""

import numba
import numpy as np

from geomkit._kernels.numba_ext.policy import _decorator
from geomkit.bench.compile_groups import read_log


def test_plain_dispatcher_compiles_callee_once():
    # oracle: numba's default dispatcher compiles the callee for Literal[int](0) and
    # for int64; the plain one only for int64, with the same results
    def add(a, k):
        return a[k] + k

    def caller(a, k):
        return add(a, 0) + add(a, k)

    a = np.arange(4.0)
    plain = _decorator(cache=False)(add)
    default = numba.njit(add)
    plain_caller = numba.njit(lambda a, k: plain(a, 0) + plain(a, k))
    default_caller = numba.njit(lambda a, k: default(a, 0) + default(a, k))
    assert plain_caller(a, 2) == default_caller(a, 2) == caller(a, 2) == 4.0 + 0.0
    assert len(default.signatures) == 2  # the duplicate the plain dispatcher avoids
    assert len(plain.signatures) == 1
    assert str(plain.signatures[0][1]) == "int64"


def test_read_log_finds_kernels_compiled_in_two_processes(tmp_path, capsys):
    log = tmp_path / "log"
    log.write_text("1\tm.f\t10.0\t12.0\t1.5\n"
                   "2\tm.f\t10.5\t12.5\t1.0\n"
                   "2\tm.g\t13.0\t14.0\t0.5\n")
    s = read_log(log)
    assert s["processes"] == 2 and s["duplicates"] == 1
    assert abs(s["duplicate_cpu"] - 1.0) < 1e-12 and abs(s["cpu"] - 3.0) < 1e-12
    assert "m.f" in capsys.readouterr().out


def test_cache_is_invalidated_by_a_change_in_another_kernel_file(tmp_path):
    """numba validates a cached kernel against its own file only, but the compiled code
    contains its callees from other files.  geomkit's stamp covers every kernel file:
    after a callee's file changes, the cached caller must run the new callee (it ran
    the old one before the fix: a stale answer after an edit or a ``git pull``)."""
    import shutil
    import subprocess
    import sys
    from pathlib import Path

    import geomkit._kernels as K

    pkg = tmp_path / "kcopy"
    shutil.copytree(Path(K.__file__).parent, pkg,
                    ignore=shutil.ignore_patterns("__pycache__"))
    (pkg / "probe_callee.py").write_text(
        "from .numba_ext.policy import jit\n\n@jit\ndef value():\n    return 1\n")
    (pkg / "probe_caller.py").write_text(
        "from .numba_ext.policy import jit\nfrom .probe_callee import value\n\n"
        "@jit\ndef twice():\n    return 2 * value()\n")
    env = {**__import__("os").environ, "PYTHONPATH": str(tmp_path),
           "NUMBA_CACHE_DIR": str(tmp_path / "cache")}
    run = [sys.executable, "-c", "from kcopy.probe_caller import twice; print(twice())"]

    def out():
        return subprocess.run(run, env=env, capture_output=True, text=True,
                               check=True).stdout.strip()

    assert out() == "2"
    assert out() == "2"  # from the cache
    assert any((tmp_path / "cache").rglob("*probe_caller*.nbi"))
    (pkg / "probe_callee.py").write_text(
        "from .numba_ext.policy import jit\n\n@jit\ndef value():\n    return 5\n")
    assert out() == "10"
