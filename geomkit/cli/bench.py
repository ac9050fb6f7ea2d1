"""The ``bench`` command: speed against error of every engine, one run."""

from __future__ import annotations

import sys


def _cmd_bench(args) -> int:
    from geomkit.bench.suite import ENGINES, FILES, format_table, run_suite, write_outputs
    from geomkit.errors import InvalidInputError
    from geomkit.cli._common import Outputs, emit_json

    engines = [e.strip() for e in args.engines.split(",") if e.strip()] if args.engines \
        else list(ENGINES)
    bad = [e for e in engines if e not in ENGINES]
    if bad or not engines:
        raise InvalidInputError(f"unknown engine(s) {bad}; choose from {', '.join(ENGINES)}",
                                "--engines")
    outputs = Outputs(args.output, FILES, args.overwrite)  # checked before minutes of work
    quiet = args.json or not sys.stderr.isatty()
    res = run_suite(engines, quick=not args.full,
                    progress=None if quiet else
                    (lambda m: print(m, file=sys.stderr, flush=True)))
    res["files"] = write_outputs(res, outputs.create(), args.overwrite)  # folder made now
    if args.json:
        emit_json({k: res[k] for k in ("mode", "seconds", "machine", "rows", "files")})
        return 0
    print(format_table(res["rows"]))
    print(f"\n{res['mode']} mode, {res['seconds']:.0f} s")
    for name, e in res["engines"].items():
        for note in e["notes"]:
            print(f"{name}: {note}")
    print(f"reports: {args.output}/ ({', '.join(FILES)})")
    return 0


def add_parser(sub):
    import argparse

    from geomkit.bench.suite import ENGINES

    p = sub.add_parser("bench", help="speed against error of every engine beside Open "
                                     "CASCADE / Coal",
                       formatter_class=argparse.RawDescriptionHelpFormatter,
                       description="Sweep each engine's tolerance (or size) and measure, in "
                                   "the same run, geomkit's time and achieved error (against "
                                   "analytic or dense oracles) beside Open CASCADE "
                                   "(evaluation, tessellation, projection, section, surface "
                                   "distance) and Coal (collision) when installed.  Writes "
                                   "bench.json, bench.md (the table) and bench.png (time "
                                   "against error per engine).",
                       epilog="example:\n  geomkit bench --engines projection,distance -o b\n"
                              "Quick mode takes ~3 min on 2 cores once the kernels are "
                              "compiled; --full takes longer.")
    p.add_argument("--full", action="store_true", help="the longer sweeps")
    p.add_argument("--engines", default=None,
                   help=f"comma-separated subset of {','.join(ENGINES)} (default all)")
    p.add_argument("-o", "--output", default="geomkit-bench",
                   help="report folder (default ./geomkit-bench)")
    p.add_argument("--overwrite", action="store_true", help="replace existing reports")
    p.add_argument("--json", action="store_true", help="machine-readable output")
    p.set_defaults(func=_cmd_bench)
    return p
