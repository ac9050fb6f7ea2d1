"""The ``geomkit`` command line.  Calls only the public API.

Layout: this module builds the parser and runs a command; :mod:`._common` loads
inputs and parses argument types; :mod:`.jobs`, :mod:`.clearance` and :mod:`.bench`
hold the commands."""

from __future__ import annotations

import argparse
import json
import sys
import warnings

from geomkit.errors import GeomkitError
from geomkit.cli._common import (WARNINGS, Parser, _positive_float, _positive_int,
                                 _positive_or_zero, _units_arg, show_warning)
from geomkit.cli import bench as _bench
from geomkit.cli import clearance as _clearance
from geomkit.cli import inspect as _inspect
from geomkit.cli.jobs import (_cmd_demo, _cmd_deviation, _cmd_distance, _cmd_info, _cmd_mesh,
                              _cmd_sample, _cmd_samples, _cmd_section)

EXAMPLES = """examples:
  geomkit demo                              deviation, section, clearance on built-in data,
                                            reports in ./geomkit-demo/
  geomkit deviation part.igs cmm.csv --probe-radius 1.5 --tolerance -0.05 0.05 --align
                                            CMM deviation report in ./cmm-deviation/
  geomkit distance part.json points.xyz -o dist.csv
                                            exact distances of points to the surfaces
  geomkit section part.step --plane 1 0 0 -20 --step 5 --count 10 -o cuts
                                            10 parallel sections as CSV/DXF/JSON/PNG
  geomkit clearance part.igs path.csv --stylus 1.5,0.75,20,3,30 --margin 2
                                            probe safety: certified stylus clearance
                                            per path segment, exit 1 if any fails
  geomkit bench                             speed against error of every engine beside
                                            Open CASCADE / Coal, table + plot
  geomkit info part.json                    list the surfaces of a file
  geomkit mesh part.json --tol 0.01 -o part.stl
                                            triangulate within 0.01 (STL/PLY/OBJ)
  geomkit samples                           list the bundled sample cases
  geomkit sample part.step --per-face 20 --noise 0.002 -o points.csv
                                            a virtual measurement: points on every face

Inputs: geomkit-case/1 or geomdl JSON, IGES (.igs/.iges; see docs/guide_cad.md for
the entities read), STEP (.stp/.step, needs cadquery-ocp), or a bundled sample name;
faces that cannot be read are an error unless --skip-unsupported.  Points: CSV/XYZ
(x y z [i j k], named headers, decimal commas), PLY, STL, NPY, LAS/LAZ, E57, or a folder
of scans (streamed; --workers N on Dask).  Units: the model's own (IGES/STEP/JSON state
them; --units overrides), written in every report.  Errors: one line on stderr,
exit code 2.
`geomkit COMMAND --help` shows each command's options and an example.
"""


UNITS_HELP = ("length unit of the model (mm, cm, m, in, ft, um, ...): overrides what "
              "the file states; reports say 'model units' when neither does")


def _add_cad_options(p) -> None:
    """The CAD-reading options of every command that loads a model."""
    p.add_argument("--skip-invalid", action="store_true",
                   help="IGES/STEP: skip faces that fail validation (counted) "
                        "instead of stopping")
    p.add_argument("--skip-unsupported", action="store_true",
                   help="IGES/STEP: go on without faces whose entities cannot be read "
                        "(they are listed, and every report says PARTIAL MODEL); "
                        "default: such a file is an error")
    p.add_argument("--verbose", action="store_true", default=argparse.SUPPRESS,
                   help="also show Open CASCADE's messages on stderr")


def _version_line() -> str:
    import numba

    from geomkit.version import __version__
    from geomkit.jobs.warmup import kernels_status

    return f"geomkit {__version__} (numba {numba.__version__}; {kernels_status()})"


