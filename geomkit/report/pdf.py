"""Archivable PDF summaries through matplotlib's PDF backend (``PdfPages``): a header
(part file and its SHA-256, date, geomkit version, units, tolerances, alignment), the
job's views and its statistics table.  Written atomically like every report file."""

from __future__ import annotations

import io
from pathlib import Path

import numpy as np

from geomkit.units import unit_label
from geomkit.report import common as rc
from geomkit.outputs import atomic_write, check_target
from geomkit.report.files import (_colorbar, _figure, _few_ticks, _nominal_mesh,
                                  _scatter_deviation, clearance_axes, clearance_title,
                                  deviation_map_axes, histogram_axes, section_figure)

__all__ = ["deviation_pdf", "section_pdf", "clearance_pdf"]

A4 = (8.27, 11.69)
ORTHO = (("top (x-y)", 0, 1, 2), ("front (x-z)", 0, 2, 1), ("side (y-z)", 1, 2, 0))
"""Orthographic views: name, horizontal axis, vertical axis, depth axis."""


def _write(pages, path, overwrite, title) -> Path:
    from matplotlib.backends.backend_pdf import PdfPages

    p = check_target(path, overwrite)
    buf = io.BytesIO()
    with PdfPages(buf, metadata={"Title": title, "Creator": "geomkit"}) as pdf:
        for fig in pages:
            pdf.savefig(fig)
    data = buf.getvalue()
    return atomic_write(p, lambda fh: fh.write(data))


def _text_table(ax, rows, title=None, col_widths=(0.42, 0.58), fontsize=8):
    ax.axis("off")
    if title:
        ax.set_title(title, fontsize=10, loc="left")
    if not rows:
        return
    t = ax.table(cellText=[[str(a), str(b)] for a, b in rows], colWidths=list(col_widths),
                 loc="upper left", cellLoc="left")
    t.auto_set_font_size(False)
    t.set_fontsize(fontsize)
    t.scale(1.0, 1.25)


def _header_page(title, head, model_note, rows_right=None, right_title=None):
    fig = _figure(figsize=A4)
    fig.text(0.06, 0.965, title, fontsize=16, weight="bold", va="top")
    if model_note:
        fig.text(0.06, 0.935, str(model_note), fontsize=9, color="#a0522d", va="top")
    ax = fig.add_axes([0.06, 0.70, 0.88, 0.22])
    _text_table(ax, list(head.items()), col_widths=(0.2, 0.8))
    return fig


def deviation_pdf(rep, surfaces, path, overwrite: bool = False, units: str | None = None,
                  model_note: str | None = None, part=None, mesh_tol=None,
                  extra: dict | None = None) -> Path:
    """Two A4 pages: (1) header, statistics table, alignment and histogram with the
    tolerance limits; (2) the colour map in an isometric view and the three
    orthographic views (top, front, side), points coloured by deviation with the
    tolerance band one colour."""
    mesh, _ = _nominal_mesh(surfaces, mesh_tol)
    head = rc.header("deviation", part, units, rep.tolerance, None, extra)
    u = unit_label(units)
    p1 = _header_page("Deviation report", head, model_note)
    ax = p1.add_axes([0.06, 0.36, 0.42, 0.32])
    _text_table(ax, rc.deviation_table(rep), f"statistics [{u}]", (0.55, 0.45))
    ax = p1.add_axes([0.54, 0.36, 0.40, 0.32])
    _text_table(ax, rc.alignment_rows(rep), "alignment", (0.4, 0.6), fontsize=7)
    ax = p1.add_axes([0.1, 0.06, 0.84, 0.25])
    histogram_axes(ax, rep, units)
    ax.set_title("distribution of the deviations", fontsize=10)
    p2 = _figure(figsize=A4)
    p2.suptitle(f"colour map: {rep.stats['valid']} points, min {rc.fmt(rep.stats['min'])}, "
                f"max {rc.fmt(rep.stats['max'])} {u}", fontsize=11)
    ax = p2.add_axes([0.02, 0.52, 0.5, 0.42], projection="3d")
    sc = deviation_map_axes(p2, ax, rep, mesh, units, elev=30.0, azim=-60.0)
    ax.set_title("isometric", fontsize=9)
    m = rc.colour_range(rep)
    cmap = rc.mpl_cmap(rep.tolerance, m)
    V, F = mesh.vertices, mesh.faces
    slots = ([0.6, 0.56, 0.36, 0.36], [0.1, 0.08, 0.36, 0.36], [0.6, 0.08, 0.36, 0.36])
    for (name, i, j, k), rect in zip(ORTHO, slots):
        ax = p2.add_axes(rect)
        from matplotlib.collections import PolyCollection

        ax.add_collection(PolyCollection(V[F][:, :, [i, j]], facecolors=(0.87, 0.89, 0.93),
                                         edgecolors="none", alpha=0.5, zorder=1))
        order = np.argsort(rep.aligned[:, k])  # nearest to the viewer drawn last
        P = rep.aligned[order]
        sub = _Sub(rep, order)
        _scatter_deviation(ax, sub, P[:, [i, j]], cmap, m, s=6, zorder=3)
        ax.set_aspect("equal", adjustable="datalim")
        ax.autoscale_view()
        ax.set_xlabel(rc.axis_label("xyz"[i], units), fontsize=8)
        ax.set_ylabel(rc.axis_label("xyz"[j], units), fontsize=8)
        ax.tick_params(labelsize=7)
        _few_ticks(ax, 5)
        ax.set_title(name, fontsize=9)
    _colorbar(p2, sc, p2.axes, rep, units, shrink=0.5, location="right", pad=0.02)
    return _write([p1, p2], path, overwrite, "geomkit deviation report")


