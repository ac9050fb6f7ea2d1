"""Report writers for the jobs: deviation CSV, summary JSON, colour-map and histogram
PNGs, section exports, probe-clearance CSV and chart.  The HTML and PDF reports are in
:mod:`geomkit.report.html` and :mod:`geomkit.report.pdf`.

Every writer takes ``units`` (e.g. ``"mm"``; None: "model units"): CSV files get a
``units`` column, JSON a ``units`` field, plots axis labels like ``x [mm]``; and
``model_note`` (e.g. "partial model: 30 of 277 faces left out"), shown in plot titles
and JSON.

Every file is written through a temporary file in the target folder and renamed into
place (:func:`geomkit.outputs.atomic_write`), so an interrupted run never leaves a
half-written file under a final name; existing files are kept unless
``overwrite=True``.  :func:`prepare_outputs` checks the whole set of targets (folder
writable, nothing overwritten, no input among them) before any work starts; the jobs
write the summary JSON last, so a folder with a summary holds a complete report.
"""

from __future__ import annotations

import io
import json
import math
import os
import tempfile
from pathlib import Path

import numpy as np

from geomkit.units import unit_label
from geomkit.nurbs.surface import as_surfaces
from geomkit.report import common as rc
from geomkit.errors import InvalidInputError
from geomkit.outputs import atomic_write, check_target, json_safe
from geomkit.query.results import STATUS_NAMES

__all__ = ["prepare_outputs", "write_deviation_csv", "write_json", "plot_deviation_map",
           "plot_histogram", "plot_section", "write_section", "write_clearance_csv",
           "plot_clearance", "clearance_counts", "section_figure"]


def prepare_outputs(folder, names, overwrite: bool = False, inputs=()) -> dict:
    """Check that the report files ``names`` can be written into ``folder``.

    Creates the folder if needed, checks it is writable (by creating and removing a
    temporary file), refuses existing files unless ``overwrite`` and refuses any
    target that is one of ``inputs``.

    Returns
    -------
    dict
        ``{name: Path}`` of the targets.

    Raises
    ------
    InvalidInputError
        The folder cannot be created or written.
    FileExistsError
        A target exists (without ``overwrite``) or is an input file.
    """
    d = Path(folder)
    if d.exists() and not d.is_dir():
        raise InvalidInputError(f"{d}: exists and is not a folder", "output folder")
    try:
        d.mkdir(parents=True, exist_ok=True)
        fd, tmp = tempfile.mkstemp(prefix=".geomkit-write-test.", dir=d)
        os.close(fd)
        os.unlink(tmp)
    except OSError as exc:
        raise InvalidInputError(f"{d}: cannot write here ({exc.strerror or exc})",
                                "output folder") from None
    targets = {n: d / n for n in names}
    ins = set()
    for p in inputs:
        try:
            if Path(p).exists():
                ins.add(Path(p).resolve())
        except OSError:
            pass
    for p in targets.values():
        if p.exists() and p.resolve() in ins:
            raise FileExistsError(f"{p}: is an input; choose another output folder")
        if p.exists() and not overwrite:
            raise FileExistsError(f"{p}: exists; pass --overwrite to replace it")
    return targets


def _fmt(x) -> str:
    x = float(x)
    return repr(x) if math.isfinite(x) else ""


def _csv_units(units) -> str:
    """The ``units`` cell: the unit name, quoted if it holds a comma."""
    u = unit_label(units)
    return f'"{u}"' if ("," in u or '"' in u) else u


def write_deviation_csv(rep, path, overwrite: bool = False, units: str | None = None,
                        model_note: str | None = None) -> Path:
    """One row per point: ``index, x, y, z`` (as measured), ``ax, ay, az`` (aligned),
    ``foot_x.. foot_z, u, v, surface, nx, ny, nz, signed_distance, deviation, status,
    edge, units`` (empty cells where there is no foot; ``units`` names the length unit
    of every coordinate and distance, "model units" when unknown).  ``model_note`` is
    not written (a CSV has no place for it; the summary JSON carries it)."""
    p = check_target(path, overwrite)
    head = ("index,x,y,z,ax,ay,az,foot_x,foot_y,foot_z,u,v,surface,nx,ny,nz,"
            "signed_distance,deviation,status,edge,units")
    lines = [head]
    u = _csv_units(units)
    for i in range(len(rep)):
        vals = [str(i)]
        vals += [_fmt(c) for c in rep.points[i]]
        vals += [_fmt(c) for c in rep.aligned[i]]
        vals += [_fmt(c) for c in rep.foot[i]]
        vals += [_fmt(c) for c in rep.uv[i]]
        vals.append(str(int(rep.surface[i])))
        vals += [_fmt(c) for c in rep.normal[i]]
        vals += [_fmt(rep.signed_distance[i]), _fmt(rep.deviation[i]),
                 STATUS_NAMES.get(int(rep.status[i]), str(int(rep.status[i]))),
                 str(int(bool(rep.edge[i]))), u]
        lines.append(",".join(vals))
    data = ("\n".join(lines) + "\n").encode("utf-8")
    return atomic_write(p, lambda fh: fh.write(data))


