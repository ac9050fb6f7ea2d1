"""Every script in examples/ runs to completion, writing only into the folder it is
given (never into the current folder, e.g. the repository root)."""

from __future__ import annotations

import os
import subprocess
import sys

import pytest

from helpers.paths import ROOT
SCRIPTS = sorted((ROOT / "examples").glob("*.py"))


@pytest.mark.parametrize("script", SCRIPTS, ids=[s.name for s in SCRIPTS])
def test_example_runs(script, tmp_path):
    if script.name == "iges_deviation.py":
        pytest.importorskip("pyiges")
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    cwd, out = tmp_path / "cwd", tmp_path / "out"
    cwd.mkdir()
    r = subprocess.run([sys.executable, str(script), str(out)], cwd=cwd, env=env,
                       capture_output=True, text=True, timeout=600)
    assert r.returncode == 0, r.stderr[-2000:]
    assert r.stdout.strip(), "an example prints what it found"
    assert list(cwd.iterdir()) == [], "an example wrote into the current folder"
    if "prepare_outputs" in script.read_text():
        assert f"reports in {out}/" in r.stdout and any(out.iterdir())
