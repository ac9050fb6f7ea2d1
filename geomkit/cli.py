"""The ``geomkit`` command line.  Calls only the public API."""

from __future__ import annotations

import argparse
import json
import sys

from .errors import GeomkitError

EXAMPLES = """examples:
  geomkit demo                              run the main job on the bundled samples
  geomkit info part.json                    list the surfaces of a file
  geomkit mesh part.json --tol 0.01 -o part.stl
                                            triangulate within 0.01 (STL/PLY/OBJ)
  geomkit mesh sphere --tol 1e-3 -o s.ply   a bundled sample by name
  geomkit samples                           list the bundled sample cases
"""


def _load_input(name: str):
    """Surfaces from a file path, or from a bundled sample name."""
    from pathlib import Path

    from . import load_case, samples

    try:
        exists = Path(name).exists()
    except OSError:  # e.g. a name too long for the file system: load_case reports it
        exists = False
    if not exists and name in samples.names():
        return samples.load_case(name)
    return load_case(name)


def _cmd_demo(args) -> int:
    from .demo import run_demo

    summary = run_demo(grid=args.grid, tol=args.tol)
    if args.json:
        print(json.dumps(summary, indent=1))
        return 0
    print(f"{'case':18s} {'surface':18s} {'kind':8s} {'deg':5s} {'net':6s} "
          f"{'us/pt':>6s}  check")
    for r in summary["surfaces"]:
        check = ""
        if "analytic" in r:
            check = f"{r['analytic']} formula err {r['analytic_max_err']:.1e}"
        if "uv_inside_fraction" in r:
            check = f"trimmed: {100 * r['uv_inside_fraction']:.2f}% of UV grid inside"
        print(f"{r['case']:18s} {r['surface'][:18]:18s} {r['kind']:8s} "
              f"{r['degree'][0]},{r['degree'][1]:<3d} {r['control_net'][0]}x{r['control_net'][1]:<4d}"
              f"{r['eval_us_per_point']:6.3f}  {check}")
    print()
    print(f"{'case':18s} {'tol':>6s} {'triangles':>9s} {'max dev':>9s} {'area':>12s} "
          f"{'truth':>12s} {'s':>6s}")
    for r in summary["surfaces"]:
        m = r.get("case_mesh")
        if m:
            truth = f"{m['area_truth']:12.4f}" if m["area_truth"] else f"{'-':>12s}"
            print(f"{r['case']:18s} {m['tol']:6.0e} {m['faces']:9d} {m['max_deviation']:9.2e} "
                  f"{m['area']:12.4f} {truth} {m['seconds']:6.2f}")
    print(f"{len(summary['surfaces'])} surfaces evaluated on {args.grid}x{args.grid} grids and "
          f"tessellated in {summary['seconds']:.2f} s")
    return 0


def _cmd_info(args) -> int:
    case = _load_input(args.file)
    out = {"name": case.name, "surfaces": []}
    for s in case.surfaces:
        (u0, u1), (v0, v1) = s.domain
        out["surfaces"].append({"name": s.name, "rational": s.is_rational,
                                "degree": [s.degree_u, s.degree_v],
                                "control_net": list(s.shape), "domain": [[u0, u1], [v0, v1]],
                                "trim_loops": len(s.trim), "bounds": s.bounds.tolist()})
    if args.json:
        print(json.dumps(out, indent=1))
    else:
        for s in out["surfaces"]:
            print(f"{s['name'] or '-'}: {'NURBS' if s['rational'] else 'B-spline'} degree "
                  f"{s['degree']}, net {s['control_net']}, domain {s['domain']}, "
                  f"{s['trim_loops']} trim loop(s), bounds {s['bounds']}")
    return 0


