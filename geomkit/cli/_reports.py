"""``--report {html,pdf}`` on the deviation, section and clearance commands (and
``--scan`` on section): the options, the file names to check before the work, and the
call that writes the reports at the end of a job."""

from __future__ import annotations

import argparse

from geomkit.report.jobs import REPORT_KINDS, parse_kinds, report_files, write_reports
from geomkit.cli._common import _tolerance

JOBS = ("deviation", "section", "clearance")


def _kinds(text: str) -> str:
    try:
        parse_kinds([text])
    except Exception as exc:
        raise argparse.ArgumentTypeError(str(exc).split(": ", 1)[-1]) from None
    return text


def add_options(sub) -> None:
    """Add ``--report`` to the job parsers of ``sub`` and ``--scan`` to section."""
    for job in JOBS:
        p = sub.choices.get(job)
        if p is None:
            continue
        p.add_argument("--report", action="append", type=_kinds, default=None,
                       metavar="|".join(REPORT_KINDS),
                       help="also write an interactive HTML report (one self-contained "
                            "file) and/or a PDF summary: html, pdf or html,pdf "
                            "(repeatable; default none)")
    p = sub.choices.get("section")
    if p is not None:
        p.add_argument("--scan", default=None, metavar="POINTS",
                       help="with --report html: measured points (CSV/XYZ or STL/PLY) near "
                            "the planes drawn as deviation whiskers")
        p.add_argument("--scan-probe-radius", type=float, default=0.0, metavar="R",
                       help="the --scan points are probe-ball centres of radius R")
        p.add_argument("--tolerance", type=float, nargs="+", metavar="T", default=None,
                       help="with --scan: tolerance band of the whiskers, T (meaning "
                            "-T..T) or LOWER UPPER")


def names(args, job: str) -> list[str]:
    """Report file names for ``prepare_outputs`` (reads ``--scan`` now, so a bad file
    is reported before the work)."""
    kinds = parse_kinds(getattr(args, "report", None))
    if job == "section" and getattr(args, "scan", None):
        from geomkit.errors import InvalidInputError
        from geomkit.exchange.points import read_points

        if "html" not in kinds:
            raise InvalidInputError("the scan is drawn in the HTML report: add --report "
                                    "html", "--scan")
        r = args.scan_probe_radius
        if not (r >= 0 and r != float("inf")):
            raise InvalidInputError(f"must be a finite number >= 0, got {r}",
                                    "--scan-probe-radius")
        args._report_tolerance = _tolerance(args.tolerance)
        args._report_scan = read_points(args.scan).points
    elif job == "section" and getattr(args, "tolerance", None) is not None:
        from geomkit.errors import InvalidInputError

        raise InvalidInputError("the tolerance band is for the --scan whiskers: add --scan "
                                "POINTS --report html", "--tolerance")
    return report_files(job, kinds)


def write(args, job: str, targets: dict, **data) -> list[str]:
    """Write the reports asked for by ``--report``; returns their paths as strings."""
    kinds = parse_kinds(getattr(args, "report", None))
    if not kinds:
        return []
    if job == "section":
        data.setdefault("scan", getattr(args, "_report_scan", None))
        data.setdefault("probe_radius", getattr(args, "scan_probe_radius", 0.0))
        data.setdefault("tolerance", getattr(args, "_report_tolerance", None))
    return [str(p) for p in write_reports(job, kinds, targets,
                                          overwrite=getattr(args, "overwrite", False),
                                          **data)]
