"""The deviation command at scale: streamed scans, folders of scans, Dask workers.
:func:`add_deviation_options` adds the options; :func:`wants_scale`
tells :func:`geomkit.cli.jobs._cmd_deviation` to hand the run to :func:`run_scaled`."""

from __future__ import annotations

import shutil
import sys
from pathlib import Path

from geomkit.errors import InvalidInputError
from geomkit.cli._common import (_load_input, _model_info, _progress, _tolerance, _unit,
                                 emit_json)

STREAM_BYTES = 64 << 20
"""Point files larger than this are streamed (no plots) without being asked."""


def add_deviation_options(p):
    g = p.add_argument_group("scale (streamed scans, folders of scans, Dask)")
    g.add_argument("--workers", type=int, default=None, metavar="N",
                   help="run the chunks on a local Dask cluster of N worker processes "
                        "(needs geomkit[scale])")
    g.add_argument("--scheduler", default=None, metavar="ADDRESS",
                   help="run the chunks on an existing Dask cluster (tcp://host:8786)")
    g.add_argument("--format", choices=("csv", "parquet"), default=None,
                   help="per-point output format of a streamed run (default csv)")
    g.add_argument("--chunk-size", type=int, default=None, metavar="N",
                   help="points per chunk / Dask task (default 65536)")
    g.add_argument("--stream", action="store_true",
                   help="stream the scan (bounded memory, no plots); implied for "
                        "folders, .npy/.las/.laz/.e57, files over 64 MB, --workers, "
                        "--scheduler and --format")


def wants_scale(args) -> bool:
    p = Path(args.points)
    if args.workers is not None or args.scheduler or args.format or args.stream or \
            args.chunk_size is not None or p.is_dir():
        return True
    if p.suffix.lower() in (".npy", ".las", ".laz", ".e57"):
        return True
    try:
        return p.stat().st_size > STREAM_BYTES
    except OSError:
        return False


def _cleanup(out: Path, existed: bool):
    """Remove the output folder a failed run created, when it holds no report."""
    if existed or not out.is_dir():
        return
    if not any(out.rglob("summary.json")):
        shutil.rmtree(out, ignore_errors=True)


def run_scaled(args) -> int:
    from geomkit.jobs.batch import batch_deviation, deviation_report

    if args.workers is not None and args.workers < 1:
        raise InvalidInputError(f"must be >= 1, got {args.workers}", "--workers")
    if args.workers is not None and args.scheduler:
        raise InvalidInputError("give --workers or --scheduler, not both", "--workers")
    chunk = args.chunk_size if args.chunk_size is not None else 1 << 16
    if chunk < 1:
        raise InvalidInputError(f"must be >= 1, got {chunk}", "--chunk-size")
    fmt = args.format or "csv"
    if fmt == "parquet":
        from geomkit.jobs.stream import pyarrow_parquet
        pyarrow_parquet()
    tol = _tolerance(args.tolerance)
    pts = Path(args.points)
    if not pts.exists():
        raise InvalidInputError(f"{pts}: no such file or folder", "points")
    out = Path(args.output or f"{pts.stem}-deviation")
    case = _load_input(args.nominal, args.skip_invalid, args.units,
                       skip_unsupported=args.skip_unsupported)
    model, note = _model_info(case)
    u = _unit(case.units)
    client = cluster = None
    if args.workers is not None or args.scheduler:
        from geomkit.jobs.distributed import make_client
        client, cluster = make_client(args.workers, args.scheduler)
    existed = out.exists()
    kw = dict(fmt=fmt, overwrite=args.overwrite, inputs=[args.nominal],
              extra={"nominal": args.nominal, "surfaces": len(case.surfaces),
                     "units": u, "model": model},
              probe_radius=args.probe_radius, align=args.align,
              max_distance=args.max_distance, tolerance=tol, chunk_size=chunk,
              client=client)
    update, bar = _progress("deviation (streamed)")
    try:
        if pts.is_dir():
            s = batch_deviation(case.surfaces, pts, out, progress=update, **kw)
        else:
            s = deviation_report(case.surfaces, pts, out, progress=update, **kw)
    except BaseException:
        _cleanup(out, existed)
        raise
    finally:
        if bar is not None:
            bar.stop()
        if client is not None:
            client.close()
        if cluster is not None:
            cluster.close()
    if args.json:
        emit_json(s)
        return 0
    if note:
        print(note)
    if pts.is_dir():
        print(f"{len(s['parts'])} parts: {s['passed']} pass, {s['failed']} fail, "
              f"{s['errors']} with errors; table {out / 'parts.csv'}")
        for r in s["parts"]:
            if r["error"]:
                print(f"  {r['part']}: error: {r['error']}", file=sys.stderr)
        return 0
    print(f"{s['points']} points, {s['valid']} matched ({s['edge']} on edges, "
          f"{s['beyond']} beyond max distance), {s['chunks']} chunks, "
          f"{s['seconds']:.1f} s")
    print(f"deviation: min {s['min']:.6g}  max {s['max']:.6g}  mean {s['mean']:.6g}  "
          f"rms {s['rms']:.6g}  std {s['std']:.6g} {u}")
    if tol:
        print(f"tolerance [{tol[0]:g}, {tol[1]:g}] {u}: in {s['pct_within']:.2f}%  "
              f"over {s['pct_over']:.2f}%  under {s['pct_under']:.2f}%")
    print(f"reports: {out}/ ({', '.join(Path(f).name for f in s['files'])})")
    return 0
