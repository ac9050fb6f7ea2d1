"""A cache of CAD reads keyed by the file's content: the second read of the same file
(same bytes, same options, same geomkit) is an unpickling, not a conversion.

Entries live in ``$GEOMKIT_CACHE_DIR`` or, by default, ``$XDG_CACHE_HOME/geomkit/cad``
(``~/.cache/geomkit/cad``), one file per read named by the SHA-256 of the file's
bytes, its path (the messages name it), the reader options, geomkit's version and
its code (:func:`code_stamp`); the warnings the first read gave are
stored with it and given again on every hit.  An entry is written atomically (a
temporary file renamed); a cache folder that cannot be written, or an entry that
cannot be read (truncated, from another Python), only costs a fresh read.  The process
also keeps the last :data:`MEMORY_ENTRIES` entries in memory.  Every hit returns a
fresh copy: callers may change what they get.

``GEOMKIT_NO_CACHE=1`` turns the cache off (the test-suite does, except where it tests
the cache); ``read_step(path, cache=False)`` for one call.
"""

from __future__ import annotations

import gc
import hashlib
import os
import pickle
import tempfile
import warnings
from collections import OrderedDict
from contextlib import contextmanager
from pathlib import Path

from geomkit.version import __version__

__all__ = ["cached_read", "cache_dir", "code_stamp", "gc_paused", "MEMORY_ENTRIES",
           "FORMAT"]

FORMAT = 1
"""Bumped when the layout of a cached entry changes."""
MEMORY_ENTRIES = 8
_memory: OrderedDict = OrderedDict()


def cache_dir() -> Path | None:
    """The cache folder, or None when the cache is off."""
    if os.environ.get("GEOMKIT_NO_CACHE", "").strip() not in ("", "0"):
        return None
    d = os.environ.get("GEOMKIT_CACHE_DIR")
    if d:
        return Path(d)
    base = os.environ.get("XDG_CACHE_HOME") or str(Path.home() / ".cache")
    return Path(base) / "geomkit" / "cad"


@contextmanager
def gc_paused():
    """Python's cyclic garbage collector off for the block (as it was after it).  A
    read builds ~10^5 small objects and no cycles; the collector's passes over them
    cost more than the unpickling of a cached read (measured on an 822-face part in a
    new process: ~90 ms with it, ~35 ms without)."""
    was = gc.isenabled()
    gc.disable()
    try:
        yield
    finally:
        if was:
            gc.enable()


_CODE: bytes | None = None


def code_stamp() -> bytes:
    """SHA-256 of every source file of the installed geomkit package (names and
    contents), computed once per process (~7 ms): an entry is valid only for the code
    that wrote it, so an edited or updated install (same version, other code) reads
    afresh instead of returning what older code made."""
    global _CODE
    if _CODE is None:
        root = Path(__file__).resolve().parents[1]
        h = hashlib.sha256()
        for f in sorted(root.rglob("*.py")):
            h.update(f.relative_to(root).as_posix().encode() + b"\0")
            h.update(f.read_bytes())
        _CODE = h.digest()
    return _CODE


def _key(data: bytes, options: tuple) -> str:
    h = hashlib.sha256()
    h.update(data)
    h.update(repr((FORMAT, __version__, options)).encode())
    h.update(code_stamp())
    return h.hexdigest()


def _replay(caught) -> None:
    for category, message in caught:
        warnings.warn(message, category, stacklevel=3)


def _load(path: Path):
    try:
        blob = path.read_bytes()
        with gc_paused():
            return pickle.loads(blob)
    except FileNotFoundError:
        return None
    except Exception:  # a truncated or foreign entry: drop it, read afresh
        try:
            path.unlink()
        except OSError:
            pass
        return None


def _store(folder: Path, name: str, blob: bytes) -> None:
    try:
        folder.mkdir(parents=True, exist_ok=True)
        fd, tmp = tempfile.mkstemp(dir=folder, prefix=".tmp-", suffix=".pkl")
        try:
            with os.fdopen(fd, "wb") as fh:
                fh.write(blob)
            os.replace(tmp, folder / name)
        except BaseException:
            os.unlink(tmp)
            raise
    except OSError:
        pass


def cached_read(data: bytes, options: tuple, read):
    """``read()``'s result for a file whose bytes are ``data``, from the cache when
    the same bytes were read with the same ``options`` before; the warnings of the
    first read are given again."""
    folder = cache_dir()
    if folder is None:
        return read()
    key = _key(data, options)
    blob = _memory.get(key)
    entry = None
    if blob is not None:
        _memory.move_to_end(key)
        with gc_paused():
            entry = pickle.loads(blob)
    else:
        entry = _load(folder / f"{key}.pkl")
    if entry is not None and isinstance(entry, dict) and entry.get("format") == FORMAT:
        _replay(entry["warnings"])
        return entry["result"]
    with warnings.catch_warnings(record=True) as got:
        warnings.simplefilter("always")
        result = read()
    caught = [(w.category, str(w.message)) for w in got]
    _replay(caught)
    try:
        blob = pickle.dumps({"format": FORMAT, "result": result, "warnings": caught},
                            protocol=pickle.HIGHEST_PROTOCOL)
    except Exception:  # an unpicklable result: no cache entry
        return result
    _memory[key] = blob
    while len(_memory) > MEMORY_ENTRIES:
        _memory.popitem(last=False)
    _store(folder, f"{key}.pkl", blob)
    return result
