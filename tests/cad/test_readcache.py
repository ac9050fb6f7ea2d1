"""The CAD read cache (geomkit.cad.readcache): a second read of the same bytes comes
from the cache, equal to the first, with its warnings; changed bytes, other options,
a corrupt entry or GEOMKIT_NO_CACHE read afresh."""

from __future__ import annotations

import shutil
import warnings

import numpy as np
import pytest

import geomkit
from geomkit.cad import readcache, step

from helpers.paths import DATA

PART = DATA / "parts" / "nist_ctc_01_ap242.stp"


@pytest.fixture
def cache(tmp_path, monkeypatch):
    monkeypatch.delenv("GEOMKIT_NO_CACHE", raising=False)
    monkeypatch.setenv("GEOMKIT_CACHE_DIR", str(tmp_path / "cache"))
    readcache._memory.clear()
    yield tmp_path / "cache"
    readcache._memory.clear()


def _count_reads(monkeypatch):
    calls = []
    real = step._read_step

    def counting(*a, **k):
        calls.append(a)
        return real(*a, **k)

    monkeypatch.setattr(step, "_read_step", counting)
    return calls


def _same(a, b):
    assert len(a.surfaces) == len(b.surfaces) and a.entities == b.entities
    for s, t in zip(a.surfaces, b.surfaces):
        np.testing.assert_array_equal(s.control_points, t.control_points)
        assert s.name == t.name
    assert a.units == b.units and a.edge_gap == b.edge_gap


def test_second_read_comes_from_the_cache(cache, monkeypatch, tmp_path):
    calls = _count_reads(monkeypatch)
    first = geomkit.read_step(PART)
    assert len(calls) == 1 and len(list(cache.glob("*.pkl"))) == 1
    second = geomkit.read_step(PART)
    assert len(calls) == 1                       # memory hit
    _same(first, second)
    assert second.surfaces[0] is not first.surfaces[0]     # a fresh copy
    readcache._memory.clear()
    third = geomkit.read_step(PART)              # disk hit
    assert len(calls) == 1
    _same(first, third)
    # other options, or cache=False: read afresh
    geomkit.read_step(PART, skip_invalid=True)
    geomkit.read_step(PART, cache=False)
    assert len(calls) == 3


def test_changed_bytes_and_corrupt_entries(cache, monkeypatch, tmp_path):
    calls = _count_reads(monkeypatch)
    f = tmp_path / "part.stp"
    shutil.copy(PART, f)
    geomkit.read_step(f)
    f.write_bytes(f.read_bytes() + b"\n/* changed */\n")
    geomkit.read_step(f)
    assert len(calls) == 2
    readcache._memory.clear()
    for e in cache.glob("*.pkl"):
        e.write_bytes(b"not a pickle")
    r = geomkit.read_step(f)                     # a corrupt entry is a fresh read
    assert len(calls) == 3 and len(r.surfaces) == 117
    monkeypatch.setenv("GEOMKIT_NO_CACHE", "1")
    readcache._memory.clear()
    geomkit.read_step(f)
    assert len(calls) == 4


def test_other_code_reads_afresh(cache, monkeypatch):
    """An entry belongs to the code that wrote it: the same version with other code
    (an edited or updated install) does not return it."""
    calls = _count_reads(monkeypatch)
    geomkit.read_step(PART)
    stamp = readcache.code_stamp()
    assert len(stamp) == 32 and readcache.code_stamp() is stamp     # once per process
    readcache._memory.clear()
    monkeypatch.setattr(readcache, "_CODE", bytes(32))              # other code
    geomkit.read_step(PART)
    assert len(calls) == 2 and len(list(cache.glob("*.pkl"))) == 2
    monkeypatch.setattr(readcache, "_CODE", stamp)                  # this code again
    readcache._memory.clear()
    geomkit.read_step(PART)
    assert len(calls) == 2


def test_warnings_are_given_again(cache, monkeypatch):
    def warn_then_read(*a, **k):
        warnings.warn("a planted warning", UserWarning)
        return real(*a, **k)

    real = step._read_step
    monkeypatch.setattr(step, "_read_step", warn_then_read)
    with pytest.warns(UserWarning, match="planted"):
        geomkit.read_step(PART)
    with pytest.warns(UserWarning, match="planted"):
        geomkit.read_step(PART)                  # from the cache


def test_unwritable_cache_folder_still_reads(monkeypatch, tmp_path):
    monkeypatch.delenv("GEOMKIT_NO_CACHE", raising=False)
    blocker = tmp_path / "file"
    blocker.write_text("x")
    monkeypatch.setenv("GEOMKIT_CACHE_DIR", str(blocker / "sub"))
    readcache._memory.clear()
    r = geomkit.read_step(PART)
    assert len(r.surfaces) == 117
    readcache._memory.clear()


def test_reads_pause_the_garbage_collector_and_restore_it():
    import gc

    assert gc.isenabled()
    with readcache.gc_paused():
        assert not gc.isenabled()
    assert gc.isenabled()
    with pytest.raises(ValueError), readcache.gc_paused():
        raise ValueError("a failed read")
    assert gc.isenabled()  # restored after a failure too
    gc.disable()
    try:
        with readcache.gc_paused():
            pass
        assert not gc.isenabled()  # a caller's own setting is kept
    finally:
        gc.enable()
