"""numba policy for every geomkit kernel, set in one place.

* ``cache=True``: compiled code is stored on disk next to the sources, so only the
  first import on a machine pays the compile time.  A cache entry is valid for the
  exact sources of every kernel file (:class:`_PackageStamp`): numba's own check
  looks only at the kernel's file, while its code includes callees from others.
* ``nogil=True``: kernels release the GIL and can run in threads.
* fastmath allows only contraction (fused multiply-add) and signed-zero freedom: no
  ``nnan``/``ninf`` (NaN checks must keep working) and no reassociation (results stay
  reproducible and as accurate as the reference algorithms); :data:`jit_exact` kernels
  do not contract either (numpy's values, bit for bit).
* ``error_model="numpy"``: a float division by zero gives inf/nan instead of raising
  inside the kernel (no hidden branch per division); kernels guard their own
  degenerate cases and the public functions check results.
* batch kernels are serial :data:`jit` workers over an index range ``[i0, i1)``,
  run in parallel by :func:`prun` on Python threads (they release the GIL).  Numba's
  ``parallel=True`` / ``prange`` (:data:`pjit`) compiles the whole call tree of the
  loop body three more times (parfor kernel, gufunc wrapper, caller), which cost more
  than half of the first-run compile time of the projection kernels.
* ahead-of-time kernels (:mod:`.numba_ext.aot`): when the package was built with them, the
  decorator returns a router for each exported kernel, which runs the compiled
  module's code for calls from Python with exactly the exported argument types and
  this dispatcher otherwise (docs/compile.md).
"""

from __future__ import annotations

import hashlib
import os
import threading
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import numba
from numba.core import caching, errors, types
from numba.core.registry import CPUDispatcher

from . import aot as _aot

# The OpenMP layer parks idle threads deeply: every parallel call then pays ~7 ms of
# wake-up, which dominates the many small kernel calls of adaptive refinement
# (measured: tessellating cylinder_quarter took 68 ms with "omp", 4 ms with
# "workqueue").  workqueue does not support launching parallel kernels from several
# Python threads at once; set NUMBA_THREADING_LAYER (e.g. "tbb" or "omp") to choose.
if "NUMBA_THREADING_LAYER" not in os.environ:
    numba.config.THREADING_LAYER = "workqueue"

FASTMATH = {"contract", "nsz"}


def _kernels_stamp() -> bytes:
    """SHA-256 of every kernel source file (``_kernels/*.py`` and this folder's numba
    extensions, not the ahead-of-time loader and build tool), computed once per process."""
    global _STAMP
    if _STAMP is None:
        h = hashlib.sha256()
        here = Path(__file__).resolve().parent
        for f in sorted(here.parent.glob("*.py")) + sorted(here.glob("*.py")):
            if f.name.startswith("aot"):  # the loader, router and build tool: no kernel code
                continue
            h.update(f"{f.parent.name}/{f.name}".encode())
            h.update(f.read_bytes())
        _STAMP = h.digest()
    return _STAMP


_STAMP = None


class _PackageStamp:
    """Cache locator mixin: a kernel's cache entry is valid only for the exact sources
    of *every* kernel file, not just its own.  numba checks only the file defining a
    function, but a kernel's compiled code includes its callees from other files
    (numba links them in): after an edit of ``bvh_query.py`` (or a ``git pull`` in an
    editable install) a cached caller in ``motion.py`` would keep running the old
    callee.  Any change in ``geomkit/_kernels`` therefore recompiles every kernel."""

    def get_source_stamp(self):
        return (super().get_source_stamp(), _kernels_stamp())


class _UserProvidedLocator(_PackageStamp, caching.UserProvidedCacheLocator):
    pass


class _InTreeLocator(_PackageStamp, caching.InTreeCacheLocator):
    pass


class _UserWideLocator(_PackageStamp, caching.UserWideCacheLocator):
    pass


