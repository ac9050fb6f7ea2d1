"""Report writers for the jobs: deviation CSV, summary JSON, colour-map and histogram
PNGs, section exports, probe-clearance CSV and chart.

Every file is written through a temporary file in the target folder and renamed into
place (:func:`geomkit.io._atomic_write`), so an interrupted run never leaves a
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

from .errors import InvalidInputError
from .io import _atomic_write
from .results import STATUS_NAMES

__all__ = ["prepare_outputs", "write_deviation_csv", "write_json", "plot_deviation_map",
           "plot_histogram", "plot_section", "write_section", "write_clearance_csv",
           "plot_clearance"]


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


def _check_target(path, overwrite):
    p = Path(path)
    if p.exists() and not overwrite:
        raise FileExistsError(f"{p}: exists; pass overwrite=True to replace it")
    return p


def _fmt(x) -> str:
    x = float(x)
    return repr(x) if math.isfinite(x) else ""


def write_deviation_csv(rep, path, overwrite: bool = False) -> Path:
    """One row per point: ``index, x, y, z`` (as measured), ``ax, ay, az`` (aligned),
    ``foot_x.. foot_z, u, v, surface, nx, ny, nz, signed_distance, deviation, status,
    edge`` (empty cells where there is no foot)."""
    p = _check_target(path, overwrite)
    head = ("index,x,y,z,ax,ay,az,foot_x,foot_y,foot_z,u,v,surface,nx,ny,nz,"
            "signed_distance,deviation,status,edge")
    lines = [head]
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
                 str(int(bool(rep.edge[i])))]
        lines.append(",".join(vals))
    data = ("\n".join(lines) + "\n").encode("utf-8")
    return _atomic_write(p, lambda fh: fh.write(data))


def _clean(obj):
    """JSON-safe: NaN / inf -> None, numpy scalars -> Python."""
    if isinstance(obj, dict):
        return {str(k): _clean(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [_clean(v) for v in obj]
    if isinstance(obj, np.ndarray):
        return _clean(obj.tolist())
    if isinstance(obj, (np.floating, float)):
        return float(obj) if math.isfinite(obj) else None
    if isinstance(obj, np.integer):
        return int(obj)
    if isinstance(obj, np.bool_):
        return bool(obj)
    return obj


def write_json(doc: dict, path, overwrite: bool = False) -> Path:
    """Write a JSON document atomically (NaN written as null)."""
    p = _check_target(path, overwrite)
    data = json.dumps(_clean(doc), indent=1, allow_nan=False).encode("utf-8")
    return _atomic_write(p, lambda fh: fh.write(data))


def _save_fig(fig, path, overwrite, dpi=120) -> Path:
    p = _check_target(path, overwrite)
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=dpi)
    data = buf.getvalue()
    return _atomic_write(p, lambda fh: fh.write(data))


def _figure(**kw):
    """A matplotlib Figure not attached to pyplot (no GUI backend, no global state)."""
    import mpl_toolkits.mplot3d  # noqa: F401  registers the 3-D projection
    from matplotlib.figure import Figure

    return Figure(**kw)


def _limits(rep):
    v = rep.deviation[np.isfinite(rep.deviation)]
    if rep.tolerance:
        lo, hi = rep.tolerance
        m = max(abs(lo), abs(hi))
    else:
        m = 0.0
    if v.size:
        m = max(m, float(np.abs(v).max()))
    return m if m > 0 else 1.0


def plot_deviation_map(rep, surfaces, path, overwrite: bool = False, mesh_tol=None) -> Path:
    """PNG: the nominal surfaces' tessellation in grey, the points coloured by deviation
    (diverging map, symmetric about 0; edge points drawn as triangles, unmatched points
    in black)."""
    from .projection import _as_surfaces
    from .tessellate import tessellate

    surfs = _as_surfaces(surfaces)
    fig = _figure(figsize=(8, 6))
    ax = fig.add_subplot(projection="3d")
    size = max(s.size for s in surfs)
    mesh = tessellate(surfs, mesh_tol or 5e-3 * size)
    V, F = mesh.vertices, mesh.faces
    ax.plot_trisurf(V[:, 0], V[:, 1], V[:, 2], triangles=F, color=(0.8, 0.8, 0.8),
                    alpha=0.35, linewidth=0)
    m = _limits(rep)
    ok = np.isfinite(rep.deviation)
    P = rep.aligned
    inner = ok & ~rep.edge
    sc = ax.scatter(*P[inner].T, c=rep.deviation[inner], cmap="coolwarm", vmin=-m, vmax=m,
                    s=8, depthshade=False)
    if (ok & rep.edge).any():
        e = ok & rep.edge
        ax.scatter(*P[e].T, c=rep.deviation[e], cmap="coolwarm", vmin=-m, vmax=m, s=14,
                   marker="^", depthshade=False)
    if (~ok).any():
        ax.scatter(*P[~ok].T, color="k", s=6, marker="x")
    cb = fig.colorbar(sc, ax=ax, shrink=0.7)
    cb.set_label("deviation along the nominal normal")
    if rep.tolerance:
        for t in rep.tolerance:
            cb.ax.axhline(t, color="k", lw=1)
    ax.set_xlabel("x")
    ax.set_ylabel("y")
    ax.set_zlabel("z")
    s = rep.stats
    ax.set_title(f"{s['valid']} points: min {s['min']:.4g}, max {s['max']:.4g}, "
                 f"rms {s['rms']:.4g}")
    try:
        ax.set_box_aspect(np.ptp(np.vstack([V, P[ok]]), axis=0) + 1e-9 * size)
    except Exception:  # older matplotlib
        pass
    return _save_fig(fig, path, overwrite)


def plot_histogram(rep, path, overwrite: bool = False, bins: int = 40) -> Path:
    """PNG: histogram of the deviations with the tolerance band marked."""
    fig = _figure(figsize=(7, 4.5))
    ax = fig.add_subplot()
    v = rep.deviation[np.isfinite(rep.deviation)]
    if v.size:
        ax.hist(v, bins=bins, color="#4477aa")
    if rep.tolerance:
        lo, hi = rep.tolerance
        ax.axvspan(lo, hi, color="#88cc88", alpha=0.3, label=f"tolerance [{lo:g}, {hi:g}]")
        ax.legend()
    ax.set_xlabel("deviation along the nominal normal")
    ax.set_ylabel("points")
    s = rep.stats
    title = f"mean {s['mean']:.4g}, std {s['std']:.4g}, rms {s['rms']:.4g}"
    if rep.tolerance:
        title += f"; in {s['pct_within']:.1f}%, over {s['pct_over']:.1f}%, " \
                 f"under {s['pct_under']:.1f}%"
    ax.set_title(title, fontsize=9)
    fig.tight_layout()
    return _save_fig(fig, path, overwrite)


def plot_section(sections, path, overwrite: bool = False) -> Path:
    """PNG: the section curves of one or several planes (3-D view)."""
    fig = _figure(figsize=(7, 6))
    ax = fig.add_subplot(projection="3d")
    for sec in sections:
        sec.plot(ax=ax)
    ax.set_xlabel("x")
    ax.set_ylabel("y")
    ax.set_zlabel("z")
    n = sum(len(s.curves) for s in sections)
    ax.set_title(f"{len(sections)} plane(s), {n} curve(s)")
    return _save_fig(fig, path, overwrite)


def write_section(section, targets: dict, fit_tol=None, overwrite: bool = False) -> dict:
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
        out["png"] = str(plot_section([section], targets["png"], overwrite=overwrite))
    return out


def write_clearance_csv(res, path_points, path, overwrite: bool = False) -> Path:
    """One row per path segment of a :class:`geomkit.Clearance`: ``segment``, start and
    end tip centres, ``motion``, ``clearance``, ``lower_bound``, ``component``,
    ``parameter``, the closest part point, ``surface``, ``first_contact`` (empty when
    clear), ``passed``, ``certified`` and each stylus piece's clearance."""
    p = _check_target(path, overwrite)
    names = list(res.component_names)
    head = ["segment", "x0", "y0", "z0", "x1", "y1", "z1", "motion", "clearance",
            "lower_bound", "component", "parameter", "part_x", "part_y", "part_z",
            "surface", "first_contact", "passed", "certified"] + [f"clearance_{n}"
                                                                  for n in names]
    lines = [",".join(head)]
    for i in range(len(res)):
        vals = [str(i)] + [_fmt(c) for c in path_points[i]] + [_fmt(c) for c in
                                                               path_points[i + 1]]
        vals += [res.motion[i], _fmt(res.clearance[i]), _fmt(res.lower_bound[i]),
                 names[int(res.component[i])], _fmt(res.parameter[i])]
        vals += [_fmt(c) for c in res.point_part[i]]
        vals += [str(int(res.surface[i])), _fmt(res.first_contact[i]),
                 str(int(bool(res.passed[i]))), str(int(bool(res.certified[i])))]
        vals += [_fmt(c) for c in res.per_component[i]]
        lines.append(",".join(vals))
    data = ("\n".join(lines) + "\n").encode("utf-8")
    return _atomic_write(p, lambda fh: fh.write(data))