def _cmd_mesh(args) -> int:
    import math
    from pathlib import Path

    from . import tessellate

    src = Path(args.input)
    out = Path(args.output)
    if out.exists() and src.exists() and src.resolve() == out.resolve():
        raise FileExistsError(f"{out}: is the input; choose another output")
    if out.exists() and not args.overwrite:
        raise FileExistsError(f"{out}: exists; pass --overwrite to replace it")
    case = _load_input(args.input)
    max_angle = math.radians(args.max_angle) if args.max_angle is not None else None
    mesh = tessellate(case.surfaces, args.tol, max_angle=max_angle, max_edge=args.max_edge)
    mesh.export(out, overwrite=args.overwrite)
    info = {"input": args.input, "output": str(out), "surfaces": len(case.surfaces),
            "vertices": int(mesh.vertices.shape[0]), "faces": int(mesh.faces.shape[0]),
            "tol": args.tol, "max_deviation": mesh.max_deviation, "area": mesh.area,
            "seconds": sum(st["seconds"] for st in mesh.stats["surfaces"])}
    if args.json:
        print(json.dumps(info, indent=1))
    else:
        print(f"{out}: {info['faces']} triangles, {info['vertices']} vertices from "
              f"{info['surfaces']} surface(s); measured max deviation "
              f"{info['max_deviation']:.3g} <= tol {args.tol:g}; {info['seconds']:.2f} s")
    return 0


def _positive_float(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a positive number, got {text!r}") from None
    if not (value > 0) or value == float("inf"):
        raise argparse.ArgumentTypeError(f"must be a positive finite number, got {text!r}")
    return value


def _cmd_samples(args) -> int:
    from . import samples

    for name in samples.names():
        case = samples.load_case(name)
        print(f"{name:18s} {case.description}")
    return 0


def _positive_int(text: str) -> int:
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a positive integer, got {text!r}") from None
    if value < 2:
        raise argparse.ArgumentTypeError(f"must be at least 2, got {value}")
    return value


def build_parser() -> argparse.ArgumentParser:
    ap = argparse.ArgumentParser(prog="geomkit",
                                 description="Exact NURBS surface geometry with stated "
                                             "error bounds.",
                                 epilog=EXAMPLES,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = ap.add_subparsers(dest="command", required=True)
    p = sub.add_parser("demo", help="run the main job on the bundled samples")
    p.add_argument("--grid", type=_positive_int, default=200, help="grid size per surface (default 200)")
    p.add_argument("--tol", type=_positive_float, default=1e-2,
                   help="tessellation tolerance (default 0.01)")
    p.add_argument("--json", action="store_true", help="machine-readable output")
    p.set_defaults(func=_cmd_demo)
    p = sub.add_parser("info", help="describe the surfaces of a file")
    p.add_argument("file")
    p.add_argument("--json", action="store_true", help="machine-readable output")
    p.set_defaults(func=_cmd_info)
    p = sub.add_parser("mesh", help="triangulate surfaces within a chord tolerance",
                       description="Triangulate every surface of INPUT so that each "
                                   "triangle is within --tol of its surface (measured), "
                                   "and write STL, PLY or OBJ by the output's extension.")
    p.add_argument("input", help="geomkit-case/1 or geomdl JSON file, or a sample name")
    p.add_argument("--tol", type=_positive_float, required=True,
                   help="chord tolerance, model units")
    p.add_argument("-o", "--output", required=True, help="output .stl, .ply or .obj")
    p.add_argument("--max-angle", type=_positive_float, default=None,
                   help="largest normal angle across a cell, degrees")
    p.add_argument("--max-edge", type=_positive_float, default=None,
                   help="largest cell edge, model units")
    p.add_argument("--overwrite", action="store_true", help="replace an existing output")
    p.add_argument("--json", action="store_true", help="machine-readable output")
    p.set_defaults(func=_cmd_mesh)
    p = sub.add_parser("samples", help="list the bundled samples")
    p.set_defaults(func=_cmd_samples)
    return ap


def main(argv=None) -> int:
    args = build_parser().parse_args(argv)
    try:
        return args.func(args)
    except GeomkitError as exc:
        print(f"geomkit: error: {exc}", file=sys.stderr)
        return 2
    except FileExistsError as exc:
        print(f"geomkit: error: {exc}", file=sys.stderr)
        return 2
    except BrokenPipeError:  # output piped into e.g. `head`
        sys.stderr.close()
        return 0


if __name__ == "__main__":
    sys.exit(main())
