"""Helpers of the end-to-end command-line tests: run ``python -m geomkit`` in a
subprocess, check one-line errors, fingerprint input files."""

from __future__ import annotations

import hashlib
import os
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def cli(*argv, cwd=None, timeout=300):
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    return subprocess.run([sys.executable, "-m", "geomkit", *map(str, argv)], cwd=cwd,
                          env=env, capture_output=True, text=True, timeout=timeout)


def assert_one_line_error(r, *phrases):
    assert r.returncode == 2, (r.returncode, r.stdout, r.stderr)
    assert r.stderr.startswith("geomkit: error: "), r.stderr
    assert r.stderr.count("\n") == 1, f"not one line: {r.stderr!r}"
    assert "Traceback" not in r.stderr
    for ph in phrases:
        assert ph in r.stderr, (ph, r.stderr)


def digest(*paths):
    return {str(p): hashlib.sha256(Path(p).read_bytes()).hexdigest() for p in paths}
