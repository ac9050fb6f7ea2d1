"""Mutation fuzz of every reader (:mod:`helpers.fuzz`): each mutated file is read or
raises a :class:`~geomkit.GeomkitError` subclass with a message through the Python
API, and through the command line ends in exit 0 or exit 2 with one error line,
JSON on stdout with ``--json``, no output folder left behind; no input is modified.
Seeded (the same inputs every run): 13 base files (IGES, STEP, geomkit-case JSON,
geomdl JSON, CSV, XYZ, PLY ASCII and binary, STL, NPY, LAS, LAZ, E57) x 18 inputs.
STEP is read with geomkit's own reader on the API side (the hand-off of what it
cannot convert to Open CASCADE, in a child process, is tested in
``tests/cad/test_step_native.py``).  The long run (>= 10,000 inputs, crashes and hangs
caught in worker processes) is ``python tests/helpers/fuzz.py``; docs/fuzzing.md."""

from __future__ import annotations

import pytest

from geomkit.cad.step import read_step
from geomkit.errors import GeomkitError
from helpers import fuzz

PER_FILE = 18


def test_mutated_files_read_or_raise_a_geomkit_error(tmp_path):
    bases = fuzz.make_bases(tmp_path / "base")
    assert len(bases) == 13
    for src in bases:  # every base file is valid: read whole
        assert fuzz.check(src, tmp_path / "out") is None, src.name
    failed = []
    for src, k, data in fuzz.inputs(bases, PER_FILE, 20261127):
        path = tmp_path / f"m{k}{src.suffix}"
        path.write_bytes(data)
        problem = fuzz.check(path, tmp_path / "out")
        if problem:
            failed.append(f"{src.name} #{k}: {problem}")
    assert not failed, "\n".join(failed[:10])


@pytest.mark.parametrize("text", ["", "ISO-10303-21;\nHEADER;\nENDSEC;\nDATA;\n#1=X(;\n"
                                  "ENDSEC;\nEND-ISO-10303-21;\n", "\x00\x01\x02"])
def test_step_garbage_is_a_file_format_error(tmp_path, text):
    path = tmp_path / "g.stp"
    path.write_bytes(text.encode("latin-1"))
    with pytest.raises(GeomkitError):
        read_step(path)