def plot_clearance(res, path, overwrite: bool = False) -> Path:
    """Bar chart of the certified clearance per segment, the margin as a line, failing
    segments in red and first-contact segments hatched."""
    fig = _figure(figsize=(8, 4), layout="constrained")
    ax = fig.add_subplot(1, 1, 1)
    k = np.arange(len(res))
    colours = ["tab:green" if ok else "tab:red" for ok in res.passed]
    bars = ax.bar(k, res.lower_bound, color=colours, edgecolor="black", linewidth=0.5)
    top = float(np.max(res.lower_bound)) if len(res) else 1.0
    for i, (b, fc) in enumerate(zip(bars, res.first_contact)):
        if np.isfinite(fc):
            b.set_hatch("//")
            ax.plot([i], [0.0], marker="x", color="tab:red", markersize=10, mew=2)
            ax.annotate(f"contact\ns = {fc:.4f}", (i, 0.0), xytext=(0, 8),
                        textcoords="offset points", ha="center", color="tab:red")
    ax.set_ylim(0.0, 1.15 * max(top, res.margin, 1e-12))
    if res.margin > 0:
        ax.axhline(res.margin, color="black", linestyle="--", linewidth=1,
                   label=f"margin {res.margin:g}")
        ax.legend(loc="upper right")
    ax.set_xlabel("path segment")
    ax.set_ylabel("certified clearance")
    ax.set_title(f"probe clearance: {int(np.sum(~res.passed))} of {len(res)} segments "
                 f"fail; min {float(np.min(res.lower_bound)):.4g}")
    if len(res) <= 30:
        ax.set_xticks(k)
    return _save_fig(fig, path, overwrite)
