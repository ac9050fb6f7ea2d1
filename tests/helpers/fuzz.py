"""Mutation fuzz of every reader, through the Python API and through the command line.

Base files: one small valid file per reader (IGES, STEP, geomkit-case JSON, geomdl
JSON, CSV, XYZ, PLY ASCII and binary, STL, NPY, LAS, LAZ, E57).  Each input is a base
file mutated once or twice (a byte replaced, a run deleted, duplicated or inserted,
the file cut, a digit made a letter or punctuation and the reverse: entity names
misspelt, numbers broken, references emptied), seeded: the same inputs every run.

What must hold for every input:

* API (:func:`read_api`): the file is read, or a :class:`~geomkit.GeomkitError`
  subclass with a message is raised; nothing else escapes.
* CLI (:func:`check_cli`): ``geomkit info FILE --json`` for models,
  ``geomkit deviation freeform_1 FILE -o OUT --json --no-plots`` for points: exit 0,
  or exit 2 with one ``geomkit: error:`` line on stderr; stdout parses as JSON; no
  traceback; no output folder left behind by a failed run.
* The input is never modified.

The suite runs a few hundred inputs in process (``tests/exchange/test_fuzz_readers.py``).
The long run executes each input in worker processes, so that a crash (a signal) or a
hang (no answer within ``--timeout`` seconds) is caught and named as well::

    python tests/helpers/fuzz.py --count 10000 --seed 1 --out /tmp/fuzz

prints a summary line per base file and exits 1 when any input failed (the failures
are listed with their files kept under ``--out``).  docs/fuzzing.md has the record.
"""

from __future__ import annotations

import contextlib
import hashlib
import io
import json
import shutil
import sys
import warnings
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
DATA = HERE.parent / "data"
MODELS = (".stp", ".igs", ".json")
SAMPLE = "freeform_1"


# ------------------------------------------------------------------ inputs
def make_bases(folder: Path) -> list[Path]:
    """One small valid file per reader in ``folder``."""
    folder.mkdir(parents=True, exist_ok=True)
    rng = np.random.default_rng(0)
    P = rng.normal(size=(60, 3)) * 10 + [50, 50, 0]
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
    _geomdl_json(folder / "geomdl.json")
    _iges(folder / "s.igs")
    for ext in (".las", ".laz"):
        _las(folder / f"p{ext}", P)
    _e57(folder / "p.e57", P, rng)
    return sorted(p for p in folder.iterdir() if p.is_file())


def _iges(path):
    sys.path.insert(0, str(HERE.parent))
    from helpers.igeswrite import write_iges

    U, cp = [0, 0, 1, 1], [0, 0, 0, 1, 0, 0, 0, 1, 0, 1, 1, 1]
    write_iges(path, [(128, [1, 1, 1, 1, 0, 0, 1, 0, 0, *U, *U, 1, 1, 1, 1,
                             *cp, 0, 1, 0, 1])])


def _geomdl_json(path):
    from geomdl import BSpline, exchange

    s = BSpline.Surface()
    s.degree_u = s.degree_v = 2
    s.ctrlpts_size_u = s.ctrlpts_size_v = 3
    s.ctrlpts = [[i * 10.0, j * 10.0, float((i * j) % 2)] for i in range(3) for j in range(3)]
    s.knotvector_u = s.knotvector_v = [0, 0, 0, 1, 1, 1]
    exchange.export_json(s, str(path))


def _las(path, P):
    import laspy

    h = laspy.LasHeader(point_format=3, version="1.2")
    h.scales = [1e-4] * 3
    h.offsets = P.min(axis=0)
    las = laspy.LasData(h)
    las.x, las.y, las.z = P[:, 0], P[:, 1], P[:, 2]
    las.intensity = np.arange(len(P), dtype=np.uint16)
    las.write(str(path))


