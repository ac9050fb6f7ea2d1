"""Ahead-of-time compiled kernels (geomkit/_kernels/numba_ext/aot.py and aot_build.py).

The export list must match the kernels (names, arity, and the argument types the demo
and the real parts call them with); the router must hand the compiled code only arguments of exactly
the exported types (oracle: ``numba.typeof``); and, when the module is built, the
compiled code must give the JIT's bits and release the GIL."""

from __future__ import annotations

import inspect
import json
import threading
from importlib import import_module

import numba
import numpy as np
import pytest

import geomkit
from geomkit import samples
from geomkit._kernels.numba_ext import aot as _aot
from geomkit._kernels.numba_ext.policy import _kernels_stamp

EXPORTS = json.loads(_aot.EXPORTS.read_text())

needs_aot = pytest.mark.skipif(
    not _aot.active(), reason=f"no ahead-of-time kernels: {_aot.status} "
                              f"(build: python geomkit/_kernels/numba_ext/aot_build.py build)")


def _kernel(mod, qual):
    obj = import_module(mod)
    for part in qual.split("."):
        obj = getattr(obj, part)
    return obj


def test_export_list_names_existing_kernels_with_their_arity():
    assert EXPORTS, "empty export list"
    for mod, qual, sig in EXPORTS:
        k = _kernel(mod, qual)
        disp = getattr(k, "dispatcher", k)
        assert isinstance(disp, numba.core.registry.CPUDispatcher), (mod, qual)
        params = inspect.signature(disp.py_func).parameters
        assert len(params) == len(sig), f"{mod}.{qual}: {len(params)} parameters, " \
                                         f"{len(sig)} exported types: run record"
        for s in sig:
            assert str(_aot.parse_type(s)) == s


def test_export_list_holds_the_demo_calls():
    """Regenerate the demo's calls (the demo run with call recording, in a child
    process) and find each in the list, in the same order: fails when a kernel's Python
    call changed types or a new kernel is called from Python (``python
    geomkit/_kernels/numba_ext/aot_build.py record`` rewrites the list: the demo's calls,
    then the real parts', checked by the test below)."""
    from geomkit._kernels.numba_ext.aot_build import record

    fresh = record(out=None, grid=8, parts=False)
    missing = [row for row in fresh if row not in EXPORTS]
    assert fresh and not missing, f"demo calls not exported: {missing[:3]}: " \
                                  "run `python geomkit/_kernels/numba_ext/aot_build.py record`"
    at = [EXPORTS.index(row) for row in fresh]
    assert at == sorted(at)


_PARTS_RUN = """
import json
from numba.core import dispatcher
from geomkit.bench.parts import exercise
out = set()
compile_for_args = dispatcher.Dispatcher._compile_for_args
def spy(self, *args, **kws):  # a call from Python that no compiled code serves
    out.add(self.py_func.__module__ + "." + self.py_func.__qualname__)
    return compile_for_args(self, *args, **kws)
dispatcher.Dispatcher._compile_for_args = spy
assert exercise({parts!r}) == {n}
print(json.dumps(sorted(out)))
"""


@needs_aot
def test_real_parts_run_only_ahead_of_time_code():
    """A real part's first read, mesh, section and projection on a fresh install
    compile nothing: in a new process, two parts of different routes (a one-face
    B-spline with a fitted quintic trim; a NIST part of planes, cylinders, cones and
    tori) call from Python only exported kernels with their exported types (no call
    from Python goes to the JIT)."""
    import subprocess
    import sys

    parts = ["inventor2015_cylinder_block_face6.stp", "nist_ctc_01_ap203.stp"]
    run = subprocess.run([sys.executable, "-c", _PARTS_RUN.format(parts=parts, n=2)],
                         capture_output=True, text=True, timeout=600)
    assert run.returncode == 0, run.stderr[-2000:]
    assert json.loads(run.stdout.strip().splitlines()[-1]) == []


