"""Helpers of the command-line tests: run ``python -m geomkit`` in a subprocess
(:func:`cli`) or ``geomkit.cli.main`` in process (:func:`run_main`), check one-line
errors, fingerprint input files, write point files."""

from __future__ import annotations

import hashlib
import os
import subprocess
import sys
from pathlib import Path

from helpers.paths import ROOT


def cli(*argv, cwd=None, timeout=300):
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    return subprocess.run([sys.executable, "-m", "geomkit", *map(str, argv)], cwd=cwd,
                          env=env, capture_output=True, text=True, timeout=timeout)


def run_main(capsys, *argv):
    """``geomkit.cli.main(argv)`` in process (arguments as strings): (rc, stdout,
    stderr) read from ``capsys``."""
    from geomkit.cli import main

    rc = main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return rc, out, err


def assert_one_line_error(r, *phrases):
    assert r.returncode == 2, (r.returncode, r.stdout, r.stderr)
    assert r.stderr.startswith("geomkit: error: "), r.stderr
    assert r.stderr.count("\n") == 1, f"not one line: {r.stderr!r}"
    assert "Traceback" not in r.stderr
    for ph in phrases:
        assert ph in r.stderr, (ph, r.stderr)


def digest(*paths):
    return {str(p): hashlib.sha256(Path(p).read_bytes()).hexdigest() for p in paths}


def write_rows(p: Path, rows):
    """Write ``rows`` of numbers to ``p`` as a whitespace-separated text file (one row
    a line, floats in ``repr``); returns ``p``."""
    p.write_text("".join(" ".join(repr(float(c)) for c in r) + "\n" for r in rows))
    return p
