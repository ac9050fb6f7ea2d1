"""The ``clearance`` command: probe safety of a stylus path past a part."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from geomkit.errors import InvalidInputError
from geomkit.cli import _reports
from geomkit.cli._common import (Outputs, _load_input, _model_info, _progress, _unit,
                                 emit_json)

STYLUS_HELP = ("stylus: a JSON file (keys tip_radius, shaft_radius, shaft_length and "
               "optionally extension_radius, extension_length, body_radius, body_length) "
               "or numbers TIP_R,SHAFT_R,SHAFT_L[,EXT_R,EXT_L[,BODY_R,BODY_L]]")

EPILOG = """example:
  geomkit clearance part.igs path.csv --stylus 1.5,0.75,20,3,30 --axis 0 0 1 --margin 2

PATH: CSV/XYZ tip-centre points (x y z per row; the stylus axis points along --axis),
or JSON {"points": [[x, y, z], ...]} or {"poses": [4x4 stylus->world, ...]} (stylus
frame: tip centre at the origin, axis +z toward the head).  Between consecutive poses the
stylus translates, or rotates about a fixed line.

--probing K [K ...]: moves meant to touch the part (a probing plunge; move k goes from
path point k to k+1, negative k counts from the end): they are reported with their first
contact and drawn blue, and do not fail the run; the others are travel moves.

Exit code 0: every travel move passes; 1: some travel move fails (margin or contact);
2: bad input.  Writes clearance.csv, clearance.png and clearance_summary.json (last)."""


def parse_stylus(text: str):
    from geomkit.jobs.clearance import STYLUS_KEYS, Stylus

    p = Path(text)
    if text.lower().endswith(".json") or p.is_file():
        return Stylus.from_json(p)
    try:
        vals = [float(x) for x in text.replace(" ", "").split(",") if x != ""]
    except ValueError:
        raise InvalidInputError(f"expected a JSON file or comma-separated numbers, got "
                                f"{text!r}", "--stylus") from None
    if len(vals) not in (3, 5, 7):
        raise InvalidInputError(f"expected 3, 5 or 7 numbers (TIP_R,SHAFT_R,SHAFT_L"
                                f"[,EXT_R,EXT_L[,BODY_R,BODY_L]]), got {len(vals)}",
                                "--stylus")
    return Stylus(**dict(zip(STYLUS_KEYS, vals)))


def _cmd_clearance(args) -> int:
    from geomkit.jobs.clearance import probe_clearance, read_path
    from geomkit.report.files import plot_clearance, write_clearance_csv, write_json

    stylus = parse_stylus(args.stylus)
    case = _load_input(args.part, args.skip_invalid, args.units,
                       skip_unsupported=args.skip_unsupported)
    path = read_path(args.path)
    probing = _probing_moves(args.probing, len(path) - 1)  # checked before the long run
    out = args.output or f"{Path(args.path).stem}-clearance"
    names = ["clearance.csv", "clearance_summary.json"]
    if not args.no_plots:
        names.append("clearance.png")
    inputs = [args.part, args.path] + ([args.stylus] if Path(args.stylus).exists() else [])
    names += _reports.names(args, "clearance")
    outputs = Outputs(out, names, args.overwrite, inputs=inputs)  # created when writing
    update, bar = _progress("checking moves")
    try:
        res = probe_clearance(case.surfaces, stylus, path, axis=args.axis, margin=args.margin,
                              tol=args.tol, progress=update)
    finally:
        if bar is not None:
            bar.stop()
    tips = path if path.ndim == 2 else path[:, :3, 3]
    u = case.units
    model, note = _model_info(case)
    rk = {"units": u, "model_note": note}
    travel = np.ones(len(res), bool)
    travel[probing] = False
    ok = bool(np.all(res.passed[travel]))
    targets = outputs.create()
    files = [write_clearance_csv(res, tips, targets["clearance.csv"], args.overwrite,
                                 **rk)]
    if not args.no_plots:
        files.append(plot_clearance(res, targets["clearance.png"], args.overwrite,
                                    probing=probing, **rk))
    files += _reports.write(args, "clearance", targets, res=res, surfaces=case.surfaces,
                            path_points=tips, stylus=stylus, part=args.part,
                            axis=args.axis if path.ndim == 2 else None, probing=probing,
                            **rk)
    summary = {"part_file": args.part, "path_file": args.path, "surfaces": len(case.surfaces),
               "units": _unit(u), "model": model, "stylus": stylus.to_dict(),
               **res.summary(), **_travel_summary(res, travel, probing, ok),
               "files": [str(f) for f in files] + [str(targets["clearance_summary.json"])]}
    write_json(summary, targets["clearance_summary.json"], args.overwrite, **rk)
    if args.json:
        emit_json(summary)
    else:
        s = summary
        if note:  # a pass on part of the part is not a pass on the part: say so first
            print(note + "; clearance to the faces left out is NOT checked")
        w = s["travel_worst_move"]
        kind = (f"{int(travel.sum())} travel move(s)" if probing
                else f"{s['segments']} segment(s)")
        if w is None:
            print(f"{kind}: nothing to check besides the probing moves")
        else:
            print(f"{kind}: {'PASS' if ok else 'FAIL'} (margin {s['margin']:g} "
                  f"{s['units']}); min clearance {res.clearance[w]:.6g} (certified >= "
                  f"{res.lower_bound[w]:.6g}) on segment {w} at parameter "
                  f"{res.parameter[w]:.4f} ({res.component_names[res.component[w]]})")
        for k in probing:
            fc = res.first_contact[k]
            print(f"  probing move {k}: " + (f"first contact at parameter {fc:.9f} "
                  f"({res.component_names[res.component[k]]})" if np.isfinite(fc)
                  else f"no contact (clearance {res.clearance[k]:.6g})"))
        for i in np.flatnonzero(~res.passed & travel):
            fc = res.first_contact[i]
            what = (f"first contact at parameter {fc:.9f}" if np.isfinite(fc)
                    else f"clearance {res.lower_bound[i]:.6g} < margin")
            print(f"  segment {i}: FAIL, {what} "
                  f"({res.component_names[res.component[i]]})")
        print(f"reports: {Path(out)}/ ({', '.join(Path(f).name for f in s['files'])})")
    return 0 if ok else 1


def _probing_moves(ks, n: int) -> list[int]:
    """``--probing`` indices as sorted non-negative move numbers (negative count from the
    end); an index outside the path's ``n`` moves is an error naming it."""
    bad = [k for k in ks if not -n <= k < n]
    if bad:
        raise InvalidInputError(f"move {bad[0]} out of range: the path has {n} move(s) "
                                f"(0..{n - 1}, or -{n}..-1 from the end)", "--probing")
    return sorted({k % n for k in ks})


