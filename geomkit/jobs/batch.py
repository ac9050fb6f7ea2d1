"""Streamed deviation reports on disk: one scan, or a folder of scans against one
nominal (one report folder per part plus a summary table of all parts).

A part's report folder holds ``deviation.csv`` (or ``deviation.parquet``) and
``summary.json``.  The per-point file is streamed into a temporary file renamed into
place only when the part succeeded; ``summary.json`` is written last, so a folder
with a summary holds a complete report.  The batch writes ``parts.csv`` (n, min, max,
rms, % in tolerance, pass/fail per part) and its own ``summary.json`` last.
"""

from __future__ import annotations

import csv
import io
from pathlib import Path

from geomkit.errors import GeomkitError, InvalidInputError
from geomkit.outputs import atomic_write
from geomkit.report.files import prepare_outputs, write_json
from geomkit.exchange.scans import is_scan_file
from geomkit.jobs.stream import stream_deviation

__all__ = ["deviation_report", "batch_deviation", "scan_files", "PART_COLUMNS"]

PART_COLUMNS = ("part", "file", "points", "valid", "min", "max", "mean", "rms",
                "pct_within", "pass", "error")


def scan_files(folder) -> list[Path]:
    """The scan files of a folder (sorted by name; hidden files skipped)."""
    d = Path(folder)
    files = sorted(p for p in d.iterdir()
                   if p.is_file() and not p.name.startswith(".") and is_scan_file(p))
    if not files:
        raise InvalidInputError(f"{d}: no scan files (.csv .xyz .txt .asc .pts .ply .npy "
                                ".las .laz .e57 .stl) in the folder", "points")
    return files


def report_names(fmt: str) -> list[str]:
    return [f"deviation.{fmt}", "summary.json"]


def deviation_report(surfaces, scan, folder, *, fmt="csv", overwrite=False, inputs=(),
                     extra=None, **kw) -> dict:
    """Stream one scan's deviation into ``folder`` (see the module doc); returns the
    summary written.  Keywords as :func:`geomkit.jobs.stream.stream_deviation`."""
    names = report_names(fmt)
    targets = prepare_outputs(folder, names, overwrite, inputs=[scan, *inputs])
    result = {}

    def job(fh):
        result.update(stream_deviation(surfaces, scan, fh, fmt=fmt, **kw))

    f = atomic_write(targets[names[0]], job)
    summary = {**(extra or {}), "points_file": str(scan), **result,
               "files": [str(f), str(targets["summary.json"])],
               "plots": "not drawn for streamed runs"}
    write_json(summary, targets["summary.json"], overwrite)
    return summary


def _part_row(name, scan, st, tol):
    row = {"part": name, "file": str(scan), "points": st["points"], "valid": st["valid"],
           "min": st["min"], "max": st["max"], "mean": st["mean"], "rms": st["rms"],
           "pct_within": st.get("pct_within"), "pass": "", "error": ""}
    if tol is not None:
        ok = st["valid"] > 0 and st["within"] == st["valid"] and \
            st["beyond"] == 0 and st["failed"] == 0
        row["pass"] = "pass" if ok else "fail"
    return row


def batch_deviation(surfaces, folder, out, *, fmt="csv", overwrite=False, inputs=(),
                    extra=None, progress=None, **kw) -> dict:
    """Every scan of ``folder`` against the same surfaces: ``out/<scan name>/`` report
    per part, ``out/parts.csv`` and ``out/summary.json`` (last).

    A part that fails (bad file, no valid point, or any other error in its run, an
    internal one included) is listed with its one-line reason and its folder holds no
    report; the batch goes on.  A part passes when a tolerance is
    given, it has valid points, every valid point is within the tolerance and no point
    is beyond ``max_distance`` or failed.

    Returns
    -------
    dict
        ``parts`` (the table rows), ``passed``, ``failed``, ``errors``.
    """
    files = scan_files(folder)
    tol = kw.get("tolerance")
    stems = [p.stem for p in files]
    dup = {s for s in stems if stems.count(s) > 1}
    names = [p.name if p.stem in dup else p.stem for p in files]
    outs = prepare_outputs(out, ["parts.csv", "summary.json"], overwrite, inputs=inputs)
    for n in names:  # check every part's folder before any work
        prepare_outputs(Path(out) / n, report_names(fmt), overwrite, inputs=[*inputs,
                                                                            *files])
    rows = []
    for k, (scan, name) in enumerate(zip(files, names)):
        try:
            st = deviation_report(surfaces, scan, Path(out) / name, fmt=fmt,
                                  overwrite=overwrite, inputs=inputs, extra=extra, **kw)
            rows.append(_part_row(name, scan, st, tol))
        except Exception as exc:  # noqa: BLE001 - one part never sinks the batch
            try:  # the part's folder, created by the check above, holds nothing
                (Path(out) / name).rmdir()
            except OSError:
                pass
            why = " ".join(str(exc).split())
            if not isinstance(exc, (GeomkitError, OSError)):
                why = f"internal error {type(exc).__name__}: {why}"
            rows.append({c: "" for c in PART_COLUMNS} | {
                "part": name, "file": str(scan), "pass": "fail" if tol else "",
                "error": why})
        if progress is not None:
            progress(k + 1, len(files))
    buf = io.StringIO()
    w = csv.DictWriter(buf, fieldnames=PART_COLUMNS, lineterminator="\n")
    w.writeheader()
    for r in rows:
        w.writerow({c: ("" if r[c] is None else r[c]) for c in PART_COLUMNS})
    data = buf.getvalue().encode()
    if outs["parts.csv"].exists() and not overwrite:
        raise FileExistsError(f"{outs['parts.csv']}: exists; pass --overwrite to replace it")
    atomic_write(outs["parts.csv"], lambda fh: fh.write(data))
    summary = {**(extra or {}), "folder": str(folder), "parts": rows,
               "passed": sum(r["pass"] == "pass" for r in rows),
               "failed": sum(r["pass"] == "fail" for r in rows),
               "errors": sum(bool(r["error"]) for r in rows),
               "files": [str(outs["parts.csv"]), str(outs["summary.json"])]}
    write_json(summary, outs["summary.json"], overwrite)
    return summary
