"""Shared pieces of the command line: input loading, argument types, progress bars."""

from __future__ import annotations

import argparse
import sys

from ..errors import InvalidInputError

def _load_input(name: str, skip_invalid: bool = False, skip_unsupported: bool = False):
    """Surfaces from a file path (JSON, IGES, STEP), or from a bundled sample name."""
    from pathlib import Path

    from .. import load_case, samples

    try:
        exists = Path(name).exists()
    except OSError:  # e.g. a name too long for the file system: load_case reports it
        exists = False
    if not exists and name in samples.names():
        return samples.load_case(name)
    ext = Path(name).suffix.lower()
    if ext in (".igs", ".iges"):
        from ..io import Case
        from ..iges import read_iges

        res = read_iges(name, skip_invalid=skip_invalid, skip_unsupported=skip_unsupported)
        _warn_skipped(res.skipped)
        return Case(Path(name).stem, res.surfaces, skipped=list(res.skipped))
    if ext in (".stp", ".step"):
        from ..io import Case
        from ..step import read_step

        res = read_step(name, skip_invalid=skip_invalid, skip_unsupported=skip_unsupported)
        _warn_skipped(res.skipped)
        return Case(Path(name).stem, res.surfaces, skipped=list(res.skipped))
    return load_case(name)


def _warn_skipped(skipped):
    if skipped:
        print(f"geomkit: warning: {len(skipped)} face(s) skipped, first: {skipped[0]}",
              file=sys.stderr)


def _progress(label: str):
    """A ``progress(done, total)`` callable drawing a rich bar on stderr, or None when
    stderr is not a terminal (pipes and CI logs stay clean)."""
    if not sys.stderr.isatty():
        return None, None
    from rich.console import Console
    from rich.progress import Progress

    prog = Progress(console=Console(stderr=True), transient=True)
    task = prog.add_task(label, total=None)
    prog.start()

    def update(done, total):
        prog.update(task, completed=done, total=total)

    return update, prog


def _positive_or_zero(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number >= 0, got {text!r}") from None
    if not (value >= 0) or value == float("inf"):
        raise argparse.ArgumentTypeError(f"must be a finite number >= 0, got {text!r}")
    return value


def _tolerance(values):
    if values is None:
        return None
    if len(values) == 1:
        t = abs(values[0])
        return (-t, t)
    if len(values) == 2:
        lo, hi = values
        if not lo <= hi:
            raise InvalidInputError(f"lower {lo:g} > upper {hi:g}", "--tolerance")
        return (lo, hi)
    raise InvalidInputError("give T (band -T..T) or LOWER UPPER", "--tolerance")


def _load_points(path):
    from ..points_io import read_points

    return read_points(path)


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


