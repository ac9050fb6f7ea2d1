"""``geomkit bench``: speed against error for each engine, one run, one table, one plot.

Every engine sweeps its tolerance (or size) and, in the same run, measures geomkit's
time and achieved error beside the reference — Open CASCADE for evaluation,
tessellation, projection, section and surface distance; coal for collision — when
installed.  Errors always come from an oracle (analytic truth of the sample cases,
else the dense oracle of the distance tests), never from the engine's own report.
Each engine runs once before it is timed (JIT warm-up); times are medians of repeats.

Usage: ``python -m geomkit.bench.suite [--full] [--engines a,b] [-o DIR] [--overwrite]``
"""

from __future__ import annotations

import argparse
import importlib
import importlib.util
import json
import os
import platform
import sys
import time
from pathlib import Path

from geomkit.errors import InvalidInputError
from geomkit.bench._common import FIELDS

ENGINES = ("evaluation", "tessellate", "projection", "section", "distance", "collision",
           "parts", "fit")
FILES = ("bench.json", "bench.md", "bench.png")

#: Per engine: (module, keyword arguments of its ``sweep``) for quick and full mode.
CONFIG = {
    "evaluation": ("evaluation", dict(sizes=(1_000, 10_000, 100_000)),
                   dict(sizes=(1_000, 10_000, 100_000, 1_000_000), repeat=7)),
    "tessellate": ("tessellate", dict(cases=("sphere", "torus", "freeform_1", "heavy_weights"),
                                      tols=(1e-1, 3e-2, 1e-2, 3e-3), budget=1.0),
                   dict(cases=("sphere", "torus", "freeform_1", "crease", "heavy_weights"),
                        tols=(1e-1, 3e-2, 1e-2, 3e-3, 1e-3), budget=5.0)),
    "projection": ("projection", dict(n=10_000, occ_n=200,
                                      mesh_cases=("freeform_1", "plate_with_hole")),
                   dict(n=50_000, occ_n=1_000, repeat=5,
                        mesh_cases=("freeform_1", "sphere", "torus", "plate_with_hole",
                                    "impeller"), mesh_n=20_000)),
    "section": ("section", dict(tols=(1e-3, 1e-5, 1e-7)),
                dict(tols=(1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9))),
    "distance": ("distance", dict(cases=("sphere_pair", "offset_planes", "random_0",
                                         "random_1", "torus_sphere_axis")),
                 dict(cases=("sphere_pair", "offset_planes", "sphere_plane_cut", "random_0",
                             "random_1", "random_2", "random_3", "sphere_vs_plate_edge",
                             "torus_sphere_axis", "coaxial_cylinders", "concentric_spheres",
                             "parallel_trimmed_planes"),
                      tols=(1e-3, 1e-6, 1e-9, 1e-12), repeat=5)),
    "collision": ("collision", dict(tols=(1e-1, 3e-2, 1e-2), poses=100),
                  dict(tols=(1e-1, 3e-2, 1e-2, 3e-3), poses=200)),
    "parts": ("parts", dict(),
              dict(parts=("nx9_face_recognition_ap214.stp", "ug16_io1_ap214.stp",
                          "sw2018_base_interface_ap203.step", "sw2013_featuretype_ap214.step",
                          "proe_as1_ap203.stp", "euclid_screw_ap214.step",
                          "nist_ctc_01_ap203.stp", "nist_ftc_06_ap242.stp",
                          "nist_ftc_07_ap242.stp"))),
    "fit": ("fit", dict(sizes=(1_000, 100_000)), dict(sizes=(1_000, 100_000, 1_000_000))),
}

REFERENCES = {"evaluation": "occ", "tessellate": "occ", "projection": "occ", "section": "occ",
              "distance": "occ", "collision": "coal", "parts": "occ", "fit": "skspatial"}


def machine_info() -> dict:
    """CPU count, numba threads and layer, load, and the versions that matter."""
    import numba
    import numpy

    from geomkit.bench._common import coal_or_none, occ_or_none

    info = {"python": sys.version.split()[0], "platform": platform.platform(),
            "cpu_count": os.cpu_count(), "numba_threads": numba.get_num_threads(),
            "numpy": numpy.__version__, "numba": numba.__version__}
    try:
        info["numba_threading_layer"] = numba.threading_layer()
    except ValueError:  # no parallel kernel has run yet
        info["numba_threading_layer"] = None
    if hasattr(os, "getloadavg"):
        info["load_average"] = [round(x, 2) for x in os.getloadavg()]
    from importlib import metadata

    for dist in ("geomkit", "cadquery-ocp", "coal", "scipy", "trimesh"):
        try:
            info[dist] = metadata.version(dist)
        except metadata.PackageNotFoundError:
            info[dist] = None
    info["have_occ"] = occ_or_none() is not None
    info["have_coal"] = coal_or_none() is not None
    return info