def write_json(doc: dict, path, overwrite: bool = False, units: str | None = None,
               model_note: str | None = None) -> Path:
    """Write a JSON document atomically (NaN written as null).  ``units`` and
    ``model_note``, when given, are added as fields of the same names unless ``doc``
    has them (a ``units`` the caller wants to show as "model units" should be put in
    ``doc`` so that what is printed and what is written agree)."""
    p = check_target(path, overwrite)
    doc = dict(doc)
    if units is not None:
        doc.setdefault("units", unit_label(units))
    if model_note:
        doc.setdefault("model_note", model_note)
    data = json.dumps(json_safe(doc), indent=1, allow_nan=False).encode("utf-8")
    return atomic_write(p, lambda fh: fh.write(data))


def _save_fig(fig, path, overwrite, dpi=120) -> Path:
    p = check_target(path, overwrite)
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=dpi)
    data = buf.getvalue()
    return atomic_write(p, lambda fh: fh.write(data))


def _figure(**kw):
    """A matplotlib Figure not attached to pyplot (no GUI backend, no global state)."""
    import mpl_toolkits.mplot3d  # noqa: F401  registers the 3-D projection
    from matplotlib.figure import Figure

    return Figure(**kw)


def _title(text: str, model_note) -> str:
    return f"{text}\n{model_note}" if model_note else text


def _few_ticks(ax, n=5, spans=None):
    """At most ``n`` ticks per axis (3-D tick labels overlap otherwise); with the axes'
    drawn lengths ``spans``, fewer on the short ones."""
    from matplotlib.ticker import MaxNLocator

    axes = (ax.xaxis, ax.yaxis) + ((ax.zaxis,) if hasattr(ax, "zaxis") else ())
    spans = np.ones(len(axes)) if spans is None else np.asarray(spans, float)
    for a, sp in zip(axes, spans / max(spans.max(), 1e-300)):
        a.set_major_locator(MaxNLocator(max(2, min(n, int(round(n * sp)))), min_n_ticks=2))


def _nominal_mesh(surfaces, mesh_tol=None):
    from geomkit.mesh.tessellate import tessellate

    surfs = as_surfaces(surfaces)
    size = max(s.size for s in surfs)
    return tessellate(surfs, mesh_tol or 5e-3 * size), size


def _scatter_deviation(ax, rep, P, cmap, m, s=8, **kw):
    """Points coloured by deviation, edge points as triangles, unmatched as black x;
    returns the mappable.  ``P``: the points' (n, 2) or (n, 3) plot coordinates."""
    ok = np.isfinite(rep.deviation)
    inner = ok & ~rep.edge
    opts = dict(cmap=cmap, vmin=-m, vmax=m, edgecolors="k", linewidths=0.15, **kw)
    sc = ax.scatter(*P[inner].T, c=rep.deviation[inner], s=s, **opts)
    if (ok & rep.edge).any():
        e = ok & rep.edge
        ax.scatter(*P[e].T, c=rep.deviation[e], s=1.8 * s, marker="^", **opts)
    if (~ok).any():
        ax.scatter(*P[~ok].T, color="k", s=s, marker="x", **kw)
    return sc


def _colorbar(fig, sc, ax, rep, units, **kw):
    cb = fig.colorbar(sc, ax=ax, **kw)
    cb.set_label(rc.axis_label("deviation", units))
    if rep.tolerance:
        for t in rep.tolerance:
            cb.ax.axhline(t, color="k", lw=1)
    return cb


