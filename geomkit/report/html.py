"""Interactive HTML reports: one self-contained file per job (plotly with its JavaScript
embedded; nothing is fetched from the network), for the deviation, section and
clearance jobs.

Each page opens with a header table (part file and its SHA-256, date, geomkit version,
units, tolerances, model note), then the job's figures (3-D views can be turned and
zoomed; hovering a point shows its values) and tables.  Written atomically like every
report file (:func:`geomkit.outputs.atomic_write`); an existing file is kept unless
``overwrite=True``.
"""

from __future__ import annotations

import html
from pathlib import Path

import numpy as np

from geomkit.units import unit_label
from geomkit.report import common as rc
from geomkit.outputs import atomic_write, check_target
from geomkit.report.files import clearance_counts, clearance_title

__all__ = ["deviation_html", "section_html", "clearance_html"]

PLOTLY_CONFIG = {"displaylogo": False, "responsive": True,
                 "toImageButtonOptions": {"format": "png", "scale": 2}}

_CSS = """
body{font-family:system-ui,-apple-system,Segoe UI,Helvetica,Arial,sans-serif;margin:1.2em 2em;
color:#222;max-width:1400px}
h1{font-size:1.5em;margin:.2em 0}h2{font-size:1.15em;margin:1.4em 0 .4em;
border-bottom:1px solid #ccc}
table{border-collapse:collapse;font-size:.9em;margin:.4em 0}
td,th{border:1px solid #ccc;padding:.2em .6em;text-align:left;vertical-align:top}
th{background:#f2f2f2}td.num{text-align:right;font-family:ui-monospace,monospace}
.note{background:#fff4e5;border:1px solid #f0b357;padding:.4em .8em;margin:.6em 0}
.pass{color:#1b7837;font-weight:bold}.fail{color:#b2182b;font-weight:bold}
.probe{color:#2166ac;font-weight:bold}.row{display:flex;flex-wrap:wrap;gap:2em}
.mono{font-family:ui-monospace,monospace;font-size:.85em}
"""


# ----------------------------------------------------------------------- page
def _table(rows, head=None, num_cols=()) -> str:
    out = ["<table>"]
    if head:
        out.append("<tr>" + "".join(f"<th>{html.escape(str(h))}</th>" for h in head)
                   + "</tr>")
    for r in rows:
        cells = []
        for j, c in enumerate(r):
            cls = ' class="num"' if j in num_cols else ""
            cells.append(f"<td{cls}>{c if isinstance(c, _Raw) else html.escape(str(c))}</td>")
        out.append("<tr>" + "".join(cells) + "</tr>")
    out.append("</table>")
    return "\n".join(out)


class _Raw(str):
    """Table cell text that is already HTML."""


class _Page:
    """Collects HTML blocks and plotly figures; the first figure carries plotly.js."""

    def __init__(self, title: str, head: dict, model_note=None):
        self.title = title
        self.blocks = [f"<h1>{html.escape(title)}</h1>"]
        if model_note:
            self.blocks.append(f'<div class="note">{html.escape(str(model_note))}</div>')
        self.blocks.append(_table([(k, _Raw(f'<span class="mono">{html.escape(v)}</span>')
                                    if k == "SHA-256" else v) for k, v in head.items()]))
        self._js = True
        self._n = 0

    def h2(self, text):
        self.blocks.append(f"<h2>{html.escape(text)}</h2>")

    def add(self, block: str):
        self.blocks.append(block)

    def figure(self, fig):
        self._n += 1
        self.blocks.append(fig.to_html(full_html=False, include_plotlyjs=self._js,
                                       include_mathjax=False, config=PLOTLY_CONFIG,
                                       div_id=f"geomkit-fig-{self._n}"))
        self._js = False

    def write(self, path, overwrite) -> Path:
        p = check_target(path, overwrite)
        doc = ("<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">"
               f"<title>{html.escape(self.title)}</title><style>{_CSS}</style></head>"
               "<body>\n" + "\n".join(self.blocks) + "\n</body></html>\n")
        data = doc.encode("utf-8")
        return atomic_write(p, lambda fh: fh.write(data))


