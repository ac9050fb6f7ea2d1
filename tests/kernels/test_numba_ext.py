"""The numba internals check (geomkit/_kernels/numba_ext/__init__.py): every internal
the kernels use is present in the installed numba, the version is in the tested range
pyproject.toml pins, and a missing internal fails the import with one line naming the
numba version."""

from __future__ import annotations

import re
import subprocess
import sys

import numba

from geomkit._kernels import numba_ext
from helpers.paths import ROOT


def test_installed_numba_has_every_internal_and_is_in_range():
    assert numba_ext.missing_internals() == []
    lo, hi = numba_ext.SUPPORTED
    assert lo <= numba_ext._version(numba.__version__) < hi


def test_pyproject_pins_the_tested_range():
    lo, hi = numba_ext.SUPPORTED
    text = (ROOT / "pyproject.toml").read_text()
    pins = re.findall(r'"numba>=([0-9.]+),<([0-9.]+)"', text)
    assert pins, "numba is not pinned in pyproject.toml"
    for a, b in pins:
        assert numba_ext._version(a) == lo and numba_ext._version(b) == hi, pins


def test_a_missing_internal_fails_the_import_in_one_line():
    code = ("import numba.core.caching as c; del c.FunctionCache\n"
            "try:\n    import geomkit\nexcept ImportError as e:\n    print(str(e))\n")
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                       cwd=str(ROOT), timeout=300)
    msg = r.stdout.strip()
    assert "\n" not in msg and f"numba {numba.__version__}" in msg, (msg, r.stderr[-2000:])
    assert "numba.core.caching.FunctionCache" in msg and "pip install" in msg


def test_an_unreadable_cache_entry_counts_as_absent(tmp_path, monkeypatch):
    """A cache index that names a module which no longer exists (a numba type whose
    module moved between releases) is read as an empty cache, not an ImportError."""
    import pickle
    import types

    from geomkit._kernels.numba_ext.policy import _CacheFile

    mod = types.ModuleType("geomkit_gone_module")
    exec("class Kind:\n    pass\n", mod.__dict__)
    mod.Kind.__module__ = mod.__name__
    monkeypatch.setitem(sys.modules, mod.__name__, mod)
    payload = pickle.dumps(("stamp", {"key": mod.Kind()}))
    monkeypatch.delitem(sys.modules, mod.__name__)
    f = _CacheFile(cache_path=str(tmp_path), filename_base="k", source_stamp="stamp")
    with open(f._index_path, "wb") as fh:
        pickle.dump(f._version, fh)
        fh.write(payload)
    try:                                    # numba's own loader fails on it
        pickle.loads(payload)
        raise AssertionError("the payload should not unpickle")
    except ModuleNotFoundError:
        pass
    assert f._load_index() == {}
    assert f.load("key") is None