class _CacheImpl(caching.CompileResultCacheImpl):
    _locator_classes = [_UserProvidedLocator, _InTreeLocator, _UserWideLocator]


class _CacheFile(caching.IndexDataCacheFile):
    """numba's cache files, except that an entry that cannot be read back counts as
    absent (the kernel is compiled again and the entry rewritten) instead of failing
    the call.  An entry pickles the types of its arguments by module path: one written
    by another layout of this package (a numba type whose module moved, e.g. after an
    upgrade) raises ImportError in numba's own loader."""

    def _load_index(self):
        try:
            return super()._load_index()
        except Exception:   # ImportError, AttributeError, UnpicklingError, EOFError, ...
            return {}

    def load(self, key):
        try:
            return super().load(key)
        except Exception:
            return None


class _FunctionCache(caching.FunctionCache):
    _impl_class = _CacheImpl

    def __init__(self, py_func):
        super().__init__(py_func)
        self._cache_file.__class__ = _CacheFile


class _CachedDispatcher(CPUDispatcher):
    """numba's CPU dispatcher with the package-wide cache stamp (:class:`_PackageStamp`)."""

    def enable_caching(self):
        self._cache = _FunctionCache(self.py_func)


class _Dispatcher(_CachedDispatcher):
    """numba's CPU dispatcher, except that a call from another kernel compiles the
    callee for the plain types of its arguments, not their literal types.

    numba types a constant argument (``0``, ``True``, a module-level int such as
    ``D2``, or a variable still holding its initial constant in numba's SSA form) as
    ``Literal[int](0)`` and compiles the callee once more for it (a whole call tree
    again: ``sphere_fit_separator`` was compiled twice, ``sep_bounds`` and
    ``_add_sep`` three times on a fresh install).  The literal specialisation is only
    tried when the plain one does not type (a callee that needs a constant)."""

    def get_call_template(self, args, kws):
        plain = tuple(types.unliteral(a) for a in args)
        if plain != tuple(args):
            try:
                return super().get_call_template(plain, kws)
            except errors.TypingError:
                pass
        return super().get_call_template(args, kws)


_RECORD = os.environ.get("GEOMKIT_AOT_RECORD")
"""When set (a file name): record every call of a kernel *from Python* (the argument
types as numba sees them) and write them there at exit (:mod:`geomkit._kernels.numba_ext.aot_build`
generates the ahead-of-time export list from it)."""

_recorded: dict = {}  # (module, qualname) -> {signature: None}, in first-call order


class _Recording:
    """Dispatcher mixin of the recording mode (:data:`_RECORD`): calls from Python go
    through this ``__call__``; calls from other kernels are compiled and never do."""

    def __call__(self, *args, **kws):
        key = (self.py_func.__module__, self.py_func.__qualname__)
        sig = ("kwargs",) if kws else tuple(str(numba.typeof(a)) for a in args)
        _recorded.setdefault(key, {}).setdefault(sig, None)
        return super().__call__(*args, **kws)


def _write_recorded():
    import json

    # in the order of the first calls: the build compiles them in that order, as the
    # JIT did in the recorded run
    rows = [[m, q, list(sig)] for (m, q), sigs in _recorded.items() for sig in sigs]
    with open(_RECORD, "w") as fh:
        json.dump(rows, fh, indent=0)


if _RECORD:
    import atexit

    atexit.register(_write_recorded)


def _decorator(cache=True, dispatcher=None, **options):
    targetoptions = dict(dict(nopython=True, nogil=True, fastmath=FASTMATH,
                              error_model="numpy"), **options)
    cls = _Dispatcher if dispatcher is None else dispatcher
    if _RECORD:
        cls = type(cls.__name__, (_Recording, cls), {})

    def wrap(func):
        if numba.config.DISABLE_JIT:
            return func
        disp = cls(py_func=func, locals={}, targetoptions=targetoptions)
        if cache:
            disp.enable_caching()
        if not _RECORD:
            table = _aot.load(_kernels_stamp().hex())
            entries = table and table.get((func.__module__, func.__qualname__))
            if entries:
                return _aot.Router(disp, entries)
        return disp
    return wrap