def _go():
    import plotly.graph_objects as go

    return go


def _scene(units, aspect="data"):
    return dict(xaxis_title=rc.axis_label("x", units), yaxis_title=rc.axis_label("y", units),
                zaxis_title=rc.axis_label("z", units), aspectmode=aspect)


def _mesh_trace(mesh, name="nominal"):
    V, F = mesh.vertices, mesh.faces
    return _go().Mesh3d(x=V[:, 0], y=V[:, 1], z=V[:, 2], i=F[:, 0], j=F[:, 1], k=F[:, 2],
                        color="#c9ced6", opacity=0.45, name=name, hoverinfo="skip",
                        showlegend=True, flatshading=False,
                        lighting=dict(ambient=0.6, diffuse=0.6, specular=0.1))


def _hex_colours(tolerance, m, values):
    from matplotlib.colors import to_hex

    cmap = rc.mpl_cmap(tolerance, m)
    return [to_hex(cmap((v + m) / (2 * m))) for v in values]


# ------------------------------------------------------------------ deviation
def deviation_html(rep, surfaces, path, overwrite: bool = False, units: str | None = None,
                   model_note: str | None = None, part=None, worst: int = rc.WORST_N,
                   mesh_tol=None, extra: dict | None = None) -> Path:
    """HTML deviation report of a :class:`~geomkit.jobs.deviation.DeviationReport`.

    Contents: header (``part`` file and SHA-256, date, version, units, tolerance,
    ``model_note``, ``extra`` rows); the nominal mesh in 3-D with the points coloured by
    signed deviation (inside the tolerance band one colour, graded beyond), callouts for
    the max, the min and the ``worst`` points farthest outside the band; a histogram
    with the tolerance limits; the statistics table (n, min, max, mean, sigma, rms,
    % in / over / under, Cp / Cpk when both limits are given); the worst points' table;
    the alignment result."""
    from geomkit.report.files import _nominal_mesh

    go = _go()
    mesh, _ = _nominal_mesh(surfaces, mesh_tol)
    u = unit_label(units)
    page = _Page("Deviation report", rc.header("deviation", part, units, rep.tolerance,
                                               None, extra), model_note)
    m = rc.colour_range(rep)
    stops = [[p, c] for p, c in rc.colour_stops(rep.tolerance, m)]
    d, P = rep.deviation, rep.aligned
    ok = np.isfinite(d)
    idx = np.arange(len(rep))
    traces = [_mesh_trace(mesh)]
    ticks = sorted({-m, 0.0, m, *(rep.tolerance or ())})
    for sel, name, symbol, bar in ((ok & ~rep.edge, "points", "circle", True),
                                   (ok & rep.edge, "points on edges", "diamond", False)):
        if not sel.any():
            continue
        marker = dict(size=4, color=d[sel], colorscale=stops, cmin=-m, cmax=m,
                      symbol=symbol, line=dict(width=0))
        if bar:
            marker["colorbar"] = dict(title=dict(text=f"deviation [{u}]"), tickvals=ticks,
                                      ticktext=[f"{t:.4g}" for t in ticks], len=0.8)
        traces.append(go.Scatter3d(
            x=P[sel, 0], y=P[sel, 1], z=P[sel, 2], mode="markers", name=name,
            marker=marker, customdata=np.column_stack([idx[sel], d[sel]]),
            hovertemplate=f"point %{{customdata[0]}}<br>deviation %{{customdata[1]:.5g}} {u}"
                          "<br>x %{x:.4f}<br>y %{y:.4f}<br>z %{z:.4f}<extra></extra>"))
    if (~ok).any():
        traces.append(go.Scatter3d(x=P[~ok, 0], y=P[~ok, 1], z=P[~ok, 2], mode="markers",
                                   name="not matched", marker=dict(size=3, color="black",
                                                                   symbol="x")))
    notes = []
    worst_idx = rc.worst_points(rep, worst)
    if ok.any():
        imax, imin = int(np.nanargmax(d)), int(np.nanargmin(d))
        called = [(imax, f"max {d[imax]:+.4g}"), (imin, f"min {d[imin]:+.4g}")]
        called += [(int(i), f"#{k + 1}: {d[i]:+.4g}") for k, i in enumerate(worst_idx)
                   if int(i) not in (imax, imin)]
        sep = 0.06 * float(np.ptp(mesh.vertices, axis=0).max())
        placed = []
        for i, text in called:  # label only points apart from the labelled ones
            if any(np.linalg.norm(P[i] - P[j]) < sep for j in placed):
                continue
            placed.append(i)
            notes.append(dict(x=P[i, 0], y=P[i, 1], z=P[i, 2], text=f"{text} (pt {i})",
                              showarrow=True, arrowhead=2, arrowsize=1,
                              ax=40 if len(placed) % 2 else -40, ay=-30,
                              font=dict(size=10), bgcolor="rgba(255,255,255,0.8)",
                              bordercolor="#444"))
        if worst_idx.size:
            W = P[worst_idx]
            traces.append(go.Scatter3d(
                x=W[:, 0], y=W[:, 1], z=W[:, 2], mode="markers",
                name=f"worst {worst_idx.size} (table below)",
                marker=dict(size=9, color="black", symbol="circle-open"),
                customdata=np.column_stack([np.arange(1, worst_idx.size + 1), worst_idx,
                                            d[worst_idx]]),
                hovertemplate="worst #%{customdata[0]}: point %{customdata[1]}<br>deviation "
                              f"%{{customdata[2]:.5g}} {u}<extra></extra>"))
    fig = go.Figure(traces)
    fig.update_layout(scene=dict(**_scene(units), annotations=notes), height=720,
                      margin=dict(l=0, r=0, t=40, b=0), legend=dict(x=0, y=1),
                      title=dict(text=f"{rep.stats['valid']} points coloured by deviation "
                                      "(turn with the mouse; hover for values)",
                                 font=dict(size=14)))
    page.h2("Colour map")
    page.figure(fig)
    # histogram + statistics side by side
    page.h2("Distribution and statistics")
    page.figure(_histogram(rep, units, m))
    page.add('<div class="row"><div>' + _table(rc.deviation_table(rep), ("statistic",
                                                                          f"value [{u}]"),
                                               num_cols=(1,))
             + "</div><div>" + _table(rc.alignment_rows(rep), ("alignment", "")) + "</div>"
             + "</div>")
    a = rep.stats.get("alignment")
    if a:
        page.add("<p>transform (aligned = T &middot; measured):</p>" + _table(
            [[f"{x:.9f}" for x in row] for row in a["transform"]], num_cols=(0, 1, 2, 3)))
    if worst_idx.size:
        page.h2(f"Worst {worst_idx.size} points")
        rows = []
        lo, hi = rep.tolerance or (None, None)
        for k, i in enumerate(worst_idx):
            excess = (max(d[i] - hi, lo - d[i], 0.0) if rep.tolerance else abs(d[i]))
            rows.append((k + 1, int(i), *(f"{c:.4f}" for c in P[i]), f"{d[i]:+.5g}",
                         f"{excess:.5g}", "edge" if rep.edge[i] else ""))
        page.add(_table(rows, ("rank", "point", f"x [{u}]", f"y [{u}]", f"z [{u}]",
                               f"deviation [{u}]",
                               "beyond tolerance" if rep.tolerance else "|deviation|",
                               "note"), num_cols=(0, 1, 2, 3, 4, 5, 6)))
    return page.write(path, overwrite)


