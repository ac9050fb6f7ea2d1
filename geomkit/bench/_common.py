"""Shared pieces of the speed-against-error sweeps: the row schema, timing, and the
optional references (Open CASCADE, coal), each found or reported missing cleanly."""

from __future__ import annotations

import time

import numpy as np

#: Keys of every sweep row (see :func:`make_row`).
FIELDS = ("engine", "case", "setting_name", "setting", "per", "geomkit_seconds",
          "geomkit_error", "reference_name", "reference_seconds", "reference_error",
          "speedup", "repeats", "note")


def make_row(engine, case, setting_name, setting, geomkit_seconds, geomkit_error,
             reference_name=None, reference_seconds=None, reference_error=None,
             per="call", repeats=1, note=""):
    """One row of the common schema.

    ``*_seconds`` are medians of ``repeats`` timed runs (per ``per``: one call, one
    point, one query); ``*_error`` are measured against an oracle (never reported by
    the engine itself), in model units; ``speedup`` is reference / geomkit time
    (None without a reference).
    """
    def f(x):
        return None if x is None else float(x)

    gs, rs = f(geomkit_seconds), f(reference_seconds)
    speedup = rs / gs if (rs is not None and gs and gs > 0) else None
    return {"engine": engine, "case": case, "setting_name": setting_name,
            "setting": setting if isinstance(setting, (int, str)) else float(setting),
            "per": per, "geomkit_seconds": gs, "geomkit_error": f(geomkit_error),
            "reference_name": reference_name, "reference_seconds": rs,
            "reference_error": f(reference_error), "speedup": speedup,
            "repeats": int(repeats), "note": note}


def median_time(fn, repeat=3, budget=None):
    """Time ``fn()`` up to ``repeat`` times; returns (median wall seconds, the last
    result, runs made).  With ``budget`` (seconds) no new run starts once the runs so
    far took longer (at least one run is always made)."""
    ts, out = [], None
    for _ in range(max(1, int(repeat))):
        t0 = time.perf_counter()
        out = fn()
        ts.append(time.perf_counter() - t0)
        if budget is not None and sum(ts) > budget:
            break
    return float(np.median(ts)), out, len(ts)


def occ_or_none():
    """The Open CASCADE oracle module, or None when ``cadquery-ocp`` is missing."""
    try:
        from geomkit.bench.oracles import occ
    except Exception:  # noqa: BLE001 - the reference is optional
        return None
    return occ if occ.HAVE_OCP else None


def coal_or_none():
    """The ``coal`` module, or None when it is not installed."""
    try:
        import coal
    except Exception:  # noqa: BLE001 - the reference is optional
        return None
    return coal


def occ_surface(occ, s):
    return occ.make_surface(s.degree_u, s.degree_v, s.knots_u, s.knots_v,
                            s.control_points, s.weights)


def occ_face(occ, s):
    trim = [[c.to_dict() for c in loop.pieces] for loop in s.trim] or None
    return occ.make_face(s.degree_u, s.degree_v, s.knots_u, s.knots_v, s.control_points,
                         s.weights, trim=trim)


MISSING_OCC = "reference skipped: Open CASCADE (cadquery-ocp) not installed"
MISSING_COAL = "reference skipped: coal not installed"