class _Sub:
    """The fields of a DeviationReport that :func:`_scatter_deviation` reads, reordered."""

    def __init__(self, rep, order):
        self.deviation = rep.deviation[order]
        self.edge = rep.edge[order]


def section_pdf(sections, path, overwrite: bool = False, units: str | None = None,
                model_note: str | None = None, part=None, extra: dict | None = None) -> Path:
    """Header page with the table of planes (curves, residuals), then the sections in
    each plane's own coordinates."""
    sections = list(sections)
    u = unit_label(units)
    p1 = _header_page("Section report", rc.header("section", part, units, None, None, extra),
                      model_note)
    rows = [(rc.plane_name(s.plane), f"{len(s.curves)} curve(s), {sum(s.closed)} closed; "
                                     f"residual {s.max_residual:.2g}, chord error "
                                     f"{s.max_chord_error:.2g} {u}") for s in sections[:40]]
    ax = p1.add_axes([0.06, 0.06, 0.88, 0.6])
    _text_table(ax, rows, "planes" + (f" (first 40 of {len(sections)})"
                                      if len(sections) > 40 else ""), (0.3, 0.7))
    p2 = section_figure(sections, units, model_note, figsize=A4)
    return _write([p1, p2], path, overwrite, "geomkit section report")


def clearance_pdf(res, path, overwrite: bool = False, units: str | None = None,
                  model_note: str | None = None, part=None, stylus=None, probing=(),
                  extra: dict | None = None) -> Path:
    """One page: header (with stylus, margin), the certified clearance chart and the
    table of moves (certified interval, result, first contact)."""
    ex = dict(extra or {})
    u = unit_label(units)
    ex.setdefault("margin", f"{res.margin:g} {u}")
    if stylus is not None:
        ex.setdefault("stylus", ", ".join(f"{k} {v:g}" for k, v in stylus.to_dict().items()
                                          if v))
    p1 = _header_page("Probe clearance report", rc.header("probe clearance", part, units,
                                                          None, None, ex), model_note)
    import textwrap

    p1.text(0.06, 0.685, textwrap.fill(clearance_title(res, probing), 110), fontsize=9,
            va="top")
    ax = p1.add_axes([0.1, 0.40, 0.84, 0.24])
    clearance_axes(ax, res, units, probing)
    pm = rc.probing_mask(len(res), probing)
    rows = []
    for i in range(min(len(res), 30)):
        st = "PROBE" if pm[i] else ("PASS" if res.passed[i] else "FAIL")
        fc = res.first_contact[i]
        rows.append((f"move {i} ({res.motion[i]})",
                     f"{st}: [{res.lower_bound[i]:.6g}, {res.clearance[i]:.6g}] {u}"
                     + (f"; first contact s = {fc:.6f}" if np.isfinite(fc) else "")))
    ax = p1.add_axes([0.06, 0.03, 0.88, 0.33])
    _text_table(ax, rows, "certified clearance per move" + (
        f" (first 30 of {len(res)})" if len(res) > 30 else ""), (0.3, 0.7), fontsize=7)
    return _write([p1], path, overwrite, "geomkit probe clearance report")