def build_parser() -> argparse.ArgumentParser:
    ap = Parser(prog="geomkit",
                                 description="Exact NURBS surface geometry with stated "
                                             "error bounds.",
                                 epilog=EXAMPLES,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--version", action="version", version=_version_line(),
                    help="the version, and whether the kernels are compiled ahead of "
                         "time or on first use (JIT)")
    ap.add_argument("--verbose", action="store_true",
                    help="also show the messages of the libraries geomkit calls (Open "
                         "CASCADE's, when a STEP file is handed to it) on stderr")
    sub = ap.add_subparsers(dest="command", required=True)
    p = sub.add_parser("demo", help="the main jobs on built-in data (deviation, section, "
                                    "clearance)",
                       description="Deviation of a synthetic CMM scan of the bundled "
                                   "freeform surface (with a known bump), a best-fit "
                                   "alignment check, a family of sections and a probe "
                                   "clearance check; writes its "
                                   "reports into ./geomkit-demo/ (replacing the demo's own "
                                   "report files there) and prints a summary.")
    p.add_argument("--grid", type=_positive_int, default=40,
                   help="scan points per side (default 40)")
    p.add_argument("--tol", type=_positive_float, default=1e-4,
                   help="section chord tolerance (default 1e-4)")
    p.add_argument("-o", "--output", default="geomkit-demo",
                   help="report folder (default ./geomkit-demo)")
    p.add_argument("--json", action="store_true", help="machine-readable output")
    p.set_defaults(func=_cmd_demo)
    common = Parser(add_help=False)
    _add_cad_options(common)
    common.add_argument("--overwrite", action="store_true", help="replace existing outputs")
    common.add_argument("--json", action="store_true", help="machine-readable output")
    common.add_argument("--units", type=_units_arg, default=None, metavar="UNIT",
                        help=UNITS_HELP)
    p = sub.add_parser("deviation", parents=[common],
                       help="CMM deviation of measured points from nominal surfaces",
                       formatter_class=argparse.RawDescriptionHelpFormatter,
                       description="Signed deviation of measured points along the nominal "
                                   "normal, with optional best-fit alignment, probe-radius "
                                   "compensation and a tolerance band.  Writes "
                                   "deviation.csv, deviation_map.png, deviation_hist.png "
                                   "and summary.json (last) into the output folder.",
                       epilog="example:\n  geomkit deviation part.igs cmm.csv "
                              "--probe-radius 1.5 --tolerance -0.05 0.05 --align -o rep")
    p.add_argument("nominal", help="nominal surfaces: JSON, IGES, STEP or a sample name")
    p.add_argument("points", help="measured points: CSV/XYZ (x y z [i j k], named "
                                  "headers), PLY, STL, NPY, LAS/LAZ, E57, or a folder of scans")
    p.add_argument("-o", "--output", default=None,
                   help="report folder (default ./<points name>-deviation)")
    p.add_argument("--probe-radius", type=_positive_or_zero, default=0.0,
                   help="probe ball radius: the points are ball centres")
    p.add_argument("--align", action="store_true",
                   help="best-fit rigid alignment first (transform reported)")
    p.add_argument("--max-distance", type=_positive_float, default=None,
                   help="points whose |deviation| exceeds this (> 0) are not matched")
    p.add_argument("--tolerance", type=float, nargs="+", metavar="T", default=None,
                   help="tolerance band: T (meaning -T..T) or LOWER UPPER")
    p.add_argument("--no-plots", action="store_true", help="skip the PNG images")
    from geomkit.cli.scale import add_deviation_options  # streamed scans, folders, Dask
    add_deviation_options(p)
    p.set_defaults(func=_cmd_deviation)
    p = sub.add_parser("distance", parents=[common],
                       help="exact distances of points to surfaces",
                       description="Nearest points of measured points on the surfaces "
                                   "(unsigned and signed distance, foot, uv, status); "
                                   "prints statistics and writes a CSV with -o.")
    p.add_argument("surface", help="surfaces: JSON, IGES, STEP or a sample name")
    p.add_argument("points", help="points: CSV/XYZ or STL/PLY")
    p.add_argument("-o", "--output", default=None, help="output CSV")
    p.add_argument("--max-distance", type=_positive_float, default=None,
                   help="points farther than this (> 0) are not matched")
    p.set_defaults(func=_cmd_distance)
    p = sub.add_parser("section", parents=[common], help="plane sections as CSV/DXF/JSON/PNG",
                       formatter_class=argparse.RawDescriptionHelpFormatter,
                       description="Intersect the surfaces with the plane A x + B y + C z "
                                   "+ D = 0, or with --count parallel planes --step apart "
                                   "along its normal.",
                       epilog="example:\n  geomkit section part.json --plane 1 0 0 -20 "
                              "--step 5 --count 10 -o cuts")
    p.add_argument("surface", help="surfaces: JSON, IGES, STEP or a sample name")
    p.add_argument("--plane", type=float, nargs=4, metavar=("A", "B", "C", "D"), required=True,
                   help="the plane A x + B y + C z + D = 0 (the first of the family)")
    p.add_argument("--step", type=_positive_float, default=None,
                   help="distance between parallel planes (model units)")
    p.add_argument("--count", type=int, default=1, help="number of parallel planes")
    p.add_argument("--tol", type=_positive_float, default=1e-4,
                   help="chord tolerance (default 1e-4)")
    p.add_argument("--fit-tol", type=_positive_float, default=None,
                   help="also fit B-splines within this tolerance (DXF SPLINEs, JSON)")
    p.add_argument("--formats", default="csv,dxf,json,png",
                   help="comma-separated subset of csv,dxf,json,png (default all)")
    p.add_argument("-o", "--output", default="section", help="output folder")
    p.set_defaults(func=_cmd_section)
    _clearance.add_parser(sub, common, _positive_float, _positive_or_zero)
    _bench.add_parser(sub)
    p = sub.add_parser("info", help="describe the surfaces of a file")
    p.add_argument("file", help="surfaces: JSON, IGES, STEP or a sample name")
    p.add_argument("--json", action="store_true", help="machine-readable output")
    p.add_argument("--units", type=_units_arg, default=None, metavar="UNIT",
                   help=UNITS_HELP)
    p.add_argument("--verbose", action="store_true", default=argparse.SUPPRESS,
                   help="also show Open CASCADE's messages on stderr")
    p.set_defaults(func=_cmd_info)
    p = sub.add_parser("mesh", help="triangulate surfaces within a chord tolerance",
                       description="Triangulate every surface of INPUT so that each "
                                   "triangle is within --tol of its surface (measured), "
                                   "and write STL, PLY or OBJ by the output's extension.")
    p.add_argument("input", help="surfaces: JSON, IGES, STEP or a sample name")
    p.add_argument("--tol", type=_positive_float, required=True,
                   help="chord tolerance, model units")
    p.add_argument("-o", "--output", required=True, help="output .stl, .ply or .obj")
    p.add_argument("--max-angle", type=_positive_float, default=None,
                   help="largest normal angle across a cell, degrees")
    p.add_argument("--max-edge", type=_positive_float, default=None,
                   help="largest cell edge, model units")
    p.add_argument("--overwrite", action="store_true", help="replace an existing output")
    p.add_argument("--json", action="store_true", help="machine-readable output")
    _add_cad_options(p)
    p.add_argument("--units", type=_units_arg, default=None, metavar="UNIT",
                   help=UNITS_HELP)
    p.set_defaults(func=_cmd_mesh)
    p = sub.add_parser("sample", help="a virtual measurement: points on every face",
                       formatter_class=argparse.RawDescriptionHelpFormatter,
                       description="Sample N points spread over each trimmed face of "
                                   "PART (exact points, outward normals), displaced by "
                                   "Gaussian noise along the normal, and write them as "
                                   "CSV x,y,z,i,j,k,face,u,v (i,j,k the nominal outward "
                                   "normal) for geomkit deviation.",
                       epilog="example:\n  geomkit sample part.step --per-face 20 "
                              "--noise 0.002 --seed 1 -o points.csv")
    p.add_argument("part", help="surfaces: JSON, IGES, STEP or a sample name")
    p.add_argument("--per-face", type=int, required=True, metavar="N",
                   help="points per face (>= 1)")
    p.add_argument("--noise", type=_positive_or_zero, default=0.0, metavar="S",
                   help="standard deviation of the noise along the normal (default 0)")
    p.add_argument("--seed", type=int, default=0, metavar="K",
                   help="random seed: the same seed gives the same points (default 0)")
    p.add_argument("--faces", default=None, metavar="LIST",
                   help="comma-separated face indices to sample (default all)")
    p.add_argument("-o", "--output", default=None,
                   help="output CSV (default ./<part name>-points.csv)")
    p.add_argument("--overwrite", action="store_true", help="replace an existing output")
    p.add_argument("--json", action="store_true", help="machine-readable output")
    p.add_argument("--units", type=_units_arg, default=None, metavar="UNIT",
                   help=UNITS_HELP)
    _add_cad_options(p)
    p.set_defaults(func=_cmd_sample)
    _inspect.add_parser(sub, common)
    p = sub.add_parser("samples", help="list the bundled samples")
    p.set_defaults(func=_cmd_samples)
    from geomkit.cli import _reports  # --report html,pdf on deviation, section, clearance

    _reports.add_options(sub)
    return ap