jit = _decorator(dispatcher=_CachedDispatcher)
"""Decorator for serial kernels."""

jit_plain = _decorator()
"""Like :data:`jit`, but calls from other kernels compile it for plain argument types
(see :class:`_Dispatcher`): for kernels whose callers pass constants and where a
constant argument gains nothing at run time (the distance and motion kernels).  Not
the default: a literal derivative order or size lets LLVM unroll the small loops of
the evaluation kernels (tessellating freeform_1 at 1e-3 looked ~15 % slower with
every kernel compiled for plain types, noisy runs on a loaded machine)."""

jit_exact = _decorator(fastmath={"nsz"})
"""Like :data:`jit_plain`, without contraction: each ``a * b + c`` rounded twice, as
numpy computes it, for kernels that replace numpy formulas value for value (the CAD
readers' closed forms, whose faces are compared bit for bit with the formulas')."""

jit_inline = _decorator(dispatcher=_CachedDispatcher, inline="always")
"""Decorator for tiny helpers called in hot loops with array arguments: inlined at the
numba IR level, which removes the per-call reference counting of array arguments
(measured: a heap push/pop with array arguments cost ~50 ns as a call)."""


def jit_holding_gil(func):
    """:data:`jit` except that the compiled entry point keeps the GIL
    (``nogil=False``; cached likewise, never ahead-of-time): for a kernel that releases
    it itself around its long part, so that a call answered at once does not pay the
    release and re-acquisition (:func:`geomkit._kernels.bvh_boxes.collide_packed`:
    ~0.09 us of a ~0.8 us call, measured interleaved with coal's calls)."""
    disp = _CachedDispatcher(py_func=func, locals={}, targetoptions=dict(
        nopython=True, nogil=False, fastmath=FASTMATH, error_model="numpy"))
    disp.enable_caching()
    return disp


def pjit(func):
    """Decorator for batch kernels parallel over their outer ``prange`` loop."""
    return _decorator(dispatcher=_CachedDispatcher, parallel=True)(func)


prange = numba.prange


def _install_compile_log(path):
    """Append one line per numba compilation in this process to ``path``:
    ``pid, function, start, end, exclusive CPU seconds`` (tab separated; times are
    ``time.time()``).  Enabled by ``GEOMKIT_COMPILE_LOG=<file>`` so that the demo and
    its background compile helper (a separate process) log to one file;
    :mod:`geomkit.bench.compile_groups` reads it (which process compiled what, and
    whether a kernel was compiled twice)."""
    import time

    from numba.core import event

    stack = []
    pid = os.getpid()

    class _Log(event.Listener):
        def on_start(self, ev):
            f = ev.data["dispatcher"].py_func
            stack.append((f"{f.__module__}.{f.__qualname__}", time.time(),
                          time.process_time(), [0.0]))

        def on_end(self, ev):
            name, w0, c0, kids = stack.pop()
            dt = time.process_time() - c0
            if stack:
                stack[-1][3][0] += dt
            with open(path, "a") as fh:
                fh.write(f"{pid}\t{name}\t{w0:.3f}\t{time.time():.3f}\t{dt - kids[0]:.3f}\n")

    event.register("numba:compile", _Log())


if os.environ.get("GEOMKIT_COMPILE_LOG"):
    _install_compile_log(os.environ["GEOMKIT_COMPILE_LOG"])

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
    # one chunk runs here without asking numba for its threads (that call takes a
    # lock and costs ~15 us: a reader calls small kernels thousands of times)
    nt = 1 if nch <= 1 else min(numba.get_num_threads(), nch)
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
        # every task is taken once run() returns here: a helper that has not started
        # yet would find none, so it is cancelled rather than waited for (on a busy
        # machine a pool thread can wait long for a core)
        for f in futures:
            if not f.cancel():
                f.result()
