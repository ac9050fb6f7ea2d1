"""The jobs run interactively: stderr on a pseudo-terminal (Python's ``pty``), where the
progress bar is drawn.  Each job must draw its progress, exit 0 and write its outputs,
with rich (a declared dependency) and, if rich is missing from an install, with the
plain fallback.  The tests without a terminal never reach this code path; before the
fix every job here exited 3 (``No module named 'rich'``) when rich was absent."""

from __future__ import annotations

import ast
import json
import os
import re
import select
import subprocess
import sys
import time

import pytest

from helpers.clihelp import write_rows
from helpers.paths import ROOT

pty = pytest.importorskip("pty", reason="needs a POSIX pseudo-terminal")

HIDE_RICH = ("import sys; sys.modules['rich'] = None; from geomkit.cli import main; "
             "sys.exit(main())")


def run_on_tty(argv, cwd, hide_rich=False, timeout=300):
    """Run ``geomkit ARGV`` with stderr on a pseudo-terminal; returns
    ``(returncode, stdout, terminal text)``."""
    master, slave = pty.openpty()
    env = dict(os.environ, PYTHONPATH=str(ROOT), TERM="xterm", COLUMNS="100")
    cmd = ([sys.executable, "-c", HIDE_RICH] if hide_rich
           else [sys.executable, "-m", "geomkit"]) + [str(a) for a in argv]
    p = subprocess.Popen(cmd, cwd=cwd, env=env, stdin=subprocess.DEVNULL,
                         stdout=subprocess.PIPE, stderr=slave)
    os.close(slave)
    chunks, t_end = [], time.monotonic() + timeout
    try:
        while time.monotonic() < t_end:
            ready, _, _ = select.select([master], [], [], 0.5)
            if ready:
                try:
                    data = os.read(master, 65536)
                except OSError:  # EIO: the child closed the terminal
                    break
                if not data:
                    break
                chunks.append(data)
            elif p.poll() is not None:
                break
        else:
            p.kill()
            pytest.fail(f"{argv} did not finish in {timeout} s")
        out = p.stdout.read().decode()
        rc = p.wait(timeout=30)
    finally:
        os.close(master)
        p.stdout.close()
    return rc, out, b"".join(chunks).decode("utf-8", "replace")


@pytest.fixture(scope="module")
def inputs(tmp_path_factory):
    d = tmp_path_factory.mktemp("tty")
    # points 0.5 above / below the torus top (z = 5 on the circle of radius 20)
    pts = write_rows(d / "pts.xyz", [[20, 0, 5.5], [0, 20, 4.5], [-20, 0, 5.25],
                                 [0, -20, 5.0]])
    path = write_rows(d / "path.xyz", [[-30, 0, 12], [30, 0, 12], [30, 0, 20]])
    return d, pts, path


JOBS = {
    "deviation": (lambda pts, path, out: ["deviation", "torus", pts, "-o", out,
                                          "--no-plots"],
                  "projecting points", ["deviation.csv", "summary.json"]),
    "distance": (lambda pts, path, out: ["distance", "torus", pts, "-o", out / "d.csv"],
                 "projecting points", ["d.csv"]),
    "section": (lambda pts, path, out: ["section", "torus", "--plane", "0", "0", "1", "-1",
                                        "--step", "1", "--count", "2", "--formats",
                                        "csv,dxf", "-o", out],
                "sectioning", ["section_000.csv", "section_000.dxf", "section_001.csv",
                               "section_001.dxf", "section_summary.json"]),
    "clearance": (lambda pts, path, out: ["clearance", "torus", path, "--stylus",
                                          "1,0.5,5", "--no-plots", "-o", out],
                  "checking moves", ["clearance.csv", "clearance_summary.json"]),
}


@pytest.mark.parametrize("hide_rich", [False, True], ids=["rich", "without-rich"])
@pytest.mark.parametrize("job", list(JOBS))
def test_job_on_a_terminal_draws_progress_and_writes(inputs, tmp_path, job, hide_rich):
    d, pts, path = inputs
    argv, label, files = JOBS[job]
    out = tmp_path / "out"
    if job == "distance":
        out.mkdir()
    rc, stdout, tty = run_on_tty(argv(pts, path, out), tmp_path, hide_rich)
    assert rc == 0, (stdout, tty)
    assert "error" not in tty, tty
    assert label in tty, f"no progress drawn: {tty!r}"
    assert sorted(p.name for p in out.iterdir()) == sorted(files)
    assert stdout.strip(), "the result is printed on stdout"


def test_the_cli_imports_only_declared_core_dependencies():
    """Every third-party module the command line imports (at any depth of its own
    code) is a core dependency in pyproject.toml: rich was not."""
    try:
        import tomllib
    except ImportError:  # Python 3.10
        tomllib = pytest.importorskip("tomli")
    from importlib.metadata import packages_distributions

    doc = tomllib.loads((ROOT / "pyproject.toml").read_text())
    name = (lambda req: re.split(r"[<>=!~\[; ]", req, maxsplit=1)[0].lower()
            .replace("_", "-"))
    core = {name(r) for r in doc["project"]["dependencies"]}
    dists = packages_distributions()
    used = set()
    for f in sorted((ROOT / "geomkit" / "cli").glob("*.py")):
        for node in ast.walk(ast.parse(f.read_text())):
            if isinstance(node, ast.Import):
                used |= {a.name.split(".")[0] for a in node.names}
            elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
                used.add(node.module.split(".")[0])
    third = {m for m in used if m not in sys.stdlib_module_names and m != "geomkit"}
    assert "rich" in third  # the progress bar
    missing = {m for m in third
               if not {name(d) for d in dists.get(m, [m])} & core}
    assert not missing, f"imported by geomkit/cli but not declared: {sorted(missing)}"
