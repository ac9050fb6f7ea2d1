"""Pieces shared by the report writers (PNG in :mod:`geomkit.report.files`, HTML in
:mod:`geomkit.report.html`, PDF in :mod:`geomkit.report.pdf`): unit labels, the
tolerance-band colour scale, a plane's own 2-D frame, the report header (part file and
its SHA-256, date, version) and the deviation statistics table."""

from __future__ import annotations

import datetime as _dt
import hashlib
import math
from pathlib import Path

import numpy as np

from geomkit.units import unit_label

WORST_N = 10
"""Worst points called out by name in the deviation reports."""


# ------------------------------------------------------------------------ units
def axis_label(name: str, units: str | None) -> str:
    """``"x [mm]"``."""
    return f"{name} [{unit_label(units)}]"


def fmt(x, digits: int = 4) -> str:
    """A number for a table: ``"-"`` for NaN / None."""
    if x is None:
        return "-"
    x = float(x)
    return f"{x:.{digits}g}" if math.isfinite(x) else "-"


# ---------------------------------------------------------------- colour scale
_BELOW = ("#08306b", "#2171b5", "#6baed6")   # far below .. just below the band
_ABOVE = ("#fdd835", "#fb8c00", "#b71c1c")   # just above .. far above
IN_TOL = "#2ca25f"
"""In-tolerance colour (one colour for the whole band)."""


def colour_stops(tolerance, m: float) -> list:
    """``[(position in [0, 1], colour), ...]`` over ``[-m, m]``: inside the tolerance
    band one colour (:data:`IN_TOL`), graded beyond it (blues below, yellow to red
    above).  Without a tolerance: a blue - green - red scale centred on 0.  Usable as a
    plotly colourscale and by ``LinearSegmentedColormap.from_list``."""
    m = float(m) if m > 0 else 1.0
    pos = (lambda v: min(max((v + m) / (2 * m), 0.0), 1.0))
    if not tolerance:
        return [(0.0, _BELOW[0]), (0.25, _BELOW[2]), (0.5, IN_TOL), (0.75, _ABOVE[0]),
                (1.0, _ABOVE[2])]
    lo, hi = (float(t) for t in tolerance)
    a, b = pos(lo), pos(hi)
    eps = 1e-6
    stops = []
    if a > eps:
        stops += [(0.0, _BELOW[0]), (a / 2, _BELOW[1]), (max(a - eps, 0.0), _BELOW[2])]
    stops += [(a, IN_TOL), (b, IN_TOL)]
    if b < 1 - eps:
        stops += [(min(b + eps, 1.0), _ABOVE[0]), ((b + 1) / 2, _ABOVE[1]), (1.0, _ABOVE[2])]
    if stops[0][0] > 0:
        stops.insert(0, (0.0, stops[0][1]))
    if stops[-1][0] < 1:
        stops.append((1.0, stops[-1][1]))
    return stops


def colour_range(rep) -> float:
    """Half-width ``m`` of the symmetric colour range: the largest |deviation|, at least
    1.5 x the tolerance limits (so the band shows as a band)."""
    v = rep.deviation[np.isfinite(rep.deviation)]
    m = float(np.abs(v).max()) if v.size else 0.0
    if rep.tolerance:
        m = max(m, 1.5 * max(abs(t) for t in rep.tolerance))
    return m if m > 0 else 1.0


def mpl_cmap(tolerance, m):
    from matplotlib.colors import LinearSegmentedColormap

    return LinearSegmentedColormap.from_list("geomkit_band", colour_stops(tolerance, m),
                                             N=512)


# ---------------------------------------------------------------- plane frames
_AXES = "xyz"


def plane_frame(plane):
    """A plane's own 2-D frame: ``(origin (3,), e1 (3,), e2 (3,), labels (2,))``.

    ``e1, e2`` are the two world axes other than the normal's largest component (x, y
    or z in that order), made orthonormal in the plane; the labels are those axes'
    names when the plane is axis-aligned, else ``"s"`` / ``"t"``.  The origin is the
    foot of the world origin."""
    pl = np.asarray(plane, float)
    n = pl[:3] / np.linalg.norm(pl[:3])
    k = int(np.argmax(np.abs(n)))
    i, j = [a for a in range(3) if a != k]
    e1 = np.eye(3)[i] - n[i] * n
    e1 /= np.linalg.norm(e1)
    e2 = np.eye(3)[j] - n[j] * n - (e1 @ np.eye(3)[j]) * e1
    e2 /= np.linalg.norm(e2)
    aligned = abs(abs(n[k]) - 1.0) < 1e-12
    labels = (_AXES[i], _AXES[j]) if aligned else ("s", "t")
    return -pl[3] * n, e1, e2, labels


def plane_name(plane, units=None) -> str:
    """``"x = 10"`` for an axis-aligned plane, else ``"0.6 x + 0.8 y - 3 = 0"``."""
    a, b, c, d = (float(t) for t in plane)
    n = np.array([a, b, c])
    k = int(np.argmax(np.abs(n)))
    if abs(abs(n[k]) - 1.0) < 1e-12:
        return f"{_AXES[k]} = {-d / n[k]:.6g}"
    terms = " ".join(f"{v:+.4g} {ax}" for v, ax in zip(n, _AXES) if v != 0)
    return f"{terms} {d:+.6g} = 0".lstrip("+")


