"""Ahead-of-time compiled kernels: the loader and the call router.

``python geomkit/_kernels/numba_ext/aot_build.py`` (run by ``setup.py`` when the package is built or
installed) compiles the kernels listed in ``aot_exports.json`` -- the kernels the
demo's jobs and a real part's read, mesh, section and projection call from Python,
with the argument types they call them with -- into the extension modules
``aot_lib`` (and ``aot_lib_1`` for the kernels compiled without contraction) next to
this file, and writes ``aot_manifest.json`` (what was built, for which kernel
sources, numba version and CPU, each export's module).

At import, :func:`load` accepts the module only if the manifest matches this
process: the same kernel sources (the stamp of :mod:`.policy`, so an edited kernel
or a ``git pull`` in an editable install falls back to the JIT), the same numba
version, the same host CPU name and features (the code is compiled for the build
machine's CPU, as the JIT compiles for this one).  Then :func:`.policy._decorator`
returns a :class:`Router` instead of the dispatcher for each exported kernel: a
call from Python whose arguments have *exactly* one exported signature's types (as
``numba.typeof`` would type them: dtype, ndim, layout, writeability, alignment) runs
the ahead-of-time function; any other call goes to the JIT dispatcher.  pycc's
argument unboxing checks only an array's item size, so that test is what keeps a
wrong array away from the compiled code.  A router is typed by numba as its
dispatcher (``_numba_type_``), so kernels calling it compile exactly as before.

``GEOMKIT_AOT=0`` disables the ahead-of-time kernels (everything runs on the JIT).
"""

from __future__ import annotations

import json
import os
import re
from pathlib import Path

import numpy as np
from numba.core import types

HERE = Path(__file__).resolve().parent
EXPORTS = HERE / "aot_exports.json"
MANIFEST = HERE / "aot_manifest.json"
LIB_NAME = "aot_lib"

status = "not loaded"
"""One line for ``geomkit --version`` / the demo: whether the ahead-of-time kernels
are in use, and if not, why."""

_table: dict | None = None  # (module, qualname) -> [(argtypes, function)]


# ---------------------------------------------------------------------------
# type strings (as ``str(numba.typeof(x))``) <-> numba types

def _split_top(s):
    out, depth, cur = [], 0, ""
    for ch in s:
        if ch == "," and depth == 0:
            out.append(cur.strip())
            cur = ""
            continue
        depth += ch == "("
        depth -= ch == ")"
        cur += ch
    if cur.strip():
        out.append(cur.strip())
    return out


_ARRAY = re.compile(r"(readonly )?(unaligned )?array\((\w+), (\d+)d, ([CFA])\)")


def parse_type(s: str):
    """The numba type printed as ``s`` (the subset kernels take from Python: arrays,
    scalars, ``none``, tuples); ``ValueError`` for anything else."""
    s = s.strip()
    m = _ARRAY.fullmatch(s)
    if m:
        t = types.Array(getattr(types, m[3]), int(m[4]), m[5], readonly=bool(m[1]),
                        aligned=not m[2])
    elif s.startswith("UniTuple(") and s.endswith(")"):
        inner, n = s[9:-1].rsplit(" x ", 1)
        t = types.UniTuple(parse_type(inner), int(n))
    elif s.startswith("Tuple(") and s.endswith(")"):
        t = types.Tuple([parse_type(x) for x in _split_top(s[6:-1])])
    elif s == "none":
        t = types.none
    elif s == "bool":
        t = types.boolean
    elif re.fullmatch(r"(u?int(8|16|32|64)|float(32|64))", s):
        t = getattr(types, s)
    else:
        raise ValueError(f"type {s!r} is not supported for ahead-of-time export")
    if str(t) != s:
        raise ValueError(f"type {s!r} does not round-trip (parsed as {t})")
    return t


_INT = {"int64": (-(2**63), 2**63 - 1)}


