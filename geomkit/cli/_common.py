"""Shared pieces of the command line: input loading, argument types, output targets,
progress bars and the one-line argument errors."""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from geomkit.errors import InvalidInputError


class Parser(argparse.ArgumentParser):
    """An ArgumentParser whose errors are one line ``geomkit: error: ...`` and exit 2
    (argparse prints a usage block otherwise); sub-parsers inherit the class."""

    last_error: str | None = None
    """The message of the last argument error (``--json`` prints it as JSON)."""

    def error(self, message):
        words = self.prog.split()
        cmd = f"{' '.join(words[1:])}: " if len(words) > 1 else ""
        message = " ".join(str(message).split())
        if not cmd and message.endswith("required: command"):
            message = "no command given (geomkit --help lists them)"
        Parser.last_error = f"{cmd}{message}"
        self.exit(2, f"geomkit: error: {cmd}{message}\n")


# --------------------------------------------------------------- warnings, JSON
WARNINGS: list[str] = []
"""The warnings of this run, in order (:func:`show_warning` appends; ``--json``
output carries them as its ``warnings`` field)."""


def show_warning(message, category, filename, lineno, file=None, line=None):
    """``warnings.showwarning`` of the command line: one line ``geomkit: warning:
    ...`` on stderr (not Python's two-line form with the source), kept for ``--json``."""
    text = " ".join(str(message).split())
    WARNINGS.append(text)
    print(f"geomkit: warning: {text}", file=sys.stderr)


def emit_json(obj) -> None:
    """Print a command's ``--json`` result on stdout, with the run's warnings (the
    ``warnings`` field) when there were any."""
    from geomkit.outputs import json_safe

    if isinstance(obj, dict) and WARNINGS:
        obj = {**obj, "warnings": list(WARNINGS)}
    print(json.dumps(json_safe(obj), indent=1, default=str))


# ----------------------------------------------------------------------- inputs
def _load_input(name: str, skip_invalid: bool = False, units: str | None = None,
                skip_unsupported: bool = False):
    """Surfaces from a file path (JSON, IGES, STEP), or from a bundled sample name.

    ``units`` (from ``--units``) overrides the units the file states; the case's
    ``units`` is None when neither says.  ``skip_unsupported`` reads a CAD file on
    without the faces it cannot convert; they are listed in ``case.skipped``."""
    from geomkit import load_case, samples
    try:
        exists = Path(name).exists()
    except OSError:  # e.g. a name too long for the file system: load_case reports it
        exists = False
    if not exists and name in samples.names():
        case = samples.load_case(name)
    else:
        case = load_case(name, skip_invalid=skip_invalid, skip_unsupported=skip_unsupported)
        _warn_skipped(case.skipped)
    if units is not None:
        case.units = units
    return case


def _warn_skipped(skipped):
    if skipped:
        print(f"geomkit: warning: partial model: {len(skipped)} face(s) left out: "
              + "; ".join(str(s) for s in skipped[:3])
              + (f"; ... ({len(skipped) - 3} more in the summary)" if len(skipped) > 3 else ""),
              file=sys.stderr)


def _model_info(case):
    """What every report says of the model: ``(info, note)``.

    ``info`` goes into the summary JSON (faces read, faces left out with their ids and
    reasons, ``complete``); ``note`` is None for a whole model and otherwise a line for
    the console, plot titles and report headers, so a result computed on part of a
    model never looks complete."""
    skipped = [str(s) for s in getattr(case, "skipped", None) or []]
    n = len(case.surfaces)
    info = {"faces": n, "faces_left_out": len(skipped), "complete": not skipped}
    if not skipped:
        return info, None
    info["left_out"] = skipped
    ids = [s.split(":", 1)[0] for s in skipped]
    shown = ", ".join(ids[:6]) + (", ..." if len(ids) > 6 else "")
    note = (f"PARTIAL MODEL: {len(skipped)} of {n + len(skipped)} faces left out "
            f"(--skip-unsupported: {shown})")
    return info, note


def _load_points(path):
    from geomkit.exchange.points import read_points

    return read_points(path)


def _unit(units) -> str:
    """The unit as printed: ``mm`` or ``model units``."""
    from geomkit.units import unit_label

    return unit_label(units)


