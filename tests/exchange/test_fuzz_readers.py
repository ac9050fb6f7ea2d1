"""Mutation fuzz of every reader through the Python API: each mutated file is read or
raises a :class:`~geomkit.GeomkitError` subclass with a message; nothing else escapes,
no input is modified.  Seeded (the same inputs every run), a few hundred inputs.

Mutations: a byte replaced, a run deleted, duplicated or inserted, the file cut, a
digit made a letter or punctuation and the reverse (entity names misspelt, numbers
broken, references emptied).  STEP is read with geomkit's own reader here (the hand-off
of what it cannot convert to Open CASCADE, in a child process, is tested in
``tests/cad/test_step_native.py``)."""

from __future__ import annotations

import hashlib
import shutil
import warnings

import numpy as np
import pytest

import geomkit
from geomkit.cad.step import read_step
from geomkit.errors import GeomkitError
from geomkit.exchange.scans import iter_scan
from helpers.igeswrite import write_iges
from helpers.paths import DATA

PER_FILE = 24


def _bases(folder):
    rng = np.random.default_rng(0)
    P = rng.normal(size=(60, 3))
    np.save(folder / "pts.npy", P)
    np.savetxt(folder / "pts.csv", P, delimiter=",", header="x,y,z", comments="")
    np.savetxt(folder / "pts.xyz", P)
    head = "ply\nformat {} 1.0\nelement vertex 60\nproperty float x\nproperty float y\n" \
           "property float z\nend_header\n"
    (folder / "a.ply").write_bytes(head.format("ascii").encode() + "".join(
        " ".join(f"{v:.6f}" for v in r) + "\n" for r in P).encode())
    (folder / "b.ply").write_bytes(head.format("binary_little_endian").encode()
                                   + P.astype("<f4").tobytes())
    import trimesh
    trimesh.creation.icosphere(1).export(folder / "m.stl")
    shutil.copy(DATA / "cases" / "plate_with_hole.json", folder / "case.json")
    shutil.copy(DATA / "parts" / "nx9_face_recognition_ap214.stp", folder / "part.stp")
    U, cp = [0, 0, 1, 1], [0, 0, 0, 1, 0, 0, 0, 1, 0, 1, 1, 1]
    write_iges(folder / "s.igs", [(128, [1, 1, 1, 1, 0, 0, 1, 0, 0, *U, *U, 1, 1, 1, 1,
                                         *cp, 0, 1, 0, 1])])
    return sorted(p for p in folder.iterdir())


def _read(path):
    if path.suffix == ".stp":
        return len(read_step(path, reader="geomkit").surfaces)
    if path.suffix in (".json", ".igs"):
        return len(geomkit.load_case(path).surfaces)
    return sum(1 for _ in iter_scan(path, 16))


def _mutate(data: bytes, rng) -> bytes:
    data = bytearray(data)
    i = int(rng.integers(len(data)))
    op = int(rng.integers(6))
    if op == 0:
        data[i] = int(rng.integers(256))
    elif op == 1:
        del data[i:i + int(rng.integers(1, 64))]
    elif op == 2:
        data[i:i] = data[i:i + int(rng.integers(1, 64))]
    elif op == 3:
        data = data[:i]
    elif op == 4:
        data[i:i] = rng.integers(0, 256, int(rng.integers(1, 16))).astype(np.uint8).tobytes()
    else:
        c = bytes(data[i:i + 1])
        pool = b"x.-e ,;()#'" if c.isdigit() else b"0123456789XZ_ " if c.isalpha() \
            else b"0123456789(),;'#. "
        data[i] = pool[int(rng.integers(len(pool)))]
    return bytes(data)


def test_mutated_files_read_or_raise_a_geomkit_error(tmp_path):
    base = tmp_path / "base"
    base.mkdir()
    rng = np.random.default_rng(20261127)
    escaped = []
    for src in _bases(base):
        raw = src.read_bytes()
        for k in range(PER_FILE):
            data = _mutate(raw, rng)
            if rng.random() < 0.3 and data:
                data = _mutate(data, rng)
            path = tmp_path / f"m{k}{src.suffix}"
            path.write_bytes(data)
            digest = hashlib.sha256(data).hexdigest()
            try:
                with warnings.catch_warnings():
                    warnings.simplefilter("ignore")
                    _read(path)
            except GeomkitError as exc:
                assert str(exc).strip(), (src.name, k)
            except Exception as exc:  # noqa: BLE001 - what the test looks for
                escaped.append(f"{src.name} #{k}: {type(exc).__name__}: {exc}")
            assert hashlib.sha256(path.read_bytes()).hexdigest() == digest
    assert not escaped, "\n".join(escaped[:10])


@pytest.mark.parametrize("text", ["", "ISO-10303-21;\nHEADER;\nENDSEC;\nDATA;\n#1=X(;\n"
                                  "ENDSEC;\nEND-ISO-10303-21;\n", "\x00\x01\x02"])
def test_step_garbage_is_a_file_format_error(tmp_path, text):
    path = tmp_path / "g.stp"
    path.write_bytes(text.encode("latin-1"))
    with pytest.raises(GeomkitError):
        read_step(path)