def deviation_map_axes(fig, ax, rep, mesh, units=None, elev=30.0, azim=-60.0):
    """Draw the deviation colour map on a 3-D axis: the nominal mesh as a light,
    translucent surface under the points (points always drawn on top, outlined, so
    in-tolerance points stay visible); returns the scatter mappable."""
    V, F = mesh.vertices, mesh.faces
    ax.computed_zorder = False
    ax.plot_trisurf(V[:, 0], V[:, 1], V[:, 2], triangles=F, color=(0.87, 0.89, 0.93),
                    alpha=0.25, linewidth=0, zorder=1)
    m = rc.colour_range(rep)
    cmap = rc.mpl_cmap(rep.tolerance, m)
    ok = np.isfinite(rep.deviation)
    sc = _scatter_deviation(ax, rep, rep.aligned, cmap, m, depthshade=False, zorder=3)
    for a, n in zip("xyz", ("set_xlabel", "set_ylabel", "set_zlabel")):
        getattr(ax, n)(rc.axis_label(a, units), labelpad=6)
    ax.tick_params(labelsize=7)
    ax.view_init(elev=elev, azim=azim)
    span = np.ptp(np.vstack([V, rep.aligned[ok]]), axis=0)
    box = np.maximum(span, 0.05 * span.max()) + 1e-12
    ax.set_box_aspect(box)
    _few_ticks(ax, 5, box)
    return sc


def plot_deviation_map(rep, surfaces, path, overwrite: bool = False, mesh_tol=None,
                       units: str | None = None, model_note: str | None = None) -> Path:
    """PNG: the nominal surfaces' tessellation (light, translucent) under the points
    coloured by deviation (tolerance band one colour, graded beyond it; edge points
    as triangles, unmatched points as black x)."""
    mesh, _ = _nominal_mesh(surfaces, mesh_tol)
    fig = _figure(figsize=(8, 6.4))
    ax = fig.add_subplot(projection="3d")
    sc = deviation_map_axes(fig, ax, rep, mesh, units)
    _colorbar(fig, sc, ax, rep, units, shrink=0.7, pad=0.1)
    s = rep.stats
    u = unit_label(units)
    ax.set_title(_title(f"{s['valid']} points: min {s['min']:.4g}, max {s['max']:.4g}, "
                        f"rms {s['rms']:.4g} {u}", model_note), fontsize=10)
    return _save_fig(fig, path, overwrite)


def histogram_axes(ax, rep, units=None, bins: int = 40):
    """Histogram of the deviations, bars coloured like the map, tolerance limits as
    dashed lines."""
    v = rep.deviation[np.isfinite(rep.deviation)]
    m = rc.colour_range(rep)
    if v.size:
        cnt, edges, patches = ax.hist(v, bins=bins, edgecolor="white", linewidth=0.4)
        cmap = rc.mpl_cmap(rep.tolerance, m)
        for c, pa in zip(0.5 * (edges[1:] + edges[:-1]), patches):
            pa.set_facecolor(cmap((c + m) / (2 * m)))
    if rep.tolerance:
        lo, hi = rep.tolerance
        for t, name in ((lo, "lower"), (hi, "upper")):
            ax.axvline(t, color="k", ls="--", lw=1)
        ax.axvspan(lo, hi, color=rc.IN_TOL, alpha=0.08,
                   label=f"tolerance [{lo:g}, {hi:g}]")
        ax.legend(fontsize=8)
    ax.set_xlabel(rc.axis_label("deviation along the nominal normal", units))
    ax.set_ylabel("points")
    _few_ticks(ax, 7)


def plot_histogram(rep, path, overwrite: bool = False, bins: int = 40,
                   units: str | None = None, model_note: str | None = None) -> Path:
    """PNG: histogram of the deviations with the tolerance limits marked."""
    fig = _figure(figsize=(7, 4.5), layout="constrained")
    ax = fig.add_subplot()
    histogram_axes(ax, rep, units, bins)
    s = rep.stats
    title = f"mean {s['mean']:.4g}, std {s['std']:.4g}, rms {s['rms']:.4g}"
    if rep.tolerance:
        title += f"; in {s['pct_within']:.1f}%, over {s['pct_over']:.1f}%, " \
                 f"under {s['pct_under']:.1f}%"
    ax.set_title(_title(title, model_note), fontsize=9)
    return _save_fig(fig, path, overwrite)


MAX_PANELS = 12
"""Section plots draw at most this many planes (one panel each)."""