# ---------------------------------------------------------------------- outputs
class Outputs:
    """Report files ``names`` in ``folder``, checked now, the folder created later.

    The check (folder writable, nothing overwritten, no input among the targets) runs
    before any work; :meth:`create` makes the folder only when the run is about to
    write, so a run that fails on its inputs or in its work leaves nothing behind."""

    def __init__(self, folder, names, overwrite: bool = False, inputs=()):
        from geomkit.report.files import prepare_outputs

        self.folder, self.names = Path(folder), list(names)
        self.overwrite, self.inputs = overwrite, list(inputs)
        d = self.folder
        if d.exists():
            prepare_outputs(d, self.names, overwrite, inputs=self.inputs)  # creates nothing
            return
        anc = d.parent
        while not anc.exists() and anc != anc.parent:
            anc = anc.parent
        if not anc.is_dir():
            raise InvalidInputError(f"{d}: cannot write here ({anc} is a file, not a "
                                    "folder)", "output folder")
        prepare_outputs(anc, [], False)  # writable? (a temporary file, removed)

    def create(self) -> dict:
        """``{name: Path}``, the folder created if needed."""
        from geomkit.report.files import prepare_outputs

        return prepare_outputs(self.folder, self.names, self.overwrite, inputs=self.inputs)


def _file_target(path, overwrite: bool, inputs=(), option: str = "-o") -> Path:
    """Check an output file before the work: its folder must exist (it is not created
    for a file target) and be writable; an existing file needs ``--overwrite``; an
    input is never a target."""
    from geomkit.report.files import prepare_outputs

    p = Path(path)
    if p.is_dir():
        raise InvalidInputError(f"{p}: is a folder, expected a file name", option)
    parent = p.parent
    if not parent.is_dir():
        what = "is not a folder" if parent.exists() else "no such folder"
        raise InvalidInputError(f"{parent}: {what} (create it first)", option)
    return prepare_outputs(parent, [p.name], overwrite, inputs=inputs)[p.name]


# --------------------------------------------------------------------- progress
def _progress(label: str):
    """``(update, bar)``: ``update(done, total)`` draws a progress bar on stderr and
    ``bar.stop()`` removes it; ``(None, None)`` when stderr is not a terminal (pipes
    and CI logs stay clean).  rich draws the bar; without rich a plain one-line
    counter does."""
    try:
        if not sys.stderr.isatty():
            return None, None
    except (AttributeError, ValueError):  # a closed or replaced stderr
        return None, None
    try:
        from rich.console import Console
        from rich.progress import Progress
    except ImportError:
        bar = _PlainProgress(label)
        return bar.update, bar
    prog = Progress(console=Console(stderr=True), transient=True)
    task = prog.add_task(label, total=None)
    prog.start()

    def update(done, total):
        prog.update(task, completed=done, total=total)

    return update, prog


class _PlainProgress:
    """``label done/total`` rewritten in place on stderr (a terminal)."""

    def __init__(self, label):
        self.label, self.shown = label, False
        self._write(f"{label} ...")

    def _write(self, text):
        sys.stderr.write(f"\r{text}\x1b[K")
        sys.stderr.flush()
        self.shown = True

    def update(self, done, total):
        self._write(f"{self.label} {done}/{total}" if total else f"{self.label} {done}")

    def stop(self):
        if self.shown:
            sys.stderr.write("\r\x1b[K")
            sys.stderr.flush()
            self.shown = False


# ------------------------------------------------------------------ argument types
def _positive_or_zero(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number >= 0, got {text!r}") from None
    if not (value >= 0) or value == float("inf"):
        raise argparse.ArgumentTypeError(f"must be a finite number >= 0, got {text!r}")
    return value


def _tolerance(values):
    """``--tolerance T`` (band -T..T) or ``LOWER UPPER``: finite, of non-zero width."""
    import math

    if values is None:
        return None
    if not all(math.isfinite(v) for v in values):
        raise InvalidInputError(f"must be finite numbers, got {' '.join(map(str, values))}",
                                "--tolerance")
    if len(values) == 1:
        t = abs(values[0])
        if t == 0:
            raise InvalidInputError("must be > 0 (the band -T..T would be empty)",
                                    "--tolerance")
        return (-t, t)
    if len(values) == 2:
        lo, hi = values
        if not lo < hi:
            raise InvalidInputError(f"lower {lo:g} must be < upper {hi:g}", "--tolerance")
        return (lo, hi)
    raise InvalidInputError("give T (band -T..T) or LOWER UPPER", "--tolerance")


def _positive_float(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a positive number, got {text!r}") from None
    if not (value > 0) or value == float("inf"):
        raise argparse.ArgumentTypeError(f"must be a positive finite number, got {text!r}")
    return value


def _positive_int(text: str) -> int:
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a positive integer, got {text!r}") from None
    if value < 2:
        raise argparse.ArgumentTypeError(f"must be at least 2, got {value}")
    return value


def _units_arg(text: str) -> str:
    """``--units``: a length unit name (mm, cm, m, in, ft, um, ...)."""
    from geomkit.units import canonical_units

    try:
        return canonical_units(text)
    except InvalidInputError as exc:
        raise argparse.ArgumentTypeError(str(exc).removeprefix("units: ")) from None
