"""Every use of numba's internals, in one folder, checked when it is imported.

* :mod:`.policy`: the decorators every kernel uses (flags, the package-wide cache
  stamp through numba's cache locator classes, the dispatcher that compiles callees
  for plain argument types, :func:`~.policy.prun`);
* :mod:`.borrow`: array views without atomic reference counts (an intrinsic that
  clears the meminfo pointer);
* :mod:`.pyobj`: a numba type whose unboxer hands a kernel the ``PyObject*`` itself,
  read through CPython's and NumPy's struct layouts (checked against a live array);
* :mod:`.aot` / :mod:`.aot_build`: the ahead-of-time module built with ``numba.pycc``,
  its loader and the router that calls it.

These depend on numba internals that change between releases, so the supported range
is pinned in ``pyproject.toml`` and checked here: if an internal is missing, importing
geomkit fails at once with one line naming the numba version, rather than failing
later or silently running slower.  (A numba without ``pycc`` still imports: the
kernels then run on the JIT and ``geomkit --version`` says so.)
"""

from __future__ import annotations

import importlib
import warnings

import numba

SUPPORTED = ((0, 59), (0, 69))
"""numba versions the suite has passed on: ``SUPPORTED[0] <= version < SUPPORTED[1]``."""

REQUIRED = {
    "numba.core.caching": ("UserProvidedCacheLocator", "InTreeCacheLocator",
                           "UserWideCacheLocator", "CompileResultCacheImpl",
                           "FunctionCache", "IndexDataCacheFile"),
    "numba.core.registry": ("CPUDispatcher",),
    "numba.core.cgutils": ("get_null_value",),
    "numba.core.codegen": ("JITCPUCodegen",),
    "numba.extending": ("intrinsic", "overload", "unbox", "NativeValue", "models",
                        "register_model"),
}
"""The numba internals the kernels use, by module."""


def _version(text: str) -> tuple:
    parts = []
    for p in text.split(".")[:2]:
        digits = "".join(ch for ch in p if ch.isdigit())
        parts.append(int(digits) if digits else 0)
    return tuple(parts)


def missing_internals() -> list:
    """The names in :data:`REQUIRED` this numba lacks (empty when all are there)."""
    out = []
    for mod, names in REQUIRED.items():
        try:
            m = importlib.import_module(mod)
        except ImportError:
            out.append(mod)
            continue
        out += [f"{mod}.{n}" for n in names if not hasattr(m, n)]
    return out


def _check() -> None:
    lo, hi = SUPPORTED
    rng = f"numba>={lo[0]}.{lo[1]},<{hi[0]}.{hi[1]}"
    gone = missing_internals()
    if gone:
        raise ImportError(f"geomkit's kernels need numba internals that numba "
                          f"{numba.__version__} does not have ({', '.join(gone)}); "
                          f"install a supported release: pip install '{rng}'")
    if not lo <= _version(numba.__version__) < hi:
        warnings.warn(f"numba {numba.__version__} is outside the range geomkit was tested "
                      f"on ({rng}); its internals are present, results are unchecked",
                      RuntimeWarning, stacklevel=2)


_check()