def main(argv=None) -> int:
    argv = sys.argv[1:] if argv is None else list(argv)
    as_json = "--json" in argv
    Parser.last_error = None
    try:
        args = build_parser().parse_args(argv)
    except SystemExit as exc:  # --help (0) or a one-line argument error (2)
        code = exc.code if isinstance(exc.code, int) else (0 if exc.code is None else 2)
        if code and as_json:
            _json_error(Parser.last_error or "argument error", code)
        return code
    WARNINGS.clear()
    if getattr(args, "verbose", False):
        import logging

        logging.basicConfig(stream=sys.stderr, level=logging.INFO,
                            format="geomkit: %(name)s: %(message)s")
    with warnings.catch_warnings():
        warnings.simplefilter("default")
        warnings.showwarning = show_warning
        code, message = _run(args)
    if message is not None:
        print(f"geomkit: error: {message}", file=sys.stderr)
        if as_json:
            _json_error(message, code)
    return code


def _run(args):
    """``(exit code, error message or None)`` of the command."""
    try:
        return args.func(args), None
    except (GeomkitError, FileExistsError) as exc:
        return 2, _one_line(exc)
    except BrokenPipeError:  # output piped into e.g. `head`
        sys.stderr.close()
        return 0, None
    except OSError as exc:
        where = f"{exc.filename}: " if getattr(exc, "filename", None) else ""
        return 2, f"{where}{exc.strerror or exc}"
    except KeyboardInterrupt:
        return 130, "interrupted"
    except Exception as exc:  # a bug: still one line, the traceback on request
        import os

        if os.environ.get("GEOMKIT_DEBUG"):
            raise
        return 3, (f"internal error {type(exc).__name__}: {_one_line(exc)} "
                   "(set GEOMKIT_DEBUG=1 for the traceback)")


def _json_error(message: str, code: int) -> None:
    """With ``--json``, stdout is JSON even when the run fails: ``{"error": ...,
    "exit_code": ...}`` (and the run's warnings)."""
    out = {"error": message, "exit_code": code}
    if WARNINGS:
        out["warnings"] = list(WARNINGS)
    try:
        print(json.dumps(out, indent=1))
    except (BrokenPipeError, ValueError):  # stdout closed
        pass


def _one_line(exc) -> str:
    return " ".join(str(exc).split())