def _arrays():
    a = np.arange(24.0).reshape(4, 6)
    ro = a.copy()
    ro.flags.writeable = False
    buf = np.zeros(8 * 7 + 1, dtype=np.uint8)
    unaligned = buf[1:].view(np.float64)
    return [a, a.T, a[:, ::2], a[0], a[:, 0], ro, ro[1:], np.asfortranarray(a),
            a.astype(np.int64), a.astype(np.float32), a.astype(np.int8), a[None],
            np.zeros(0), np.zeros((0, 3)), unaligned, np.int64(3), np.float64(2.5),
            3, 2.5, True, np.bool_(False), None, 2**70, (1, 2), (1.0, 2), (a, a[0]),
            np.int32(4), "x", [1.0],
            # equal to float64 but not numpy's canonical dtype object (seen in the demo)
            np.zeros(3, np.dtype("f8").newbyteorder("S").newbyteorder("S")),
            np.zeros(3, np.dtype("f8", metadata={"a": 1})),
            np.zeros(3, np.dtype("f8").newbyteorder("S"))]


def test_router_type_check_agrees_with_numba_typeof():
    """The check that keeps a wrong argument away from the compiled code: exactly
    ``numba.typeof`` (layout, dtype, ndim, writeability, alignment, int range)."""
    vals = _arrays()
    kinds = []
    for v in vals:
        try:
            kinds.append(_aot.parse_type(str(numba.typeof(v))))
        except (ValueError, Exception):
            continue
    assert len(kinds) >= 15
    for t in kinds:
        check = _aot.signature_checker([t])
        for v in vals:
            try:
                tv = numba.typeof(v)
            except Exception:
                tv = None
            # stricter on one point: numba types an unaligned array as aligned; the
            # router sends it to the JIT
            want = tv == t and not (isinstance(v, np.ndarray) and not v.flags.aligned)
            assert check((v,)) == want, (t, tv, v if not isinstance(v, np.ndarray)
                                         else (v.dtype, v.shape, v.flags))
    assert not _aot.signature_checker(kinds[:2])((vals[0],))  # arity


def test_router_sends_other_types_to_the_jit():
    calls = []

    class Disp:
        py_func = test_router_sends_other_types_to_the_jit

        def __call__(self, *a):
            calls.append("jit")

    t = _aot.parse_type("array(float64, 2d, C)")
    r = _aot.Router(Disp(), [(_aot.signature_checker([t]),
                              lambda *a: calls.append("aot"))])
    try:
        a = np.zeros((3, 3))
        r(a)
        r(a.T)          # F layout: the compiled code would misread it
        r(a[:, ::2])    # A layout
        r(a.astype(np.int64))
        r(a, 1)
        with _aot.use_aot(False):
            r(a)
        r(a)
    finally:
        _aot.routers.remove(r)
    assert calls == ["aot", "jit", "jit", "jit", "jit", "jit", "aot"]
    assert r.aot_calls == 2


def test_manifest_mismatch_falls_back_to_the_jit():
    stamp = _kernels_stamp().hex()
    good = {"stamp": stamp, "numba": numba.__version__, "cpu": list(_aot.host_cpu())}
    assert _aot.mismatch(good, stamp) is None
    assert "sources changed" in _aot.mismatch(dict(good, stamp="0" * 64), stamp)
    assert "numba" in _aot.mismatch(dict(good, numba="0.1"), stamp)
    assert "CPU" in _aot.mismatch(dict(good, cpu=["other", "+x"]), stamp)


def _jobs():
    """The demo's kernels on every bundled case: results as a flat list of arrays."""
    out = []
    rng = np.random.default_rng(5)
    for name in ("freeform_1", "sphere", "torus", "plate_with_hole", "saddle"):
        for s in samples.load(name):
            lo, hi = s.bounds
            P = lo + (hi - lo) * rng.random((300, 3))
            r = geomkit.project_points(s, P)
            out += [r.point, r.uv, r.distance, r.lower_bound, r.status]
            m = geomkit.tessellate(s, 1e-2)
            out += [np.asarray(m.vertices), np.asarray(m.faces)]
            x = 0.5 * (lo[0] + hi[0])
            sec = geomkit.plane_section(s, np.array([1.0, 0.0, 0.0, -x]), 1e-4)
            out += [np.asarray(c) for c in sec.curves]
    a, b = samples.load("sphere_pair")
    d = geomkit.surface_distance(a, b, tol=1e-9)
    out += [np.array([d.distance, d.lower, d.upper]), d.uv_a, d.uv_b]
    return out


