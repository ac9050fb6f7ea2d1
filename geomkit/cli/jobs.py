"""The deviation, distance, section, info, mesh, samples, sample and demo commands."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from geomkit.errors import InvalidInputError
from geomkit.cli import _reports
from geomkit.cli._common import (Outputs, _file_target, _load_input, _load_points, _model_info,
                                 _progress, _tolerance, _unit, emit_json)


def _cmd_demo(args) -> int:
    import sys

    from geomkit.jobs.demo import STEPS, run_demo

    if args.json:
        emit_json(run_demo(out_dir=args.output, grid=args.grid, tol=args.tol))
        return 0
    print(f"geomkit demo: reports in {Path(args.output)}/", flush=True)

    def progress(step, summary, seconds):
        k = STEPS.index(step) + 1
        if summary is None:  # the step starts: say so before the wait
            print(f"[{k}/{len(STEPS)}] {step} ...", flush=True)
            return
        lines = _DEMO_LINES[step](summary)
        lines[-1] += f"  ({seconds:.1f} s)"
        print("\n".join(lines), flush=True)

    try:
        summary = run_demo(out_dir=args.output, grid=args.grid, tol=args.tol,
                           progress=progress)
    finally:
        sys.stdout.flush()
    print(f"done in {summary['seconds']:.2f} s; files: {', '.join(summary['files'])}")
    return 0


def _demo_deviation(summary):
    d, b = summary["deviation"], summary["bump"]
    return [f"deviation  {d['points']} scan points of {summary['surface']} "
            f"(probe r={d['probe_radius']:g}): min {d['min']:.4f} max {d['max']:.4f} "
            f"rms {d['rms']:.4f}; in tolerance [{d['tolerance'][0]:g}, "
            f"{d['tolerance'][1]:g}] {d['pct_within']:.1f}%, over {d['pct_over']:.1f}%, "
            f"under {d['pct_under']:.1f}%",
            f"bump       known height {b['height']:g} at {b['center_xyz']}: found "
            f"{b['found_max']:.4f} at {b['found_xyz']} ({b['found_distance']:.2f} away)"]


def _demo_alignment(summary):
    a = summary["alignment_check"]
    return [f"alignment  known rigid transform recovered to {a['transform_error']:.1e} in "
            f"{a['iterations']} iterations (rms {a['rms_before']:.3g} -> "
            f"{a['rms_after']:.1e})"]


def _demo_section(summary):
    s = summary["section"]
    return [f"section    {s['planes']} planes {s['description']}: {s['curves']} curves, "
            f"max plane residual {s['max_residual']:.1e}"]


def _demo_clearance(summary):
    c = summary["clearance"]
    return [f"clearance  stylus travel: {c['travel_moves_passed']} of {c['travel_moves']} "
            f"moves keep the margin {c['margin']:g}; closest: move "
            f"{c['travel_worst_move']} at {c['travel_min_clearance']:.4f} (certified >= "
            f"{c['travel_min_lower_bound']:.4f})",
            f"           plunge first contact at parameter "
            f"{c['plunge_first_contact']:.6f} ({c['plunge_contact_component']}; tip centre "
            f"{c['tip_distance_at_contact']:.6f} from the surface, radius "
            f"{c['stylus']['tip_radius']:g})"]


def _demo_reports(summary):
    html = [f for f in summary["files"] if f.endswith(".html")]
    return [f"reports    interactive HTML: {', '.join(html)}"]


_DEMO_LINES = {"deviation": _demo_deviation, "alignment": _demo_alignment,
               "section": _demo_section, "clearance": _demo_clearance,
               "reports": _demo_reports}


def _cmd_deviation(args) -> int:
    from geomkit.cli.scale import run_scaled, wants_scale  # streamed scans, folders, Dask
    if wants_scale(args):
        return run_scaled(args)
    from geomkit.jobs.deviation import deviation
    from geomkit.report.files import (plot_deviation_map, plot_histogram, write_deviation_csv,
                                      write_json)

    tol = _tolerance(args.tolerance)
    out = args.output or f"{Path(args.points).stem}-deviation"
    names = ["deviation.csv", "summary.json"]
    if not args.no_plots:
        names += ["deviation_map.png", "deviation_hist.png"]
    # inputs are read first (clear errors), then the folder is checked before the work
    # and created only when the reports are written
    case = _load_input(args.nominal, args.skip_invalid, args.units,
                       skip_unsupported=args.skip_unsupported)
    pts = _load_points(args.points)
    names += _reports.names(args, "deviation")
    outputs = Outputs(out, names, args.overwrite, inputs=[args.nominal, args.points])
    update, bar = _progress("projecting points")
    try:
        rep = deviation(case.surfaces, pts.points, pts.normals, args.probe_radius,
                        align=args.align, max_distance=args.max_distance, tolerance=tol,
                        progress=update)
    finally:
        if bar is not None:
            bar.stop()
    _require_matches(rep.summary()["valid"], len(rep), args.max_distance)
    u = case.units
    model, note = _model_info(case)
    rk = {"units": u, "model_note": note}
    targets = outputs.create()
    files = [write_deviation_csv(rep, targets["deviation.csv"], args.overwrite, **rk)]
    if not args.no_plots:
        files.append(plot_deviation_map(rep, case.surfaces, targets["deviation_map.png"],
                                        args.overwrite, **rk))
        files.append(plot_histogram(rep, targets["deviation_hist.png"], args.overwrite,
                                    **rk))
    files += _reports.write(args, "deviation", targets, rep=rep, surfaces=case.surfaces,
                            part=args.nominal, **rk)
    summary = {"nominal": args.nominal, "points_file": args.points,
               "surfaces": len(case.surfaces), "units": _unit(u), "model": model,
               **rep.summary(),
               "files": [str(f) for f in files] + [str(targets["summary.json"])]}
    write_json(summary, targets["summary.json"], args.overwrite, **rk)  # last
    if args.json:
        emit_json(summary)
        return 0
    s = summary
    print(f"{s['points']} points, {s['valid']} matched ({s['edge']} on edges, "
          f"{s['beyond']} beyond max distance); units: {s['units']}")
    print(f"deviation: min {s['min']:.6g}  max {s['max']:.6g}  mean {s['mean']:.6g}  "
          f"rms {s['rms']:.6g}  std {s['std']:.6g} {s['units']}")
    if tol:
        print(f"tolerance [{tol[0]:g}, {tol[1]:g}] {s['units']}: in {s['pct_within']:.2f}%  "
              f"over {s['pct_over']:.2f}%  under {s['pct_under']:.2f}%")
    if s["alignment"]:
        a = s["alignment"]
        print(f"alignment: rms {a['rms_before']:.6g} -> {a['rms_after']:.6g} in "
              f"{a['iterations']} iterations (rank {a['rank']}); transform:")
        for row in a["transform"]:
            print("  " + " ".join(f"{x:14.9f}" for x in row))
    print(f"reports: {Path(out)}/ ({', '.join(Path(f).name for f in s['files'])})")
    if note:
        print(note)
    return 0


def _require_matches(matched: int, total: int, max_distance) -> None:
    """No statistics from nothing: a run where no point has a foot is an error."""
    if matched:
        return
    if max_distance is not None:
        raise InvalidInputError(f"none of the {total} point(s) is within {max_distance:g} "
                                "of the surfaces; raise it or check the units and the "
                                "alignment", "--max-distance")
    raise InvalidInputError(f"none of the {total} point(s) has a foot on the surfaces",
                            "points")


def _cmd_distance(args) -> int:
    from geomkit import project_points

    case = _load_input(args.surface, args.skip_invalid, args.units,
                       skip_unsupported=args.skip_unsupported)
    pts = _load_points(args.points)
    target = None
    if args.output:
        target = _file_target(args.output, args.overwrite, [args.surface, args.points])
    update, bar = _progress("projecting points")
    try:
        pr = project_points(case.surfaces, pts.points, args.max_distance, progress=update)
    finally:
        if bar is not None:
            bar.stop()
    ok = np.isfinite(pr.distance)
    u = _unit(case.units)
    model, note = _model_info(case)
    if target is not None:
        from geomkit.outputs import atomic_write
        from geomkit.query.results import STATUS_NAMES

        lines = ["index,x,y,z,foot_x,foot_y,foot_z,u,v,surface,distance,signed_distance,"
                 "lower_bound,status,units"]
        f = (lambda x: repr(float(x)) if np.isfinite(x) else "")
        cu = f'"{u}"' if ("," in u or '"' in u) else u
        for i in range(len(pr)):
            lines.append(",".join([str(i)] + [f(c) for c in pts.points[i]]
                                  + [f(c) for c in pr.point[i]] + [f(c) for c in pr.uv[i]]
                                  + [str(int(pr.surface[i])), f(pr.distance[i]),
                                     f(pr.signed_distance[i]), f(pr.lower_bound[i]),
                                     STATUS_NAMES[int(pr.status[i])], cu]))
        data = ("\n".join(lines) + "\n").encode("utf-8")
        if target.exists() and not args.overwrite:
            raise FileExistsError(f"{target}: exists; pass --overwrite to replace it")
        atomic_write(target, lambda fh: fh.write(data))
    d = pr.distance[ok]
    info = {"surface_file": args.surface, "points_file": args.points, "points": len(pr),
            "matched": int(ok.sum()), "counts": pr.counts(), "units": u, "model": model,
            "min": float(d.min()) if d.size else None,
            "max": float(d.max()) if d.size else None,
            "mean": float(d.mean()) if d.size else None,
            "output": str(target) if target else None}
    if args.json:
        emit_json(info)
        return 0
    written = f"; written {target}" if target else ""
    if note:
        print(note)
    if not d.size:
        beyond = (f" within --max-distance {args.max_distance:g}"
                  if args.max_distance is not None else "")
        print(f"{info['points']} points, none matched{beyond} ({u}){written}")
        return 0
    print(f"{info['points']} points, {info['matched']} matched: distance min "
          f"{info['min']:.6g} max {info['max']:.6g} mean {info['mean']:.6g} {u}{written}")
    return 0


def _cmd_section(args) -> int:
    from geomkit import plane_section
    from geomkit.report.files import plot_section, write_json, write_section
    from geomkit.section.plane import as_plane

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
    case = _load_input(args.surface, args.skip_invalid, args.units,
                       skip_unsupported=args.skip_unsupported)
    stem = "section" if len(planes) == 1 else "section_{:03d}"
    names, per = [], []
    for k in range(len(planes)):
        st = stem.format(k)
        t = {kind: f"{st}.{kind}" for kind in kinds if kind != "png"}
        per.append(t)
        names += list(t.values())
    png = ("section.png" if len(planes) == 1 else "sections.png") if "png" in kinds else None
    names += [png] if png else []
    names += _reports.names(args, "section")
    names.append("section_summary.json")
    outputs = Outputs(args.output, names, args.overwrite, inputs=[args.surface])
    u = case.units
    model, note = _model_info(case)
    rk = {"units": u, "model_note": note}
    update, bar = _progress("sectioning")
    sections = []
    try:
        for k, pl in enumerate(planes):
            sec = plane_section(case.surfaces, pl, args.tol, gap=case.gap or 0.0)
            sec.units = u  # the CSV and DXF writers state it
            sections.append(sec)
            if update:
                update(k + 1, len(planes))
    finally:
        if bar is not None:
            bar.stop()
    targets = outputs.create()
    rows, files = [], []
    for sec, t in zip(sections, per):
        written = write_section(sec, {kind: targets[n] for kind, n in t.items()},
                                fit_tol=args.fit_tol, overwrite=args.overwrite, **rk)
        files += list(written.values())
        rows.append({"plane": sec.plane.tolist(), "curves": len(sec.curves),
                     "closed": int(sum(sec.closed)), "points": int(len(sec.points)),
                     "curve_points": int(sum(len(c) for c in sec.curves)),
                     "max_residual": sec.max_residual,
                     "max_chord_error": sec.max_chord_error,
                     "max_gap_bridged": sec.max_gap_bridged,
                     "failed_faces": {int(k): v for k, v in sec.failed.items()}})
    if png:
        files.append(str(plot_section(sections, targets[png], args.overwrite, **rk)))
    files += _reports.write(args, "section", targets, sections=sections,
                            surfaces=case.surfaces, part=args.surface, **rk)
    summary = {"surface_file": args.surface, "surfaces": len(case.surfaces),
               "units": _unit(u), "model": model, "tol": args.tol,
               "gap": case.gap or 0.0, "planes": rows,
               "files": files + [str(targets["section_summary.json"])]}
    write_json(summary, targets["section_summary.json"], args.overwrite, **rk)
    if args.json:
        emit_json(summary)
        return 0
    for r in rows:
        a, b, c, d = r["plane"]
        print(f"plane {a:.6g} {b:.6g} {c:.6g} {d:.6g}: {r['curves']} curve(s) "
              f"({r['closed']} closed), {r['curve_points']} points, {r['points']} contact "
              f"point(s), max residual {r['max_residual']:.2g} {summary['units']}")
        if r["failed_faces"]:
            print(f"  {len(r['failed_faces'])} face(s) left out (could not be sectioned): "
                  + ", ".join(str(k) for k in r["failed_faces"]))
    print(f"reports: {Path(args.output)}/ ({len(summary['files'])} files; "
          f"units: {summary['units']})")
    if note:
        print(note)
    return 0


def _cmd_info(args) -> int:
    case = _load_input(args.file, units=args.units)
    out = {"name": case.name, "units": _unit(case.units), "surfaces": []}
    for s in case.surfaces:
        (u0, u1), (v0, v1) = s.domain
        out["surfaces"].append({"name": s.name, "rational": s.is_rational,
                                "degree": [s.degree_u, s.degree_v],
                                "control_net": list(s.shape), "domain": [[u0, u1], [v0, v1]],
                                "trim_loops": len(s.trim), "bounds": s.bounds.tolist()})
    dup = getattr(case, "duplicates", None) or {}
    if dup:
        out["duplicate_faces"] = {str(k): v for k, v in dup.items()}
    if args.json:
        emit_json(out)
    else:
        for s in out["surfaces"]:
            print(f"{s['name'] or '-'}: {'NURBS' if s['rational'] else 'B-spline'} degree "
                  f"{s['degree']}, net {s['control_net']}, domain {s['domain']}, "
                  f"{s['trim_loops']} trim loop(s), bounds {s['bounds']} ({out['units']})")
        for k, v in dup.items():
            print(f"{case.surfaces[k].name}: a loose face lying on the solid's face(s) "
                  f"{', '.join(case.surfaces[i].name for i in v)} (left out of the "
                  "outward-normal vote and of inspect's face assignment)")
    return 0


def _cmd_mesh(args) -> int:
    import math

    from geomkit import tessellate
    from geomkit.exchange.cases import MESH_FORMATS

    out = Path(args.output)
    if out.suffix.lower() not in MESH_FORMATS:
        raise InvalidInputError(f"{out}: unknown mesh format {out.suffix or '(none)'!r}; "
                                f"use {', '.join(MESH_FORMATS)}", "-o")
    out = _file_target(out, args.overwrite, inputs=[args.input])
    case = _load_input(args.input, args.skip_invalid, args.units,
                       skip_unsupported=args.skip_unsupported)
    max_angle = math.radians(args.max_angle) if args.max_angle is not None else None
    mesh = tessellate(case.surfaces, args.tol, max_angle=max_angle, max_edge=args.max_edge)
    mesh.export(out, overwrite=args.overwrite)
    model, note = _model_info(case)
    info = {"input": args.input, "output": str(out), "surfaces": len(case.surfaces),
            "model": model,
            "vertices": int(mesh.vertices.shape[0]), "faces": int(mesh.faces.shape[0]),
            "units": _unit(case.units), "tol": args.tol,
            "max_deviation": mesh.max_deviation, "area": mesh.area,
            "seconds": sum(st.get("seconds", 0.0) for st in mesh.stats["surfaces"]),
            "failed_surfaces": [i for i, st in enumerate(mesh.stats["surfaces"])
                                if "failed" in st]}
    if args.json:
        emit_json(info)
    else:
        print(f"{out}: {info['faces']} triangles, {info['vertices']} vertices from "
              f"{info['surfaces']} surface(s); measured max deviation "
              f"{info['max_deviation']:.3g} <= tol {args.tol:g} {info['units']}; "
              f"{info['seconds']:.2f} s")
        if info["failed_surfaces"]:
            print(f"left out ({len(info['failed_surfaces'])} surface(s) could not be "
                  f"triangulated): {info['failed_surfaces'][:20]}")
        if note:
            print(note)
    return 0


def _cmd_samples(args) -> int:
    from geomkit import samples

    for name in samples.names():
        case = samples.load_case(name)
        print(f"{name:18s} {case.description}")
    return 0




def _faces_arg(text):
    """``--faces 1,2,5`` as a list of face indices (range-checked by the job)."""
    if text is None:
        return None
    try:
        faces = [int(t) for t in text.split(",") if t.strip()]
    except ValueError:
        raise InvalidInputError(f"expected comma-separated face indices, got {text!r}",
                                "--faces") from None
    if not faces:
        raise InvalidInputError("no face given", "--faces")
    return faces


def _cmd_sample(args) -> int:
    from geomkit.jobs.sample import sample_faces
    from geomkit.outputs import atomic_write

    if args.per_face < 1:
        raise InvalidInputError(f"must be >= 1, got {args.per_face}", "--per-face")
    faces = _faces_arg(args.faces)
    out = args.output or f"{Path(args.part).stem}-points.csv"
    target = _file_target(out, args.overwrite, inputs=[args.part])
    case = _load_input(args.part, args.skip_invalid, args.units,
                       skip_unsupported=args.skip_unsupported)
    n = len(case.surfaces)
    bad = [f for f in faces or [] if not 0 <= f < n]
    if bad:
        raise InvalidInputError(f"face {bad[0]} is out of range: the part has {n} face(s), "
                                f"0..{n - 1}", "--faces")
    res = sample_faces(case.surfaces, args.per_face, noise=args.noise, seed=args.seed,
                       faces=faces)
    data = res.csv_text().encode("utf-8")
    if target.exists() and not args.overwrite:
        raise FileExistsError(f"{target}: exists; pass --overwrite to replace it")
    atomic_write(target, lambda fh: fh.write(data))
    model, note = _model_info(case)
    s = res.summary()
    info = {"part": args.part, "output": str(target), "units": _unit(case.units),
            "model": model, "points": s["points"], "faces": s["faces"],
            "per_face": s["per_face"], "noise": args.noise, "seed": args.seed,
            "short_faces": s["short_faces"], "flipped_faces": s["flipped_faces"],
            "undecided_faces": s["undecided_faces"]}
    if args.json:
        emit_json(info)
        return 0
    short = (f"; {len(s['short_faces'])} face(s) short of {args.per_face}"
             if s["short_faces"] else "")
    print(f"{target}: {s['points']} points on {s['faces']} face(s) ({args.per_face} per "
          f"face{short}), noise {args.noise:g} {info['units']}, seed {args.seed}")
    if note:
        print(note)
    return 0