def section_figure(sections, units=None, model_note=None, figsize=None):
    """A Figure with one 2-D panel per plane, in the plane's own coordinates
    (:func:`geomkit.report.common.plane_frame`), equal aspect, titled with the plane."""
    sections = list(sections)
    shown = sections[:MAX_PANELS]
    k = max(len(shown), 1)
    ext = np.zeros(2)
    for sec in shown:
        for X in sec.curves:
            ext = np.maximum(ext, np.ptp(rc.to_plane(X, sec.plane), axis=0))
    tall = ext[1] > ext[0]
    cols = min(k, 6) if tall else (1 if k <= 3 else 2)
    rows = -(-k // cols)
    w = 10 if cols > 1 else 7.5
    aspect = (ext[1] / ext[0]) if ext.min() > 0 else 0.6
    h = min(max(w / cols * min(max(aspect, 0.25), 2.5), 1.6), 7) * rows + 0.8
    fig = _figure(figsize=figsize or (w, h), layout="constrained")
    n = sum(len(s.curves) for s in sections)
    head = f"{len(sections)} plane(s), {n} curve(s)"
    if len(sections) > len(shown):
        head += f" (first {len(shown)} planes shown)"
    fig.suptitle(_title(head, model_note), fontsize=10)
    for i, sec in enumerate(shown):
        ax = fig.add_subplot(rows, cols, i + 1)
        _, _, _, (l1, l2) = rc.plane_frame(sec.plane)
        for j, (X, closed) in enumerate(zip(sec.curves, sec.closed)):
            Q = rc.to_plane(np.concatenate([X, X[:1]]) if closed else X, sec.plane)
            ax.plot(Q[:, 0], Q[:, 1], lw=1.2, color=f"C{j % 10}")
        if len(sec.points):
            Q = rc.to_plane(sec.points, sec.plane)
            ax.plot(Q[:, 0], Q[:, 1], "ko", ms=3)
        ax.set_aspect("equal", adjustable="box")
        ax.set_xlabel(rc.axis_label(l1, units), fontsize=8)
        ax.set_ylabel(rc.axis_label(l2, units), fontsize=8)
        ax.tick_params(labelsize=7)
        Q = np.vstack([rc.to_plane(X, sec.plane) for X in sec.curves] or [np.zeros((1, 2))])
        _few_ticks(ax, 6, np.maximum(np.ptp(Q, axis=0), 1e-12))
        ax.grid(True, lw=0.3)
        ax.set_title(f"plane {rc.plane_name(sec.plane)}: {len(sec.curves)} curve(s)",
                     fontsize=9)
    return fig


def plot_section(sections, path, overwrite: bool = False, units: str | None = None,
                 model_note: str | None = None) -> Path:
    """PNG: the section curves, one 2-D panel per plane in the plane's own coordinates
    (equal aspect; at most :data:`MAX_PANELS` planes)."""
    return _save_fig(section_figure(sections, units, model_note), path, overwrite)


def write_section(section, targets: dict, fit_tol=None, overwrite: bool = False,
                  units: str | None = None, model_note: str | None = None) -> dict:
    """Write one :class:`~geomkit.Section` to the targets of ``{"csv", "dxf", "json",
    "png"}`` present in ``targets`` (each atomically); returns ``{kind: path}``."""
    out = {}
    if "csv" in targets:
        out["csv"] = str(section.to_csv(targets["csv"], overwrite=overwrite))
    if "dxf" in targets:
        out["dxf"] = str(section.to_dxf(targets["dxf"], fit_tol=fit_tol, overwrite=overwrite))
    if "json" in targets:
        out["json"] = str(section.to_json(targets["json"], fit_tol=fit_tol,
                                          overwrite=overwrite))
    if "png" in targets:
        out["png"] = str(plot_section([section], targets["png"], overwrite=overwrite,
                                       units=units, model_note=model_note))
    return out



def write_clearance_csv(res, path_points, path, overwrite: bool = False,
                        units: str | None = None, model_note: str | None = None) -> Path:
    """One row per path segment of a :class:`geomkit.Clearance`: ``segment``, start and
    end tip centres, ``motion``, ``clearance``, ``lower_bound``, ``component``,
    ``parameter``, the closest part point, ``surface``, ``first_contact`` (empty when
    clear), ``passed``, ``certified``, each stylus piece's clearance and ``units`` (the
    length unit of coordinates and clearances, "model units" when unknown)."""
    p = check_target(path, overwrite)
    names = list(res.component_names)
    head = ["segment", "x0", "y0", "z0", "x1", "y1", "z1", "motion", "clearance",
            "lower_bound", "component", "parameter", "part_x", "part_y", "part_z",
            "surface", "first_contact", "passed", "certified"] + [f"clearance_{n}"
                                                                  for n in names] + ["units"]
    lines = [",".join(head)]
    u = _csv_units(units)
    for i in range(len(res)):
        vals = [str(i)] + [_fmt(c) for c in path_points[i]] + [_fmt(c) for c in
                                                               path_points[i + 1]]
        vals += [res.motion[i], _fmt(res.clearance[i]), _fmt(res.lower_bound[i]),
                 names[int(res.component[i])], _fmt(res.parameter[i])]
        vals += [_fmt(c) for c in res.point_part[i]]
        vals += [str(int(res.surface[i])), _fmt(res.first_contact[i]),
                 str(int(bool(res.passed[i]))), str(int(bool(res.certified[i])))]
        vals += [_fmt(c) for c in res.per_component[i]] + [u]
        lines.append(",".join(vals))
    data = ("\n".join(lines) + "\n").encode("utf-8")
    return atomic_write(p, lambda fh: fh.write(data))


def clearance_counts(res, probing=()) -> dict:
    """How the reports count moves: ``probing`` moves (meant to touch, e.g. a
    measuring plunge) are not failures; the others are travel moves.  Returns
    ``{"moves", "travel", "travel_failed", "probing"}`` (index lists)."""
    pm = rc.probing_mask(len(res), probing)
    travel = np.flatnonzero(~pm)
    return {"moves": len(res), "travel": travel.tolist(),
            "travel_failed": travel[~res.passed[travel]].tolist(),
            "probing": np.flatnonzero(pm).tolist()}


def clearance_title(res, probing=()) -> str:
    """``"1 of 3 travel moves fail the margin 2; ..."``: the same count as the console."""
    c = clearance_counts(res, probing)
    nt, nf = len(c["travel"]), len(c["travel_failed"])
    kind = "travel moves" if c["probing"] else "moves"
    text = f"{nf} of {nt} {kind} fail" if nf else f"all {nt} {kind} pass"
    text += f" (margin {res.margin:g})" if res.margin > 0 else " (no contact)"
    if nt:
        lb = res.lower_bound[c["travel"]]
        text += f"; min certified clearance {float(np.min(lb)):.4g}"
    for k in c["probing"]:
        fc = res.first_contact[k]
        text += (f"; probing move {k}: first contact at s = {fc:.4f}" if np.isfinite(fc)
                 else f"; probing move {k}: no contact")
    return text


def clearance_axes(ax, res, units=None, probing=()):
    """Bar chart of the certified clearance per move: travel moves green (pass) or red
    (fail), probing moves blue; first contacts marked; the margin as a dashed line."""
    pm = rc.probing_mask(len(res), probing)
    k = np.arange(len(res))
    colours = ["tab:blue" if p else ("tab:green" if ok else "tab:red")
               for ok, p in zip(res.passed, pm)]
    bars = ax.bar(k, res.lower_bound, color=colours, edgecolor="black", linewidth=0.5)
    top = float(np.max(res.lower_bound)) if len(res) else 1.0
    for i, (b, fc) in enumerate(zip(bars, res.first_contact)):
        if np.isfinite(fc):
            b.set_hatch("//")
            col = "tab:blue" if pm[i] else "tab:red"
            ax.plot([i], [0.0], marker="x", color=col, markersize=10, mew=2)
            ax.annotate(f"{'probe ' if pm[i] else ''}contact\ns = {fc:.4f}", (i, 0.0),
                        xytext=(0, 8), textcoords="offset points", ha="center", color=col,
                        fontsize=8)
    ax.set_ylim(0.0, 1.2 * max(top, res.margin, 1e-12))
    if res.margin > 0:
        ax.axhline(res.margin, color="black", linestyle="--", linewidth=1,
                   label=f"margin {res.margin:g}")
    from matplotlib.patches import Patch

    handles = [Patch(color="tab:green", label="pass"), Patch(color="tab:red", label="fail")]
    if pm.any():
        handles.append(Patch(color="tab:blue", label="probing move (contact intended)"))
    ax.legend(handles=handles + ax.get_legend_handles_labels()[0], loc="upper right",
              fontsize=8)
    ax.set_xlabel("path move")
    ax.set_ylabel(rc.axis_label("certified clearance", units))
    if len(res) <= 30:
        ax.set_xticks(k)
    else:
        _few_ticks(ax, 10)


def plot_clearance(res, path, overwrite: bool = False, units: str | None = None,
                   model_note: str | None = None, probing=()) -> Path:
    """Bar chart of the certified clearance per move, the margin as a line, failing
    moves in red and first-contact moves hatched.  ``probing``: indices of moves meant
    to touch (a measuring plunge): drawn blue and not counted as failures, as the demo's
    console summary counts them."""
    fig = _figure(figsize=(8, 4.2), layout="constrained")
    ax = fig.add_subplot(1, 1, 1)
    clearance_axes(ax, res, units, probing)
    text = "probe clearance: " + clearance_title(res, probing).replace("; probing",
                                                                         "\nprobing")
    ax.set_title(_title(text, model_note), fontsize=9)
    return _save_fig(fig, path, overwrite)
