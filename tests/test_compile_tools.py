"""The compile-time tools: the plain-argument dispatcher and the compile log reader."""

import numba
import numpy as np

from geomkit._kernels._numba import _decorator
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