def _targets(out_dir, overwrite):
    paths = {name: Path(out_dir) / name for name in FILES}
    if not overwrite:
        taken = [str(p) for p in paths.values() if p.exists()]
        if taken:
            raise FileExistsError(f"would overwrite {', '.join(taken)}; pass overwrite=True "
                                  "(--overwrite)")
    return paths


def run_suite(engines=None, quick=True, out_dir=None, progress=None, overwrite=False,
              config=None) -> dict:
    """Run the sweeps and (with ``out_dir``) write ``bench.json``, ``bench.md`` and
    ``bench.png`` there.

    Parameters
    ----------
    engines : iterable of str, optional
        Subset of :data:`ENGINES` (default: all).
    quick : bool
        The quick configuration (a few minutes on 2 cores) or the full one.
    out_dir : path, optional
        Folder for the three files (created if needed); files are written atomically
        and existing ones are kept unless ``overwrite`` (checked before any work).
    progress : callable(str), optional
        Called with a one-line message before and after each engine.
    config : dict, optional
        Per-engine keyword arguments for its ``sweep`` overriding the chosen mode
        (e.g. ``{"evaluation": {"sizes": (100,)}}``), for small test runs.

    Returns
    -------
    dict with ``rows`` (list of dicts with keys :data:`~geomkit.bench._common.FIELDS`),
    ``machine`` (:func:`machine_info`), ``engines`` (per engine: wall seconds and
    notes), ``mode``, ``seconds`` and ``files`` (paths written).
    """

    from geomkit.bench._common import MISSING_COAL, MISSING_OCC, coal_or_none, occ_or_none

    engines = list(ENGINES if engines is None else engines)
    unknown = [e for e in engines if e not in CONFIG]
    if unknown:
        raise InvalidInputError(f"unknown engine(s) {unknown}; choose from "
                                f"{', '.join(ENGINES)}", "engines")
    paths = _targets(out_dir, overwrite) if out_dir is not None else None
    say = progress or (lambda msg: None)
    config = config or {}
    have = {"occ": occ_or_none() is not None, "coal": coal_or_none() is not None,
            "skspatial": importlib.util.find_spec("skspatial") is not None}
    t_start = time.perf_counter()
    machine = machine_info()
    rows, per_engine = [], {}
    for k, name in enumerate(engines):
        module, quick_kw, full_kw = CONFIG[name]
        kw = dict(quick_kw if quick else full_kw)
        kw.update(config.get(name, {}))
        say(f"[{k + 1}/{len(engines)}] {name} ...")
        t0 = time.perf_counter()
        mod = importlib.import_module(f"geomkit.bench.{module}")
        new = mod.sweep(**kw)
        dt = time.perf_counter() - t0
        notes = [] if have[REFERENCES[name]] else [
            {"occ": MISSING_OCC, "coal": MISSING_COAL}.get(
                REFERENCES[name], "scikit-spatial not installed: its columns are empty")]
        per_engine[name] = {"seconds": dt, "rows": len(new), "settings": _jsonable(kw),
                            "notes": notes}
        rows.extend(new)
        say(f"[{k + 1}/{len(engines)}] {name}: {len(new)} rows in {dt:.1f} s")
    machine["load_average_end"] = ([round(x, 2) for x in os.getloadavg()]
                                   if hasattr(os, "getloadavg") else None)
    result = {"mode": "quick" if quick else "full", "rows": rows, "machine": machine,
              "engines": per_engine, "seconds": time.perf_counter() - t_start,
              "fields": list(FIELDS), "files": {}}
    if paths is not None:
        result["files"] = write_outputs(result, paths, overwrite)
    return result