def to_plane(points, plane) -> np.ndarray:
    """(n, 3) points -> (n, 2) coordinates in :func:`plane_frame`."""
    o, e1, e2, _ = plane_frame(plane)
    P = np.asarray(points, float).reshape(-1, 3) - o
    return np.column_stack([P @ e1, P @ e2])


# ---------------------------------------------------------------------- header
def sha256(path) -> str | None:
    """Hex SHA-256 of a file, None when it is not a readable file."""
    try:
        h = hashlib.sha256()
        with open(path, "rb") as fh:
            for chunk in iter(lambda: fh.read(1 << 20), b""):
                h.update(chunk)
        return h.hexdigest()
    except (OSError, TypeError):
        return None


def header(title: str, part=None, units=None, tolerance=None, model_note=None,
           extra: dict | None = None) -> dict:
    """The report header as an ordered ``{label: text}``: part file (a path, or a
    bundled sample name resolved to its file) and SHA-256, date (UTC), geomkit version,
    units, tolerance, model note and ``extra`` rows."""
    from geomkit.version import __version__

    rows = {"report": title}
    if part is not None:
        p = Path(str(part))
        if not p.is_file():
            from geomkit import samples

            if str(part) in samples.names():
                p = Path(str(samples.path(str(part))))
        rows["part file"] = str(part)
        rows["SHA-256"] = sha256(p) or "- (not a file)"
    rows["date"] = _dt.datetime.now(_dt.timezone.utc).strftime("%Y-%m-%d %H:%M:%S UTC")
    rows["geomkit"] = __version__
    rows["units"] = unit_label(units)
    if tolerance is not None:
        lo, hi = tolerance
        rows["tolerance"] = f"[{lo:g}, {hi:g}] {unit_label(units)}"
    if model_note:
        rows["model"] = str(model_note)
    for k, v in (extra or {}).items():
        rows[k] = str(v)
    return rows


# ------------------------------------------------------------------ statistics
def deviation_table(rep) -> list[tuple[str, str]]:
    """Rows ``(name, value)`` of the deviation statistics: n, min, max, mean, sigma,
    rms, % in / over / under tolerance and, when both limits are given, Cp and Cpk
    (sigma with n - 1)."""
    v = rep.deviation[np.isfinite(rep.deviation)]
    s = rep.stats
    rows = [("points", f"{s['points']}"), ("matched", f"{s['valid']}"),
            ("on edges", f"{s['edge']}")]
    if s.get("beyond"):
        rows.append(("beyond max distance", f"{s['beyond']}"))
    sigma = float(v.std(ddof=1)) if v.size > 1 else float("nan")
    rows += [("min", fmt(s["min"], 6)), ("max", fmt(s["max"], 6)),
             ("mean", fmt(s["mean"], 6)), ("sigma (n-1)", fmt(sigma, 6)),
             ("rms", fmt(s["rms"], 6))]
    if rep.tolerance:
        lo, hi = rep.tolerance
        rows += [("in tolerance", f"{s['within']} ({fmt(s['pct_within'], 4)} %)"),
                 ("over", f"{s['over']} ({fmt(s['pct_over'], 4)} %)"),
                 ("under", f"{s['under']} ({fmt(s['pct_under'], 4)} %)")]
        if sigma > 0 and hi > lo:
            mu = float(v.mean())
            rows += [("Cp", fmt((hi - lo) / (6 * sigma), 4)),
                     ("Cpk", fmt(min(hi - mu, mu - lo) / (3 * sigma), 4))]
    if rep.probe_radius:
        rows.append(("probe radius", f"{rep.probe_radius:g}"))
    return rows


def worst_points(rep, n: int = WORST_N) -> np.ndarray:
    """Indices of the ``n`` points farthest outside the tolerance band (by |deviation|
    when there is none), worst first; only matched points."""
    d = rep.deviation
    ok = np.flatnonzero(np.isfinite(d))
    if not ok.size:
        return ok
    if rep.tolerance:
        lo, hi = rep.tolerance
        excess = np.maximum(d[ok] - hi, lo - d[ok])
    else:
        excess = np.abs(d[ok])
    return ok[np.argsort(-excess, kind="stable")[:n]]


def alignment_rows(rep) -> list[tuple[str, str]]:
    a = rep.stats.get("alignment")
    if not a:
        return [("alignment", "none (points used as measured)")]
    T = np.asarray(a["transform"])
    ang = math.degrees(math.acos(min(1.0, max(-1.0, (np.trace(T[:3, :3]) - 1) / 2))))
    return [("alignment", "best-fit rigid (point-to-plane on the exact feet)"),
            ("rms before / after", f"{fmt(a['rms_before'], 6)} / {fmt(a['rms_after'], 6)}"),
            ("iterations", f"{a['iterations']} (converged: {a['converged']}, rank "
                           f"{a['rank']})"),
            ("rotation", f"{ang:.6g} deg"),
            ("translation", " ".join(f"{t:.6g}" for t in T[:3, 3]))]


def probing_mask(n: int, probing=()) -> np.ndarray:
    """(n,) bool: the moves that are meant to touch (probing moves)."""
    m = np.zeros(n, bool)
    for k in probing or ():
        if not -n <= int(k) < n:
            from geomkit.errors import InvalidInputError

            raise InvalidInputError(f"move {k} out of range (0..{n - 1})", "probing")
        m[int(k)] = True
    return m
