"""Reports of ``geomkit inspect``: the characteristic table (green / red / grey rows)
and a colour map per characteristic (its points coloured by their distance to their
own face, the deciding points ringed), as one self-contained HTML file or an A4 PDF.

The colour maps show the points placed by the datum system ``Inspection.shown_in``
(the first that fixes every degree of freedom) or as evaluated; each map's band is
the characteristic's zone taken as +-tolerance/2 about the nominal (the verdict itself
comes from the characteristic's own evaluation, in the table).
"""

from __future__ import annotations

import html

import numpy as np

from geomkit.report import common as rc
from geomkit.report.files import _figure, _nominal_mesh
from geomkit.report.html import _Page, _go, _mesh_trace, _scene
from geomkit.report.pdf import A4, _header_page, _write
from geomkit.units import unit_label

__all__ = ["inspect_html", "inspect_pdf", "table_rows"]

_ROW_CSS = ("<style>tr.pass td{background:#e3f4e6}tr.fail td{background:#fbe0e0}"
            "tr.ne td{background:#eeeeee;color:#555}</style>")
_HEAD = ("id", "characteristic", "faces", "tolerance", "datums", "measured", "limit",
         "result", "points", "note")
#: Most colour maps drawn (the failing characteristics first).
MAX_MAPS = 40


def _fmt(x):
    return "" if x is None else f"{x:.5g}"


def _faces_text(faces, n=8):
    f = list(faces)
    return " ".join(map(str, f[:n])) + (f" ... ({len(f)})" if len(f) > n else "")


def table_rows(res) -> list:
    """One row per characteristic: the table's cells as strings and its class
    (``pass`` / ``fail`` / ``ne``)."""
    rows = []
    for c in res.characteristics:
        t = c.tolerance
        tol = "" if t["value"] is None else f"{'⌀' if t['diameter'] else ''}{t['value']:.5g}"
        if t["modifiers"]:
            tol += " " + " ".join(m.replace("_requirement", "").replace("_", " ")
                                  for m in t["modifiers"])
        cls = {"pass": "pass", "fail": "fail"}.get(c.status, "ne")
        notes = [c.reason] if c.reason else []
        notes += sorted({f["note"] for f in c.features if f.get("note")})
        rows.append(([c.id, c.type.replace("_", " "), _faces_text(c.faces), tol,
                      "|".join(c.datums), _fmt(c.measured), _fmt(c.limit),
                      c.status.upper(), str(c.n_points), "; ".join(notes)], cls))
    return rows


def _verdict_rows(res) -> dict:
    n = res.counts()
    a = res.assignment
    return {"verdict": res.verdict.upper(),
            "characteristics": f"{n['pass']} pass, {n['fail']} fail, "
                               f"{n['not evaluated']} not evaluated",
            "points": f"{a['points']} ({a['assigned']} on faces, "
                      f"{'face column' if a['given'] else 'by projection'})",
            "alignment": res.align + (f"; maps placed by {res.shown_in}"
                                      if res.shown_in else "")}


def _maps(res):
    """(characteristic, point indices) to draw: evaluated ones, failures first."""
    out = []
    for c in res.characteristics:
        if c.status == "not evaluated":
            continue
        idx = np.nonzero(np.isin(res.face, list(c.surfaces)))[0]
        if idx.size:
            out.append((c, idx))
    out.sort(key=lambda ci: ci[0].status != "fail")
    return out[:MAX_MAPS]


def _band(c):
    t = c.tolerance["value"] or 0.0
    return (-t / 2, t / 2) if t > 0 else None


def _range(d, band):
    v = d[np.isfinite(d)]
    m = float(np.abs(v).max()) if v.size else 0.0
    if band:
        m = max(m, 1.5 * band[1])
    return m if m > 0 else 1.0