def _histogram(rep, units, m, bins: int = 40):
    go = _go()
    v = rep.deviation[np.isfinite(rep.deviation)]
    u = unit_label(units)
    cnt, edges = np.histogram(v, bins=bins) if v.size else (np.zeros(0), np.zeros(1))
    mid = 0.5 * (edges[1:] + edges[:-1])
    fig = go.Figure(go.Bar(x=mid, y=cnt, width=np.diff(edges),
                           marker=dict(color=_hex_colours(rep.tolerance, m, mid),
                                       line=dict(width=0.5, color="white")),
                           hovertemplate=f"%{{x:.4g}} {u}: %{{y}} points<extra></extra>",
                           name="points"))
    shapes, notes = [], []
    if rep.tolerance:
        lo, hi = rep.tolerance
        shapes.append(dict(type="rect", xref="x", yref="paper", x0=lo, x1=hi, y0=0, y1=1,
                           fillcolor=rc.IN_TOL, opacity=0.08, line=dict(width=0)))
        for t, name in ((lo, "lower"), (hi, "upper")):
            shapes.append(dict(type="line", xref="x", yref="paper", x0=t, x1=t, y0=0, y1=1,
                               line=dict(color="black", dash="dash", width=1.5)))
            notes.append(dict(x=t, y=1, xref="x", yref="paper", text=f"{name} {t:g}",
                              showarrow=False, yanchor="bottom"))
    fig.update_layout(shapes=shapes, annotations=notes, height=380, bargap=0,
                      xaxis_title=rc.axis_label("deviation along the nominal normal", units),
                      yaxis_title="points", margin=dict(l=60, r=20, t=40, b=50))
    return fig