def _jsonable(x):
    if isinstance(x, dict):
        return {k: _jsonable(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [_jsonable(v) for v in x]
    return x


def write_outputs(result, paths, overwrite=False) -> dict:
    """Write ``bench.json``, ``bench.md``, ``bench.png`` atomically (keeping existing
    files unless ``overwrite``); returns {name: path}."""
    from geomkit.outputs import atomic_write
    from geomkit.bench.plot import plot_rows

    for p in paths.values():
        if p.exists() and not overwrite:
            raise FileExistsError(f"{p} exists; pass overwrite=True")
    doc = {k: v for k, v in result.items() if k != "files"}
    text = json.dumps(doc, indent=1, allow_nan=True).encode("utf-8")
    atomic_write(paths["bench.json"], lambda fh: fh.write(text))
    md = (f"# geomkit bench ({result['mode']} mode, {result['seconds']:.0f} s)\n\n"
          f"{_machine_line(result['machine'])}\n\n{format_table(result['rows'])}\n")
    atomic_write(paths["bench.md"], lambda fh: fh.write(md.encode("utf-8")))
    atomic_write(paths["bench.png"], lambda fh: plot_rows(result["rows"], fh,
                                                           title=_machine_line(
                                                               result["machine"])))
    return {k: str(v) for k, v in paths.items()}


def _machine_line(m) -> str:
    load = m.get("load_average")
    return (f"{m.get('cpu_count')} CPUs, {m.get('numba_threads')} numba threads, "
            f"Python {m.get('python')}, numba {m.get('numba')}, "
            f"OCP {m.get('cadquery-ocp') or 'missing'}, coal {m.get('coal') or 'missing'}"
            + (f", load average at start {load[0]:.1f}" if load else ""))


def _sec(x) -> str:
    if x is None:
        return "-"
    for unit, f in (("s", 1.0), ("ms", 1e3), ("µs", 1e6), ("ns", 1e9)):
        if x * f >= 1.0 or unit == "ns":
            return f"{x * f:.3g} {unit}"
    return f"{x:.3g} s"  # pragma: no cover


def _err(x) -> str:
    if x is None:
        return "-"
    return "0" if x == 0 else f"{x:.1e}"


def _setting(r) -> str:
    v = r["setting"]
    if isinstance(v, float):  # one digit when that is the value (1e-03), else three
        txt = f"{v:.0e}"
        if abs(float(txt) - v) > 1e-9 * abs(v):
            txt = f"{v:.3g}"
    else:
        txt = f"{v:,}"
    return f"{r['setting_name']} {txt}"


def format_table(rows) -> str:
    """The rows as a markdown table (one line per row; times per ``per``)."""
    head = ("| engine | case | setting | per | geomkit time | geomkit error | reference | "
            "reference time | reference error | speed-up | note |")
    out = [head, "|" + "---|" * head.count(" | ") + "---|"]
    for r in rows:
        sp = "-" if r["speedup"] is None else f"{r['speedup']:.3g}×"
        out.append(f"| {r['engine']} | {r['case']} | {_setting(r)} | {r['per']} | "
                   f"{_sec(r['geomkit_seconds'])} | {_err(r['geomkit_error'])} | "
                   f"{r['reference_name'] or '-'} | {_sec(r['reference_seconds'])} | "
                   f"{_err(r['reference_error'])} | {sp} | {r['note']} |")
    return "\n".join(out)


def main(argv=None):
    ap = argparse.ArgumentParser(prog="python -m geomkit.bench.suite",
                                 description=__doc__.splitlines()[0])
    ap.add_argument("--full", action="store_true", help="the longer sweeps")
    ap.add_argument("--engines", default=",".join(ENGINES),
                    help=f"comma list of: {', '.join(ENGINES)}")
    ap.add_argument("-o", "--out-dir", default=None, help="write bench.json/.md/.png here")
    ap.add_argument("--overwrite", action="store_true", help="replace existing files")
    a = ap.parse_args(argv)
    engines = [e.strip() for e in a.engines.split(",") if e.strip()]
    res = run_suite(engines, quick=not a.full, out_dir=a.out_dir,
                    progress=lambda m: print(m, file=sys.stderr, flush=True),
                    overwrite=a.overwrite)
    print(format_table(res["rows"]))
    print(f"\n{res['mode']} mode, {res['seconds']:.0f} s; {_machine_line(res['machine'])}")
    for name, e in res["engines"].items():
        for note in e["notes"]:
            print(f"{name}: {note}")
    for p in res["files"].values():
        print(f"wrote {p}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