def inspect_html(res, surfaces, path, overwrite: bool = False, part=None,
                 model_note=None) -> "Path":  # noqa: F821
    """The HTML report of an :class:`~geomkit.jobs.inspect.Inspection`."""
    go = _go()
    u = unit_label(res.units)
    head = rc.header("inspection", part, res.units, None, None, _verdict_rows(res))
    page = _Page("Inspection report", head, model_note)
    page.add(_ROW_CSS)
    page.h2("Characteristics")
    out = ["<table><tr>" + "".join(f"<th>{h}</th>" for h in _HEAD) + "</tr>"]
    for cells, cls in table_rows(res):
        out.append(f'<tr class="{cls}">' + "".join(
            f'<td{" class=num" if j in (5, 6, 8) else ""}>{html.escape(v)}</td>'
            for j, v in enumerate(cells)) + "</tr>")
    out.append("</table>")
    page.add("\n".join(out))
    page.h2("Colour maps (distance of each point to its face)")
    for c, idx in _maps(res):
        band = _band(c)
        d = res.deviation[idx]
        m = _range(d, band)
        P = res.shown_points[idx]
        mesh, _ = _nominal_mesh([surfaces[f] for f in c.surfaces])
        stops = [[p, col] for p, col in rc.colour_stops(band, m)]
        tr = [_mesh_trace(mesh),
              go.Scatter3d(x=P[:, 0], y=P[:, 1], z=P[:, 2], mode="markers", name="points",
                           marker=dict(size=4, color=np.nan_to_num(d), colorscale=stops,
                                       cmin=-m, cmax=m,
                                       colorbar=dict(title=dict(text=f"[{u}]"), len=0.7)),
                           customdata=np.column_stack([idx, d]),
                           hovertemplate="point %{customdata[0]}<br>distance "
                                         f"%{{customdata[1]:.5g}} {u}<extra></extra>")]
        D = res.shown_points[c.deciding] if c.deciding.size else np.zeros((0, 3))
        if D.size:
            tr.append(go.Scatter3d(x=D[:, 0], y=D[:, 1], z=D[:, 2], mode="markers",
                                   name="deciding points",
                                   marker=dict(size=8, color="black",
                                               symbol="circle-open")))
        fig = go.Figure(tr)
        fig.update_layout(scene=_scene(res.units), height=420,
                          margin=dict(l=0, r=0, t=36, b=0),
                          title=dict(text=f"{c.id} {c.type.replace('_', ' ')}: measured "
                                          f"{_fmt(c.measured)} / limit {_fmt(c.limit)} "
                                          f"{u} — {c.status.upper()}",
                                     font=dict(size=13)))
        page.figure(fig)
    return page.write(path, overwrite)


def _view(P):
    """Plot coordinates: the points' two principal directions (a face seen square on;
    lengths kept)."""
    c = P.mean(axis=0)
    if P.shape[0] < 3:
        return lambda X: (X - c)[:, :2]
    _, _, Vt = np.linalg.svd(P - c, full_matrices=False)
    return lambda X: (X - c) @ Vt[:2].T


def inspect_pdf(res, surfaces, path, overwrite: bool = False, part=None,
                model_note=None) -> "Path":  # noqa: F821
    """The A4 PDF report: the header and the characteristic table (green / red /
    grey rows), then colour maps (top views), six a page."""
    head = rc.header("inspection", part, res.units, None, None, _verdict_rows(res))
    u = unit_label(res.units)
    rows = table_rows(res)
    pages = []
    per_page = 34
    for k in range(0, max(len(rows), 1), per_page):
        fig = _header_page("Inspection report", head, model_note) if k == 0 else \
            _figure(figsize=A4)
        top = 0.68 if k == 0 else 0.95
        ax = fig.add_axes([0.03, 0.03, 0.94, top - 0.03])
        ax.axis("off")
        chunk = rows[k:k + per_page]
        if chunk:
            cells = [[c[i] for i in (0, 1, 3, 4, 5, 6, 7, 8)] for c, _ in chunk]
            t = ax.table(cellText=cells, colLabels=[_HEAD[i] for i in
                                                    (0, 1, 3, 4, 5, 6, 7, 8)],
                         loc="upper left", cellLoc="left",
                         colWidths=[0.09, 0.2, 0.17, 0.1, 0.12, 0.12, 0.12, 0.08])
            t.auto_set_font_size(False)
            t.set_fontsize(7)
            colour = {"pass": "#e3f4e6", "fail": "#fbe0e0", "ne": "#eeeeee"}
            for r, (_, cls) in enumerate(chunk, start=1):
                for j in range(8):
                    t[r, j].set_facecolor(colour[cls])
        pages.append(fig)
    maps = _maps(res)
    for k in range(0, len(maps), 6):
        fig = _figure(figsize=A4)
        fig.suptitle(f"colour maps: distance of each point to its face [{u}] (each "
                     "seen along its points' least spread)",
                     fontsize=10)
        for j, (c, idx) in enumerate(maps[k:k + 6]):
            ax = fig.add_axes([0.07 + 0.48 * (j % 2), 0.68 - 0.31 * (j // 2), 0.38, 0.24])
            band = _band(c)
            d = res.deviation[idx]
            m = _range(d, band)
            view = _view(res.shown_points[idx])
            P = view(res.shown_points[idx])
            sc = ax.scatter(P[:, 0], P[:, 1], c=np.nan_to_num(d), s=5,
                            cmap=rc.mpl_cmap(band, m), vmin=-m, vmax=m)
            if c.deciding.size:
                D = view(res.shown_points[c.deciding])
                ax.scatter(D[:, 0], D[:, 1], s=30, facecolors="none", edgecolors="k",
                           linewidths=0.8)
            ax.set_aspect("equal", adjustable="datalim")
            ax.tick_params(labelsize=6)
            ax.set_title(f"{c.id} {c.type.replace('_', ' ')}: {_fmt(c.measured)} / "
                         f"{_fmt(c.limit)} {c.status.upper()}", fontsize=8,
                         color="#b2182b" if c.status == "fail" else "#1b7837")
            fig.colorbar(sc, ax=ax, shrink=0.8).ax.tick_params(labelsize=6)
        pages.append(fig)
    return _write(pages, path, overwrite, "geomkit inspection report")
