"""``geomkit inspect PART.stp POINTS``: every tolerance of the part's AP242 PMI
evaluated on measured points (:func:`geomkit.jobs.inspect.inspect_part`)."""

from __future__ import annotations

import argparse
import csv
import io
from pathlib import Path

from geomkit.cli import _reports
from geomkit.cli._common import Outputs, _load_input, _load_points, _model_info, emit_json
from geomkit.errors import FileFormatError, InvalidInputError

OUTPUTS = ("characteristics.csv", "summary.json")
CSV_COLUMNS = ("id", "type", "faces", "tolerance", "unit", "modifiers", "datums",
               "measured", "limit", "pass", "status", "points", "reason")


def add_parser(sub, common) -> None:
    p = sub.add_parser(
        "inspect", parents=[common],
        help="every tolerance of a STEP AP242 part's PMI evaluated on measured points",
        formatter_class=argparse.RawDescriptionHelpFormatter,
        description="Reads the geometric tolerances and datums of PART's semantic PMI, "
                    "assigns each measured point to a face (its 'face' column, or the "
                    "face of its exact foot), builds each datum reference frame from "
                    "the datum features' points and evaluates every characteristic.  "
                    "Writes characteristics.csv and summary.json (last) into the output "
                    "folder.  Exit 0 when every characteristic passes, 1 when one fails "
                    "or one could not be evaluated (verdict 'incomplete'), 2 on bad "
                    "input.",
        epilog="example:\n  geomkit sample part.stp --per-face 30 -o points.csv\n"
               "  geomkit inspect part.stp points.csv --report html -o inspection")
    p.add_argument("part", help="the part: a STEP file with AP242 semantic PMI")
    p.add_argument("points", help="measured points: CSV/XYZ (x y z [i j k] [face], named "
                                  "headers), PLY, STL, NPY, LAS/LAZ, E57")
    p.add_argument("-o", "--output", default=None,
                   help="report folder (default ./<points name>-inspection)")
    p.add_argument("--align", choices=("datums", "bestfit", "none"), default="datums",
                   help="datums: each characteristic in its measured datum reference "
                        "frame (default); bestfit: the points best-fitted to the part "
                        "first; none: the points are in CAD coordinates")
    p.add_argument("--max-distance", type=float, default=None, metavar="D",
                   help="points farther than D from every face are left out (default 2%% "
                        "of the part size; faces found by projection only)")
    p.add_argument("--ignore-face-column", action="store_true",
                   help="assign points to faces by projection even when the file has a "
                        "face column")
    p.add_argument("--report", action="append", type=_reports._kinds, default=None,
                   metavar="html|pdf",
                   help="also write an HTML report (one self-contained file) and/or a PDF "
                        "with the characteristic table and a colour map per "
                        "characteristic: html, pdf or html,pdf")
    p.set_defaults(func=_cmd_inspect)


def _csv_text(res) -> str:
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(CSV_COLUMNS)
    for c in res.characteristics:
        t = c.tolerance
        w.writerow([c.id, c.type, " ".join(map(str, c.faces)),
                    "" if t["value"] is None else repr(t["value"]), t["unit"] or "",
                    " ".join(t["modifiers"] + (["diameter"] if t["diameter"] else [])),
                    "|".join(c.datums), "" if c.measured is None else repr(c.measured),
                    "" if c.limit is None else repr(c.limit),
                    "" if c.passed is None else str(c.passed).lower(), c.status,
                    c.n_points, c.reason or ""])
    return buf.getvalue()


def _face_column(path, n, ignore):
    from geomkit.exchange.text import read_int_column

    if ignore:
        return None
    col = read_int_column(path, "face")
    if col is not None and col.shape[0] != n:
        raise FileFormatError(f"{path}: {col.shape[0]} face values for {n} points")
    return col


def _cmd_inspect(args) -> int:
    from geomkit.cad.steppmi import read_pmi
    from geomkit.jobs.inspect import inspect_part
    from geomkit.outputs import atomic_write
    from geomkit.report.files import write_json

    if args.max_distance is not None and not args.max_distance > 0:
        raise InvalidInputError(f"must be > 0, got {args.max_distance}", "--max-distance")
    if Path(args.part).suffix.lower() not in (".stp", ".step", ".p21"):
        raise InvalidInputError(f"{args.part}: the tolerances are read from a STEP "
                                "AP242 file (.stp / .step)", "part")
    case = _load_input(args.part, args.skip_invalid, args.units,
                       skip_unsupported=args.skip_unsupported)
    pmi = read_pmi(args.part)
    if not pmi.tolerances:
        raise InvalidInputError(f"no PMI in {args.part}: use `geomkit deviation` (with "
                                "--tolerance) instead" if not pmi.has_pmi else
                                f"no geometric tolerance in the PMI of {args.part} "
                                f"({pmi.counts()}); use `geomkit deviation`", "part")
    pts = _load_points(args.points)
    face = _face_column(args.points, len(pts.points), args.ignore_face_column)
    out = args.output or f"{Path(args.points).stem}-inspection"
    kinds = _reports.parse_kinds(args.report)
    names = list(OUTPUTS) + [f"inspection_report.{k}" for k in kinds]
    outputs = Outputs(out, names, args.overwrite, inputs=[args.part, args.points])
    res = inspect_part(case, pmi, pts.points, face, align=args.align,
                       max_distance=args.max_distance)
    model, note = _model_info(case)
    targets = outputs.create()
    data = _csv_text(res).encode("utf-8")
    files = [atomic_write(targets["characteristics.csv"], lambda fh: fh.write(data))]
    for k in kinds:
        from geomkit.report.inspect import inspect_html, inspect_pdf

        w = inspect_html if k == "html" else inspect_pdf
        files.append(w(res, case.surfaces, targets[f"inspection_report.{k}"],
                       args.overwrite, part=args.part, model_note=note))
    summary = {"part": args.part, "points_file": args.points, "model": model,
               **res.to_dict(),
               "files": [str(f) for f in files] + [str(targets["summary.json"])]}
    write_json(summary, targets["summary.json"], args.overwrite, units=res.units)
    code = 0 if res.verdict == "pass" else 1
    if args.json:
        emit_json(summary)
        return code
    _print_table(res, out, summary["files"])
    return code


def _print_table(res, out, files) -> None:
    u = res.units or ""
    print(f"{'id':>8}  {'type':18s} {'datums':8s} {'measured':>12} {'limit':>12}  status")
    for c in res.characteristics:
        m = "" if c.measured is None else f"{c.measured:.6g}"
        lim = "" if c.limit is None else f"{c.limit:.6g}"
        status = c.status if c.reason is None else f"{c.status}: {c.reason}"
        print(f"{c.id:>8}  {c.type:18s} {'|'.join(c.datums):8s} {m:>12} {lim:>12}  "
              f"{status}")
    n = res.counts()
    a = res.assignment
    print(f"{a['points']} points, {a['assigned']} on faces "
          f"({'face column' if a['given'] else 'by projection'}); units: {u}")
    print(f"verdict: {res.verdict.upper()} ({n['pass']} pass, {n['fail']} fail, "
          f"{n['not evaluated']} not evaluated)")
    print(f"reports: {Path(out)}/ ({', '.join(Path(f).name for f in files)})")