def _checker(t):
    """A cheap predicate: does ``numba.typeof(x)`` equal ``t``?"""
    if isinstance(t, types.Array):
        dt = np.dtype(str(t.dtype))
        nd, layout, writeable, aligned = t.ndim, t.layout, t.mutable, t.aligned

        def check(x):
            if type(x) is not np.ndarray or x.dtype != dt or x.ndim != nd:
                return False
            f = x.flags
            if f.writeable != writeable or f.aligned != aligned:
                return False
            lay = "C" if f.c_contiguous else ("F" if f.f_contiguous else "A")
            return lay == layout
        return check
    if isinstance(t, types.BaseTuple):
        subs = [_checker(e) for e in t.types]
        n = len(subs)
        return lambda x: (type(x) is tuple and len(x) == n
                          and all(c(e) for c, e in zip(subs, x)))
    if t == types.none:
        return lambda x: x is None
    if t == types.boolean:
        return lambda x: type(x) is bool or type(x) is np.bool_
    if t == types.float64:
        return lambda x: type(x) is float or type(x) is np.float64
    if t == types.int64:
        lo, hi = _INT["int64"]
        return lambda x: (type(x) is np.int64
                          or (type(x) is int and lo <= x <= hi))
    scalar = getattr(np, str(t))
    return lambda x: type(x) is scalar


_C, _F, _ALIGNED, _WRITEABLE = 0x1, 0x2, 0x100, 0x400  # ndarray.flags.num bits


def signature_checker(argtypes):
    """A predicate over an argument tuple: exactly these numba types (generated
    code: one test per argument, arrays by their ``flags.num`` bits; ~0.1 us an
    argument)."""
    lines = ["def check(args):", f"    if len(args) != {len(argtypes)}:", "        return False"]
    ns = {"ndarray": np.ndarray, "float": float, "int": int, "bool": bool}
    if argtypes:
        lines.append("    " + ", ".join(f"a{i}" for i in range(len(argtypes))) + ", = args")
    for i, t in enumerate(argtypes):
        a = f"a{i}"
        if isinstance(t, types.Array):
            ns[f"D{i}"] = np.dtype(str(t.dtype))
            need = _ALIGNED | (_WRITEABLE if t.mutable else 0)
            mask = _ALIGNED | _WRITEABLE
            if t.layout == "C":
                mask, need = mask | _C, need | _C
            else:  # F: F and not C; A: neither
                mask |= _C | _F
                need |= _F if t.layout == "F" else 0
            cond = (f"type({a}) is not ndarray or ({a}.dtype is not D{i} and "
                    f"{a}.dtype != D{i}) or {a}.ndim != {t.ndim} or "
                    f"({a}.flags.num & {mask}) != {need}")
        elif t == types.none:
            cond = f"{a} is not None"
        elif t == types.float64:
            ns["f64"] = np.float64
            cond = f"type({a}) is not float and type({a}) is not f64"
        elif t == types.int64:
            ns["i64"] = np.int64
            cond = (f"type({a}) is not i64 and not (type({a}) is int and "
                    f"{_INT['int64'][0]} <= {a} <= {_INT['int64'][1]})")
        elif t == types.boolean:
            ns["b_"] = np.bool_
            cond = f"type({a}) is not bool and type({a}) is not b_"
        else:
            ns[f"K{i}"] = _checker(t)
            cond = f"not K{i}({a})"
        lines += [f"    if {cond}:", "        return False"]
    lines.append("    return True")
    exec("\n".join(lines), ns)
    return ns["check"]


# ---------------------------------------------------------------------------
# loading

def host_cpu():
    """``(cpu name, features)`` as the JIT compiles for them."""
    from numba.core.codegen import JITCPUCodegen

    import llvmlite.binding as ll

    return ll.get_host_cpu_name(), JITCPUCodegen._get_host_cpu_features(None)


def export_symbol(module: str, qualname: str, k: int) -> str:
    """The name of export number ``k`` (its place in the export list) in ``aot_lib``;
    pycc compiles its exports sorted by name, i.e. in the list's order."""
    return f"k{k:03d}_{module.rsplit('.', 1)[-1]}__{qualname.replace('.', '_')}"


def active() -> bool:
    """True when the ahead-of-time module is loaded and its kernels are routed."""
    return _table is not None