def _travel_summary(res, travel, probing, ok) -> dict:
    """The summary's travel / probing entries: the verdict counts travel moves only."""
    idx = np.flatnonzero(travel)
    w = int(idx[np.argmin(res.lower_bound[idx])]) if idx.size else None
    return {"travel_passed": ok, "travel_worst_move": w,
            "probing_moves": [{"move": k, "first_contact": (float(res.first_contact[k])
                               if np.isfinite(res.first_contact[k]) else None),
                               "component": res.component_names[res.component[k]]}
                              for k in probing]}


def add_parser(sub, common, positive_float, positive_or_zero):
    import argparse

    p = sub.add_parser("clearance", parents=[common],
                       help="probe safety: certified stylus clearance along a path",
                       formatter_class=argparse.RawDescriptionHelpFormatter,
                       description="Certified minimum clearance between a CMM stylus (tip "
                                   "sphere + shaft + optional extension and body) moved "
                                   "along PATH and the exact NURBS part, per segment, with "
                                   "where it occurs, the first contact parameter and "
                                   "pass/fail against --margin.",
                       epilog=EPILOG)
    p.add_argument("part", help="part surfaces: JSON, IGES, STEP or a sample name")
    p.add_argument("path", help="probe path: CSV/XYZ tip-centre points or JSON poses")
    p.add_argument("--stylus", required=True, help=STYLUS_HELP)
    p.add_argument("--axis", type=float, nargs=3, metavar=("X", "Y", "Z"),
                   default=(0.0, 0.0, 1.0),
                   help="stylus direction tip -> head for point paths (default 0 0 1)")
    p.add_argument("--margin", type=positive_or_zero, default=0.0,
                   help="required clearance (default 0: no contact)")
    p.add_argument("--probing", type=int, nargs="+", default=[], metavar="K",
                   help="moves meant to touch (probing plunges; negative counts from the "
                        "end): reported with their first contact, not failed")
    p.add_argument("--tol", type=positive_float, default=None,
                   help="certified interval width (default 1e-6 of the part's size)")
    p.add_argument("-o", "--output", default=None,
                   help="report folder (default ./<path name>-clearance)")
    p.add_argument("--no-plots", action="store_true", help="skip the PNG chart")
    p.set_defaults(func=_cmd_clearance)
    return p