def _e57(path, P, rng):
    import pye57

    e = pye57.E57(str(path), mode="w")
    e.write_scan_raw({"cartesianX": P[:, 0].copy(), "cartesianY": P[:, 1].copy(),
                      "cartesianZ": P[:, 2].copy(),
                      "intensity": rng.random(len(P)).astype("f"),
                      "colorRed": rng.integers(0, 255, len(P)).astype("B"),
                      "colorGreen": rng.integers(0, 255, len(P)).astype("B"),
                      "colorBlue": rng.integers(0, 255, len(P)).astype("B")})
    e.close()


def mutate(data: bytes, rng) -> bytes:
    data = bytearray(data)
    if not data:
        return bytes(data)
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


def inputs(bases, per_file: int, seed: int):
    """``(base, k, bytes)`` for ``per_file`` mutations of each base, seeded."""
    rng = np.random.default_rng(seed)
    for src in bases:
        raw = src.read_bytes()
        for k in range(per_file):
            data = mutate(raw, rng)
            if rng.random() < 0.3 and data:
                data = mutate(data, rng)
            yield src, k, data


# ------------------------------------------------------------------ checks
def read_api(path: Path):
    """Read ``path`` with the reader its suffix names (STEP with geomkit's own)."""
    import geomkit
    from geomkit.cad.step import read_step
    from geomkit.exchange.scans import iter_scan

    if path.suffix == ".stp":
        return len(read_step(path, reader="geomkit").surfaces)
    if path.suffix in (".json", ".igs"):
        return len(geomkit.load_case(path).surfaces)
    return sum(1 for _ in iter_scan(path, 16))


def check_api(path: Path) -> str | None:
    """None when the API read or raised a GeomkitError with a message, else what
    escaped."""
    from geomkit.errors import GeomkitError

    digest = hashlib.sha256(path.read_bytes()).hexdigest()
    problem = None
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            read_api(path)
    except GeomkitError as exc:
        if not str(exc).strip():
            problem = f"{type(exc).__name__} without a message"
    except Exception as exc:  # noqa: BLE001 - what the fuzz looks for
        problem = f"API: {type(exc).__name__}: {' '.join(str(exc).split())[:200]}"
    if hashlib.sha256(path.read_bytes()).hexdigest() != digest:
        problem = "input modified"
    return problem


def cli_args(path: Path, out: Path) -> list[str]:
    if path.suffix in MODELS:
        return ["info", str(path), "--json"]
    return ["deviation", SAMPLE, str(path), "-o", str(out), "--json", "--no-plots"]


def check_cli(path: Path, out: Path) -> str | None:
    """None when ``geomkit`` (in this process) ended as it must on ``path``, else
    what went wrong."""
    from geomkit.cli import main

    digest = hashlib.sha256(path.read_bytes()).hexdigest()
    so, se = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(so), contextlib.redirect_stderr(se):
        try:
            code = main(cli_args(path, out))
        except BaseException as exc:  # noqa: BLE001 - main must not raise
            code = f"raised {type(exc).__name__}: {exc}"
    err = se.getvalue()
    lines = [ln for ln in err.splitlines() if ln.strip()]
    errors = [ln for ln in lines if ln.startswith("geomkit: error:")]
    problem = None
    if code not in (0, 2):
        problem = f"exit {code}: {err.strip()[:200]}"
    elif "Traceback" in err or any(not ln.startswith("geomkit: ") for ln in lines):
        problem = f"stderr not geomkit's lines: {err.strip()[:200]}"
    elif code == 2 and len(errors) != 1:
        problem = f"exit 2 with {len(errors)} error lines"
    else:
        try:
            json.loads(so.getvalue())
        except ValueError:
            problem = f"stdout is not JSON: {so.getvalue()[:120]!r}"
    if code == 2 and out.exists():
        problem = problem or "a failed run left its output folder"
    if hashlib.sha256(path.read_bytes()).hexdigest() != digest:
        problem = "input modified"
    shutil.rmtree(out, ignore_errors=True)
    return problem


def check(path: Path, out: Path) -> str | None:
    return check_api(path) or check_cli(path, out)