# -------------------------------------------------------------------- section
def section_html(sections, path, overwrite: bool = False, units: str | None = None,
                 model_note: str | None = None, part=None, scan=None, surfaces=None,
                 band: float | None = None, tolerance=None, probe_radius: float = 0.0,
                 extra: dict | None = None) -> Path:
    """HTML section report: each plane's curves in 2-D in the plane's own coordinates
    (:func:`geomkit.report.common.plane_frame`, equal aspect), a table of curves and
    residuals, and, when a ``scan`` ((n, 3) measured points) is given with the nominal
    ``surfaces``, the scan points within ``band`` of each plane (default 0.5 % of the
    scan's extent) drawn as nominal-vs-measured deviation whiskers (from the nominal
    foot toward the measured point, magnified by the stated factor, coloured by
    deviation with the ``tolerance`` band).  The deviation is the signed distance along
    the nominal normal less ``probe_radius`` (scan points as probe-ball centres on the
    normal side)."""
    from plotly.subplots import make_subplots

    go = _go()
    sections = list(sections)
    u = unit_label(units)
    page = _Page("Section report", rc.header("section", part, units, tolerance, None,
                                             extra), model_note)
    shown = sections[:24]
    whisk = _whiskers(sections, scan, surfaces, band, probe_radius) if scan is not None else None
    cols = 1 if len(shown) == 1 else 2
    rows = -(-max(len(shown), 1) // cols)
    fig = make_subplots(rows=rows, cols=cols, subplot_titles=[
        f"plane {rc.plane_name(s.plane)}" for s in shown], horizontal_spacing=0.08,
        vertical_spacing=min(0.12, 0.3 / rows))
    m = 1.0
    if whisk is not None:
        allv = np.concatenate([w[2] for w in whisk] + [np.zeros(1)])
        m = float(np.abs(allv).max()) or 1.0
        if tolerance:
            m = max(m, 1.5 * max(abs(t) for t in tolerance))
    for k, sec in enumerate(shown):
        r, c = k // cols + 1, k % cols + 1
        _, _, _, (l1, l2) = rc.plane_frame(sec.plane)
        for j, (X, closed) in enumerate(zip(sec.curves, sec.closed)):
            Q = rc.to_plane(np.concatenate([X, X[:1]]) if closed else X, sec.plane)
            fig.add_trace(go.Scatter(x=Q[:, 0], y=Q[:, 1], mode="lines", name=f"curve {j}",
                                     line=dict(width=2, color="#1f4e79"), showlegend=False,
                                     hovertemplate=f"plane {k}, curve {j}<br>{l1} %{{x:.4f}}"
                                                   f"<br>{l2} %{{y:.4f}}<extra></extra>"),
                          row=r, col=c)
        if len(sec.points):
            Q = rc.to_plane(sec.points, sec.plane)
            fig.add_trace(go.Scatter(x=Q[:, 0], y=Q[:, 1], mode="markers", showlegend=False,
                                     marker=dict(color="black", size=6), name="contact"),
                          row=r, col=c)
        if whisk is not None:
            _add_whiskers(fig, go, whisk[k], sec, tolerance, m, u, r, c)
        n = (r - 1) * cols + c
        fig.update_xaxes(title_text=rc.axis_label(l1, units), row=r, col=c)
        fig.update_yaxes(title_text=rc.axis_label(l2, units), row=r, col=c,
                         scaleanchor="x" if n == 1 else f"x{n}", scaleratio=1)
    title = f"{len(sections)} plane(s), {sum(len(s.curves) for s in sections)} curve(s)"
    if len(sections) > len(shown):
        title += f" (first {len(shown)} planes drawn)"
    if whisk is not None:
        title += f"; whiskers: scan deviation x {whisk[0][3]:.3g}"
    fig.update_layout(height=max(420, 380 * rows), title=dict(text=title, font=dict(size=14)),
                      margin=dict(l=60, r=20, t=80, b=40))
    page.h2("Sections, each in its plane's own coordinates")
    page.figure(fig)
    page.h2("Curves")
    trs = []
    for k, sec in enumerate(sections):
        o, e1, e2, (l1, l2) = rc.plane_frame(sec.plane)
        row = [k, rc.plane_name(sec.plane), len(sec.curves), int(sum(sec.closed)),
               int(sum(len(c) for c in sec.curves)), f"{sec.max_residual:.2g}",
               f"{sec.max_chord_error:.2g} (tol {sec.tol:.2g})",
               f"{l1} = ({', '.join(f'{x:.3g}' for x in e1)}), "
               f"{l2} = ({', '.join(f'{x:.3g}' for x in e2)})"]
        if whisk is not None:
            v = whisk[k][2]
            row.append(f"{v.size}: min {rc.fmt(v.min() if v.size else None)}, max "
                       f"{rc.fmt(v.max() if v.size else None)}, rms "
                       f"{rc.fmt(np.sqrt(np.mean(v * v)) if v.size else None)}")
        trs.append(row)
    head = ["plane", "equation", "curves", "closed", "curve points",
            f"max plane residual [{u}]", f"max chord error [{u}]", "2-D frame"]
    if whisk is not None:
        head.append(f"scan points in band (deviation [{u}])")
    page.add(_table(trs, head, num_cols=(0, 2, 3, 4, 5)))
    return page.write(path, overwrite)


def _whiskers(sections, scan, surfaces, band, probe_radius=0.0):
    """Per section ``(foot_2d (k, 2), point_2d (k, 2), deviation (k,), scale)``."""
    from geomkit.validate import as_points
    from geomkit.query.projection_part import project_points

    if surfaces is None:
        from geomkit.errors import InvalidInputError

        raise InvalidInputError("a scan needs the nominal surfaces", "surfaces")
    P, _ = as_points(scan, 3, "scan")
    if band is None:
        band = 0.005 * float(np.linalg.norm(np.ptp(P, axis=0)))
    out, ext, devs = [], 1e-300, []
    for sec in sections:
        near = np.abs(P @ sec.plane[:3] + sec.plane[3]) <= band
        Q = P[near]
        if Q.shape[0]:
            pr = project_points(surfaces, Q)
            okk = np.isfinite(pr.signed_distance)
            Q, foot = Q[okk], pr.point[okk]
            dev = pr.signed_distance[okk] - float(probe_radius)
            n = Q - foot  # whisker along the normal: from the foot, length = deviation
            ln = np.linalg.norm(n, axis=1, keepdims=True)
            n = np.divide(n, ln, out=np.zeros_like(n), where=ln > 0)
            Q = foot + np.sign(pr.signed_distance[okk])[:, None] * n * dev[:, None]
        else:
            foot, dev = Q, np.zeros(0)
        out.append([rc.to_plane(foot, sec.plane), rc.to_plane(Q, sec.plane), dev])
        for X in sec.curves:
            ext = max(ext, float(np.ptp(rc.to_plane(X, sec.plane), axis=0).max()))
        devs.append(np.abs(dev))
    return [(f, f + scale * (q - f), d, scale) for (f, q, d), scale in
            zip(out, [_whisker_scale(np.concatenate(devs), ext)] * len(out))]


def _whisker_scale(a, ext) -> float:
    """Magnification (1, 2 or 5 x a power of 10) drawing the 95th-percentile deviation
    at ~8 % of the curves' extent ``ext``, the largest at most ~30 %."""
    if not a.size or not a.max() > 0:
        return 1.0
    ref = max(float(np.percentile(a, 95)), float(a.max()) / 4)
    x = 0.08 * ext / ref
    e = np.floor(np.log10(x) + 1e-9)
    m = max(k for k in (1, 2, 5) if k * 10 ** e <= x * (1 + 1e-9))
    return float(m * 10 ** e)


def _add_whiskers(fig, go, w, sec, tolerance, m, u, r, c):
    foot, tip, dev, scale = w
    if not dev.size:
        return
    cols = _hex_colours(tolerance, m, dev)
    xs, ys = [], []
    for f, t in zip(foot, tip):
        xs += [f[0], t[0], None]
        ys += [f[1], t[1], None]
    fig.add_trace(go.Scatter(x=xs, y=ys, mode="lines", line=dict(color="#555", width=1),
                             hoverinfo="skip", showlegend=False), row=r, col=c)
    fig.add_trace(go.Scatter(x=tip[:, 0], y=tip[:, 1], mode="markers", showlegend=False,
                             marker=dict(color=cols, size=6, line=dict(width=0.5,
                                                                       color="#333")),
                             customdata=dev, name="scan",
                             hovertemplate=f"deviation %{{customdata:.5g}} {u}"
                                           "<extra></extra>"), row=r, col=c)


# ------------------------------------------------------------------ clearance
def clearance_html(res, surfaces, path_points, path, overwrite: bool = False,
                   units: str | None = None, model_note: str | None = None, part=None,
                   stylus=None, axis=None, probing=(), mesh_tol=None,
                   extra: dict | None = None) -> Path:
    """HTML probe-clearance report of a :class:`~geomkit.Clearance`: the part and the
    stylus path (tip centres ``path_points``, (m + 1, 3)) in 3-D, moves coloured pass
    (green) / fail (red) / probing (blue, ``probing`` = moves meant to touch), the
    closest approach of each move, the first-contact markers with the stylus drawn at
    the first contact (when ``stylus`` and the stylus ``axis`` are given), a chart and a
    table of the certified interval ``[lower_bound, clearance]`` per move."""
    from geomkit.report.files import _nominal_mesh

    go = _go()
    mesh, size = _nominal_mesh(surfaces, mesh_tol)
    u = unit_label(units)
    T = np.asarray(path_points, float)
    ex = dict(extra or {})
    ex.setdefault("margin", f"{res.margin:g} {u}")
    ex.setdefault("certified interval width", f"{res.tol:.3g} {u}")
    if stylus is not None:
        ex.setdefault("stylus", ", ".join(f"{k} {v:g}" for k, v in stylus.to_dict().items()
                                          if v))
    page = _Page("Probe clearance report", rc.header("probe clearance", part, units, None,
                                                     None, ex), model_note)
    pm = rc.probing_mask(len(res), probing)
    traces = [_mesh_trace(mesh, "part")]
    status = ["probe" if p else ("pass" if ok else "fail") for ok, p in zip(res.passed, pm)]
    colour = {"pass": "#1b9e3e", "fail": "#d62728", "probe": "#1f77b4"}
    seen = set()
    for i in range(len(res)):
        st = status[i]
        traces.append(go.Scatter3d(
            x=T[i:i + 2, 0], y=T[i:i + 2, 1], z=T[i:i + 2, 2], mode="lines",
            line=dict(color=colour[st], width=7), name=st, legendgroup=st,
            showlegend=st not in seen,
            hovertemplate=f"move {i} ({res.motion[i]}): {st.upper()}<br>clearance in "
                          f"[{res.lower_bound[i]:.6g}, {res.clearance[i]:.6g}] {u}"
                          "<extra></extra>"))
        seen.add(st)
    traces.append(go.Scatter3d(x=T[:, 0], y=T[:, 1], z=T[:, 2], mode="markers+text",
                               text=[f"P{k}" for k in range(len(T))], name="tip centres",
                               marker=dict(size=3, color="black"), textposition="top center"))
    gx, gy, gz = [], [], []
    for i in range(len(res)):
        for a, b in ((res.point_part[i], res.point_stylus[i]),):
            if np.all(np.isfinite(a)) and np.all(np.isfinite(b)):
                gx += [a[0], b[0], None]
                gy += [a[1], b[1], None]
                gz += [a[2], b[2], None]
    traces.append(go.Scatter3d(x=gx, y=gy, z=gz, mode="lines", name="closest approach",
                               line=dict(color="#ff7f0e", width=3, dash="dash")))
    notes = []
    for i in np.flatnonzero(np.isfinite(res.first_contact)):
        s = float(res.first_contact[i])
        c = res.point_part[i]
        traces.append(go.Scatter3d(x=[c[0]], y=[c[1]], z=[c[2]], mode="markers",
                                   name=f"first contact, move {i}",
                                   marker=dict(size=7, color="red", symbol="x")))
        notes.append(dict(x=c[0], y=c[1], z=c[2], text=f"move {i}: first contact s = {s:.6f}",
                          showarrow=True, arrowhead=2, ax=50, ay=-40,
                          bgcolor="rgba(255,255,255,0.85)", bordercolor="#444"))
        if stylus is not None and axis is not None and res.motion[i] == "translation":
            tip = T[i] + s * (T[i + 1] - T[i])
            a = np.asarray(axis, float)
            a = a / np.linalg.norm(a)
            top = tip + stylus.length * a
            traces.append(go.Scatter3d(x=[tip[0], top[0]], y=[tip[1], top[1]],
                                       z=[tip[2], top[2]], mode="lines+markers",
                                       name=f"stylus at first contact (move {i})",
                                       line=dict(color="#444", width=5),
                                       marker=dict(size=[8, 2], color="#444")))
    fig = go.Figure(traces)
    fig.update_layout(scene=dict(**_scene(units), annotations=notes), height=720,
                      margin=dict(l=0, r=0, t=40, b=0), legend=dict(x=0, y=1),
                      title=dict(text="probe clearance: " + clearance_title(res, probing),
                                 font=dict(size=14)))
    page.h2("Part and stylus path")
    page.figure(fig)
    bar = go.Figure(go.Bar(x=np.arange(len(res)), y=res.lower_bound,
                           marker=dict(color=[colour[s] for s in status]),
                           hovertemplate=f"move %{{x}}: >= %{{y:.6g}} {u}<extra></extra>"))
    if res.margin > 0:
        bar.add_hline(y=res.margin, line_dash="dash", annotation_text=f"margin {res.margin:g}")
    bar.update_layout(height=320, xaxis_title="path move", xaxis=dict(dtick=1),
                      yaxis_title=rc.axis_label("certified clearance", units),
                      margin=dict(l=60, r=20, t=30, b=50))
    page.h2("Certified clearance per move")
    page.figure(bar)
    cnt = clearance_counts(res, probing)
    rows = []
    for i in range(len(res)):
        st = status[i]
        fc = res.first_contact[i]
        rows.append((i, res.motion[i], " -> ".join(
            "(" + ", ".join(f"{x:.3f}" for x in T[j]) + ")" for j in (i, i + 1)),
            f"[{res.lower_bound[i]:.6g}, {res.clearance[i]:.6g}]",
            _Raw(f'<span class="{st}">{st.upper()}</span>'),
            "yes" if res.certified[i] else "no (looser bound)",
            res.component_names[int(res.component[i])], f"{res.parameter[i]:.4f}",
            f"{fc:.9f}" if np.isfinite(fc) else ""))
    page.add(_table(rows, ("move", "motion", f"tip centre from -> to [{u}]",
                           f"certified clearance [{u}]", "result", "certified", "closest piece",
                           "at s", "first contact s"), num_cols=(0, 3, 7, 8)))
    page.add(f"<p>{len(cnt['travel_failed'])} of {len(cnt['travel'])} "
             f"{'travel ' if cnt['probing'] else ''}moves fail"
             + (f"; probing moves (contact intended): {cnt['probing']}" if cnt["probing"]
                else "") + ".</p>")
    return page.write(path, overwrite)