def mismatch(man: dict, stamp_hex: str):
    """Why the build described by manifest ``man`` cannot serve this process (None if
    it can): other kernel sources, numba version or CPU than the running ones."""
    import numba

    if man.get("stamp") != stamp_hex:
        return "kernel sources changed since the build"
    if man.get("numba") != numba.__version__:
        return f"built with numba {man.get('numba')}, running {numba.__version__}"
    if man.get("cpu") != list(host_cpu()):
        return f"built for CPU {(man.get('cpu') or ['?'])[0]}, not this one's features"
    return None


def load(stamp_hex: str):
    """Load the ahead-of-time module if it is valid for this process; sets
    :data:`status`.  Returns the table or None."""
    global status, _table
    if _table is not None:
        return _table
    if os.environ.get("GEOMKIT_AOT", "1") == "0":
        status = "ahead-of-time kernels off (GEOMKIT_AOT=0): JIT"
        return None
    if not MANIFEST.exists():
        status = "no ahead-of-time kernels built: JIT"
        try:
            import importlib.util

            import numba
            if importlib.util.find_spec("numba.pycc") is None:
                status = (f"no ahead-of-time kernels (numba {numba.__version__} has no pycc "
                          "to build them): JIT")
        except (ImportError, ValueError):
            pass
        return None
    try:
        import numba

        man = json.loads(MANIFEST.read_text())
        why = mismatch(man, stamp_hex)
        if why:
            status = f"ahead-of-time kernels not used ({why}): JIT"
            return None
        import importlib

        libs = {}  # one module per set of compile flags (aot_build.build)
        table = {}
        for mod, qual, k, sig, *name in man["exports"]:
            name = name[0] if name else LIB_NAME
            if name not in libs:
                libs[name] = importlib.import_module(f"{__package__}.{name}")
            argtypes = [parse_type(s) for s in sig]
            fn = getattr(libs[name], export_symbol(mod, qual, k))
            table.setdefault((mod, qual), []).append((signature_checker(argtypes), fn))
        _table = table
        status = (f"ahead-of-time kernels: {sum(map(len, table.values()))} entries "
                  f"of {len(table)} kernels (numba {numba.__version__}, "
                  f"CPU {man['cpu'][0]})")
        return table
    except Exception as e:  # never let a broken build stop the package: JIT
        status = f"ahead-of-time kernels failed to load ({type(e).__name__}: {e}): JIT"
        return None


routers: list = []
"""Every :class:`Router` made in this process."""


class use_aot:
    """``with use_aot(False):`` runs every routed kernel on its JIT dispatcher (to
    compare the two in one process); ``use_aot(True)`` restores the routing."""

    def __init__(self, on: bool):
        self.on = on

    def __enter__(self):
        self.saved = [r.entries for r in routers]
        for r in routers:
            if not self.on:
                r.entries = []
        return self

    def __exit__(self, *exc):
        for r, e in zip(routers, self.saved):
            r.entries = e
        return False


class Router:
    """The Python-visible name of an exported kernel: runs the ahead-of-time
    function when the arguments have exactly its types, else the JIT dispatcher
    (:attr:`dispatcher`).  numba types it as the dispatcher."""

    def __init__(self, dispatcher, entries):
        self.dispatcher = dispatcher
        self.entries = entries
        self.aot_calls = 0  # calls that ran the ahead-of-time code (diagnostics, tests)
        self.jit_calls = 0  # calls sent to the JIT dispatcher
        routers.append(self)
        self.__wrapped__ = dispatcher
        f = dispatcher.py_func
        self.__doc__ = f.__doc__
        self.__name__ = f.__name__
        self.__qualname__ = f.__qualname__
        self.__module__ = f.__module__

    @property
    def _numba_type_(self):
        return self.dispatcher._numba_type_

    @property
    def py_func(self):
        return self.dispatcher.py_func

    def __getattr__(self, name):  # signatures, overloads, ...: the dispatcher's
        return getattr(self.dispatcher, name)

    def __call__(self, *args, **kws):
        if not kws:
            for check, fn in self.entries:
                if check(args):
                    self.aot_calls += 1
                    return fn(*args)
        self.jit_calls += 1
        return self.dispatcher(*args, **kws)

    def __repr__(self):
        return f"<AOT router for {self.dispatcher!r}>"