# ------------------------------------------------------------------ long run
def _worker() -> int:
    """Read input paths on stdin, answer one JSON line each on the real stdout (file
    descriptor 1 itself goes to /dev/null: a library's C code printing there cannot
    garble the answers)."""
    import os

    real = os.fdopen(os.dup(1), "w")
    os.dup2(os.open(os.devnull, os.O_WRONLY), 1)
    sys.stdout = open(os.devnull, "w")
    for line in sys.stdin:
        path = Path(line.strip())
        problem = check(path, path.with_name(path.name + ".out"))
        real.write(json.dumps({"path": str(path), "problem": problem}) + "\n")
        real.flush()
    return 0


class _Worker:
    def __init__(self):
        import subprocess

        self.proc = subprocess.Popen([sys.executable, __file__, "--worker"],
                                     stdin=subprocess.PIPE, stdout=subprocess.PIPE,
                                     stderr=subprocess.DEVNULL, text=True, bufsize=1)

    def ask(self, path: Path, timeout: float) -> str | None:
        import select

        self.proc.stdin.write(f"{path}\n")
        self.proc.stdin.flush()
        ready, _, _ = select.select([self.proc.stdout], [], [], timeout)
        if not ready:
            self.proc.kill()
            self.proc.wait()
            return f"hang: no answer within {timeout:g} s"
        line = self.proc.stdout.readline()
        if not line:
            code = self.proc.wait()
            return f"crash: the process ended with exit {code}"
        return json.loads(line)["problem"]

    def alive(self) -> bool:
        return self.proc.poll() is None

    def close(self):
        if self.alive():
            self.proc.stdin.close()
            self.proc.wait()


def long_run(count: int, seed: int, out: Path, workers: int = 2,
             timeout: float = 120.0) -> int:
    import threading
    import time
    from collections import Counter, defaultdict

    out.mkdir(parents=True, exist_ok=True)
    bases = make_bases(out / "base")
    per_file = -(-count // len(bases))
    todo = []
    for src, k, data in inputs(bases, per_file, seed):
        path = out / "in" / src.stem / f"{k:05d}{src.suffix}"
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_bytes(data)
        todo.append((src.name, path))
    lock = threading.Lock()
    results = []
    t0 = time.time()

    def run():
        w = _Worker()
        while True:
            with lock:
                if not todo:
                    break
                name, path = todo.pop()
            problem = w.ask(path, timeout)
            if not w.alive():
                w = _Worker()
            with lock:
                results.append((name, path, problem))
                if len(results) % 500 == 0:
                    print(f"{len(results)} inputs, {time.time() - t0:.0f} s, "
                          f"{sum(1 for r in results if r[2])} failed", flush=True)
        w.close()

    threads = [threading.Thread(target=run) for _ in range(workers)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    seconds = time.time() - t0
    totals, bad = Counter(), defaultdict(list)
    for name, path, problem in results:
        totals[name] += 1
        if problem:
            bad[name].append((path, problem))
        else:
            path.unlink()
    for name in sorted(totals):
        print(f"{name:16s} {totals[name]:6d} inputs  {len(bad[name]):4d} failed")
    print(f"{len(results)} inputs (seed {seed}) in {seconds:.0f} s with {workers} workers: "
          f"{sum(len(v) for v in bad.values())} failed")
    for name in sorted(bad):
        for path, problem in bad[name][:20]:
            print(f"  {path}: {problem}")
    return 1 if bad else 0


def main(argv=None) -> int:
    import argparse

    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--count", type=int, default=10000)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--out", type=Path, default=Path("fuzz-run"))
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--timeout", type=float, default=120.0)
    ap.add_argument("--worker", action="store_true", help=argparse.SUPPRESS)
    a = ap.parse_args(argv)
    if a.worker:
        return _worker()
    return long_run(a.count, a.seed, a.out, a.workers, a.timeout)


if __name__ == "__main__":
    sys.exit(main())
