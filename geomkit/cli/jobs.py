"""The deviation, distance, section, info, mesh, samples and demo commands."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from ..errors import InvalidInputError
from ._common import _load_input, _load_points, _progress, _tolerance

def _cmd_demo(args) -> int:
    from ..demo import run_demo

    summary = run_demo(out_dir=args.output, grid=args.grid, tol=args.tol)
    if args.json:
        print(json.dumps(summary, indent=1))
        return 0
    d = summary["deviation"]
    b = summary["bump"]
    a = summary["alignment_check"]
    print(f"geomkit demo: reports in {summary['output']}/")
    print(f"deviation  {d['points']} scan points of {summary['surface']} "
          f"(probe r={d['probe_radius']:g}): min {d['min']:.4f} max {d['max']:.4f} "
          f"rms {d['rms']:.4f}; in tolerance [{d['tolerance'][0]:g}, {d['tolerance'][1]:g}] "
          f"{d['pct_within']:.1f}%, over {d['pct_over']:.1f}%, under {d['pct_under']:.1f}%")
    print(f"bump       known height {b['height']:g} at {b['center_xyz']}: found "
          f"{b['found_max']:.4f} at {b['found_xyz']} ({b['found_distance']:.2f} away)")
    print(f"alignment  known rigid transform recovered to {a['transform_error']:.1e} in "
          f"{a['iterations']} iterations (rms {a['rms_before']:.3g} -> {a['rms_after']:.1e})")
    s = summary["section"]
    print(f"section    {s['planes']} planes {s['description']}: {s['curves']} curves, "
          f"max plane residual {s['max_residual']:.1e}")
    c = summary["clearance"]
    print(f"clearance  stylus travel: {c['travel_moves_passed']} of {c['travel_moves']} moves "
          f"keep the margin {c['margin']:g}; closest: move {c['travel_worst_move']} at "
          f"{c['travel_min_clearance']:.4f} (certified >= {c['travel_min_lower_bound']:.4f})")
    print(f"           plunge first contact at "
          f"parameter {c['plunge_first_contact']:.6f} ({c['plunge_contact_component']}; tip "
          f"centre {c['tip_distance_at_contact']:.6f} from the surface, radius "
          f"{c['stylus']['tip_radius']:g})")
    print(f"done in {summary['seconds']:.2f} s; files: {', '.join(summary['files'])}")
    return 0


def _cmd_deviation(args) -> int:
    from .scale import run_scaled, wants_scale  # issue 16: streamed / folder / Dask runs
    if wants_scale(args):
        return run_scaled(args)
    from ..deviation import deviation
    from ..report import (plot_deviation_map, plot_histogram, prepare_outputs,
                          write_deviation_csv, write_json)

    tol = _tolerance(args.tolerance)
    out = args.output or f"{Path(args.points).stem}-deviation"
    names = ["deviation.csv", "summary.json"]
    if not args.no_plots:
        names += ["deviation_map.png", "deviation_hist.png"]
    # inputs are read first (clear errors), then the folder is checked before the work
    case = _load_input(args.nominal, args.skip_invalid)
    pts = _load_points(args.points)
    targets = prepare_outputs(out, names, args.overwrite, inputs=[args.nominal, args.points])
    update, bar = _progress("projecting points")
    try:
        rep = deviation(case.surfaces, pts.points, pts.normals, args.probe_radius,
                        align=args.align, max_distance=args.max_distance, tolerance=tol,
                        progress=update)
    finally:
        if bar is not None:
            bar.stop()
    files = [write_deviation_csv(rep, targets["deviation.csv"], args.overwrite)]
    if not args.no_plots:
        files.append(plot_deviation_map(rep, case.surfaces, targets["deviation_map.png"],
                                        args.overwrite))
        files.append(plot_histogram(rep, targets["deviation_hist.png"], args.overwrite))
    summary = {"nominal": args.nominal, "points_file": args.points,
               "surfaces": len(case.surfaces), **rep.summary(),
               "files": [str(f) for f in files] + [str(targets["summary.json"])]}
    write_json(summary, targets["summary.json"], args.overwrite)  # last: marks complete
    if args.json:
        from ..report import _clean
        print(json.dumps(_clean(summary), indent=1))
        return 0
    s = summary
    print(f"{s['points']} points, {s['valid']} matched ({s['edge']} on edges, "
          f"{s['beyond']} beyond max distance)")
    print(f"deviation: min {s['min']:.6g}  max {s['max']:.6g}  mean {s['mean']:.6g}  "
          f"rms {s['rms']:.6g}  std {s['std']:.6g}")
    if tol:
        print(f"tolerance [{tol[0]:g}, {tol[1]:g}]: in {s['pct_within']:.2f}%  "
              f"over {s['pct_over']:.2f}%  under {s['pct_under']:.2f}%")
    if s["alignment"]:
        a = s["alignment"]
        print(f"alignment: rms {a['rms_before']:.6g} -> {a['rms_after']:.6g} in "
              f"{a['iterations']} iterations (rank {a['rank']}); transform:")
        for row in a["transform"]:
            print("  " + " ".join(f"{x:14.9f}" for x in row))
    print(f"reports: {Path(out)}/ ({', '.join(Path(f).name for f in s['files'])})")
    return 0


def _cmd_distance(args) -> int:
    from .. import project_points
    from ..report import _clean, prepare_outputs

    case = _load_input(args.surface, args.skip_invalid)
    pts = _load_points(args.points)
    target = None
    if args.output:
        o = Path(args.output)
        target = prepare_outputs(o.parent if str(o.parent) else ".", [o.name],
                                 args.overwrite, inputs=[args.surface, args.points])[o.name]
    update, bar = _progress("projecting points")
    try:
        pr = project_points(case.surfaces, pts.points, args.max_distance, progress=update)
    finally:
        if bar is not None:
            bar.stop()
    if target is not None:
        from ..io import _atomic_write
        from ..results import STATUS_NAMES

        lines = ["index,x,y,z,foot_x,foot_y,foot_z,u,v,surface,distance,signed_distance,"
                 "lower_bound,status"]
        f = (lambda x: repr(float(x)) if np.isfinite(x) else "")
        for i in range(len(pr)):
            lines.append(",".join([str(i)] + [f(c) for c in pts.points[i]]
                                  + [f(c) for c in pr.point[i]] + [f(c) for c in pr.uv[i]]
                                  + [str(int(pr.surface[i])), f(pr.distance[i]),
                                     f(pr.signed_distance[i]), f(pr.lower_bound[i]),
                                     STATUS_NAMES[int(pr.status[i])]]))
        data = ("\n".join(lines) + "\n").encode("utf-8")
        if target.exists() and not args.overwrite:
            raise FileExistsError(f"{target}: exists; pass --overwrite to replace it")
        _atomic_write(target, lambda fh: fh.write(data))
    ok = np.isfinite(pr.distance)
    d = pr.distance[ok]
    info = {"surface_file": args.surface, "points_file": args.points, "points": len(pr),
            "matched": int(ok.sum()), "counts": pr.counts(),
            "min": float(d.min()) if d.size else float("nan"),
            "max": float(d.max()) if d.size else float("nan"),
            "mean": float(d.mean()) if d.size else float("nan"),
            "output": str(target) if target else None}
    if args.json:
        print(json.dumps(_clean(info), indent=1))
        return 0
    print(f"{info['points']} points, {info['matched']} matched: distance min "
          f"{info['min']:.6g} max {info['max']:.6g} mean {info['mean']:.6g}"
          + (f"; written {target}" if target else ""))
    return 0


def _cmd_section(args) -> int:
    from .. import plane_section
    from ..report import _clean, plot_section, prepare_outputs, write_json, write_section
    from ..section import as_plane

    base = as_plane(args.plane)
    if args.count < 1:
        raise InvalidInputError(f"must be >= 1, got {args.count}", "--count")
    if args.count > 1 and not args.step:
        raise InvalidInputError("a family of planes (--count > 1) needs --step", "--step")
    planes = [base - np.array([0, 0, 0, k * (args.step or 0.0)]) for k in range(args.count)]
    kinds = [k.strip().lower() for k in args.formats.split(",") if k.strip()]
    bad = [k for k in kinds if k not in ("csv", "dxf", "json", "png")]
    if bad or not kinds:
        raise InvalidInputError(f"unknown format(s) {bad}; use csv, dxf, json, png",
                                "--formats")
    case = _load_input(args.surface, args.skip_invalid)
    stem = "section" if len(planes) == 1 else "section_{:03d}"
    names, per = [], []
    for k in range(len(planes)):
        st = stem.format(k)
        t = {kind: f"{st}.{kind}" for kind in kinds if kind != "png"}
        per.append(t)
        names += list(t.values())
    if "png" in kinds:
        names.append("section.png" if len(planes) == 1 else "sections.png")
    names.append("section_summary.json")
    targets = prepare_outputs(args.output, names, args.overwrite, inputs=[args.surface])
    update, bar = _progress("sectioning")
    rows, sections, files = [], [], []
    try:
        for k, pl in enumerate(planes):
            sec = plane_section(case.surfaces, pl, args.tol)
            sections.append(sec)
            written = write_section(sec, {kind: targets[n] for kind, n in per[k].items()},
                                    fit_tol=args.fit_tol, overwrite=args.overwrite)
            files += list(written.values())
            rows.append({"plane": sec.plane.tolist(), "curves": len(sec.curves),
                         "closed": int(sum(sec.closed)), "points": int(len(sec.points)),
                         "curve_points": int(sum(len(c) for c in sec.curves)),
                         "max_residual": sec.max_residual,
                         "max_chord_error": sec.max_chord_error})
            if update:
                update(k + 1, len(planes))
    finally:
        if bar is not None:
            bar.stop()
    if "png" in kinds:
        png = targets["section.png" if len(planes) == 1 else "sections.png"]
        files.append(str(plot_section(sections, png, args.overwrite)))
    summary = {"surface_file": args.surface, "surfaces": len(case.surfaces), "tol": args.tol,
               "planes": rows, "files": files + [str(targets["section_summary.json"])]}
    write_json(summary, targets["section_summary.json"], args.overwrite)
    if args.json:
        print(json.dumps(_clean(summary), indent=1))
        return 0
    for r in rows:
        a, b, c, d = r["plane"]
        print(f"plane {a:.6g} {b:.6g} {c:.6g} {d:.6g}: {r['curves']} curve(s) "
              f"({r['closed']} closed), {r['curve_points']} points, {r['points']} contact "
              f"point(s), max residual {r['max_residual']:.2g}")
    print(f"reports: {Path(args.output)}/ ({len(summary['files'])} files)")
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
    from .. import tessellate

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


def _cmd_samples(args) -> int:
    from .. import samples

    for name in samples.names():
        case = samples.load_case(name)
        print(f"{name:18s} {case.description}")
    return 0