@needs_aot
def test_the_demo_runs_only_ahead_of_time_code(tmp_path):
    """Every kernel call the demo makes from Python has its exported types (a call
    sent to the JIT would compile on a fresh install: a cold demo's whole point)."""
    from geomkit.jobs.demo import run_demo

    jit0 = {id(r): r.jit_calls for r in _aot.routers}
    aot0 = sum(r.aot_calls for r in _aot.routers)
    run_demo(tmp_path / "demo", grid=8, warm_up=False)
    sent = [r.__qualname__ for r in _aot.routers if r.jit_calls != jit0[id(r)]]
    assert not sent, f"demo calls sent to the JIT: {sent}"
    assert sum(r.aot_calls for r in _aot.routers) > aot0


@needs_aot
def test_aot_gives_the_jit_bits_on_the_shared_cases():
    before = sum(r.aot_calls for r in _aot.routers)
    aot = _jobs()
    used = sum(r.aot_calls for r in _aot.routers) - before
    with _aot.use_aot(False):
        jit = _jobs()
    assert used > 0, "no call ran the ahead-of-time code"
    assert len(aot) == len(jit)
    for x, y in zip(aot, jit):
        assert x.shape == y.shape and x.dtype == y.dtype
        assert np.array_equal(x, y, equal_nan=True)


@needs_aot
def test_aot_kernels_release_the_gil():
    """One long compiled call of the projection kernel (its arguments captured from a
    ``project_points`` call, widened to every point); a Python thread must keep
    running meanwhile.  A held GIL stops it for the whole call: its longest pause is
    then the call's duration (measured: 0.80 s for a 0.80 s ``nogil=False`` kernel)."""
    import time

    from geomkit._kernels import project

    R = project._project_chunk
    surf = samples.load("freeform_1")[0]
    lo, hi = surf.bounds
    P = lo + (hi - lo) * np.random.default_rng(1).random((6000, 3))
    captured = []
    saved = R.entries
    R.entries = [(c, (lambda fn: lambda *a: (captured.append(a), fn(*a))[1])(f))
                 for c, f in saved]
    try:
        geomkit.project_points(surf, P)
    finally:
        R.entries = saved
    args = list(captured[0])
    args[0], args[1] = 0, args[2].shape[0]
    n0 = R.aot_calls
    t = time.perf_counter()
    R(*args)
    call = time.perf_counter() - t
    done, gap = [], 0.0
    th = threading.Thread(target=lambda: (R(*args), done.append(1)))
    last = time.perf_counter()
    th.start()
    while not done:
        t = time.perf_counter()
        gap = max(gap, t - last)
        last = t
    th.join()
    assert R.aot_calls == n0 + 2
    assert call > 0.05, call
    assert gap < 0.5 * call, (gap, call)


def test_a_kernel_calling_a_router_compiles_against_its_dispatcher():
    """numba types a router as its dispatcher: kernels that call an exported kernel
    compile and run as before (a call from Python goes through the router)."""
    from geomkit._kernels.numba_ext.policy import _decorator

    def add(a, k):
        return a[k] + k

    disp = _decorator(cache=False)(add)
    r = _aot.Router(disp, [])
    try:
        caller = _decorator(cache=False)(lambda a, k: r(a, k) * 2)
        assert caller(np.arange(4.0), 2) == 8.0
        assert r(np.arange(4.0), 1) == 2.0 and r.jit_calls == 1
        assert len(disp.signatures) == 1  # one compile, shared by both paths
    finally:
        _aot.routers.remove(r)
