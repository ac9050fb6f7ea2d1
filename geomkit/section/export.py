"""Fitting and export of plane sections (private helper of :mod:`geomkit.section.plane`).

* :func:`fit_curves` — least-squares cubic B-splines (scipy ``make_lsq_spline``) with
  knot doubling until the error is <= tol, measured at the exact section points and
  at exact curve midpoints between them (Newton on the surface and the plane).
* :func:`to_csv`, :func:`to_dxf` (ezdxf POLYLINE 3-D, SPLINE, POINT),
  :func:`to_json` (geomdl curve JSON), :func:`plot` (matplotlib).

Files are written atomically and never overwrite an existing file unless asked.
"""

from __future__ import annotations

import io
import json
from dataclasses import dataclass

import numpy as np

from geomkit.errors import InvalidInputError, MissingDependencyError
from geomkit.outputs import atomic_write, check_target


@dataclass(eq=False)
class FittedCurve:
    """A clamped B-spline curve fitted to one section curve.

    Attributes
    ----------
    degree : int
    knots : (n + degree + 1,) float, clamped, over [0, 1].
    control_points : (n, 3) float.
    closed : bool, the section curve is a loop (the fit starts and ends near one point).
    max_error : float, largest distance ``|C(t_i) - P_i|`` over the exact section points
        and the exact curve midpoints between them (an upper bound of the distance from
        the exact points to the fitted curve).
    plane_error : float, largest plane residual of the fitted curve at 8 samples per data
        interval (a lower bound of its deviation from the exact section).
    """

    degree: int
    knots: np.ndarray
    control_points: np.ndarray
    closed: bool
    max_error: float
    plane_error: float

    def evaluate(self, t) -> np.ndarray:
        """Points (n, 3) at parameters ``t`` (n,) in [0, 1]."""
        from scipy.interpolate import BSpline

        return BSpline(self.knots, self.control_points, self.degree)(np.asarray(t, float))


def _exact_midpoints(section, ci):
    """Exact curve points between consecutive points of curve ``ci`` (same surface)."""
    from geomkit.section.trace import _Eval

    uv, sid, X = section.uv[ci], section.surface_index[ci], section.curves[ci]
    if section.closed[ci]:
        uv = np.concatenate([uv, uv[:1]])
        sid = np.concatenate([sid, sid[:1]])
        X = np.concatenate([X, X[:1]])
    M = 0.5 * (X[:-1] + X[1:])
    same = sid[:-1] == sid[1:]
    for k in np.unique(sid):
        sel = np.nonzero(same & (sid[:-1] == k))[0]
        if not len(sel):
            continue
        ev = _Eval(section.surfaces[int(k)], section.plane)
        a, b = uv[sel], uv[sel + 1]
        mid, f = ev.project(0.5 * (a + b), np.linalg.norm(b - a, axis=1), 1e-14)
        Y = ev.points(mid)
        # a UV midpoint across a seam projects elsewhere: keep the chord midpoint
        # there (within the section's chord tolerance of the curve)
        near = (np.linalg.norm(Y - M[sel], axis=1)
                <= np.linalg.norm(X[sel + 1] - X[sel], axis=1))
        ok = (np.abs(f) <= 1e-9) & near
        M[sel[ok]] = Y[ok]
    return X, M


def fit_curves(section, tol: float) -> list:
    """Fit each curve of ``section`` by a B-spline within ``tol``.

    Returns
    -------
    list of FittedCurve, one per curve; ``max_error <= tol`` unless the data could not
    be fitted (then the interpolating spline is returned with its measured error).
    """
    from scipy.interpolate import make_interp_spline, make_lsq_spline

    tol = float(tol)
    if not (np.isfinite(tol) and tol > 0):
        raise InvalidInputError(f"must be a finite number > 0, got {tol!r}", "tol")
    out = []
    for ci in range(len(section.curves)):
        X, M = _exact_midpoints(section, ci)
        # data: points and exact midpoints interleaved
        D = np.empty((2 * len(X) - 1, 3))
        D[0::2] = X
        D[1::2] = M
        seg = np.linalg.norm(np.diff(D, axis=0), axis=1)
        t = np.concatenate([[0.0], np.cumsum(seg)])
        t = t / t[-1] if t[-1] > 0 else np.linspace(0, 1, len(D))
        k = int(min(3, len(X) - 1))
        if k < 1:
            continue
        nseg = 1
        best = None
        while True:
            nint = nseg - 1
            if len(D) < nint + 2 * (k + 1):
                spl = make_interp_spline(t[0::2], X, k=k)
            else:
                inner = np.quantile(t, np.linspace(0, 1, nseg + 1)[1:-1]) if nint else []
                knots = np.concatenate([[0.0] * (k + 1), inner, [1.0] * (k + 1)])
                try:
                    spl = make_lsq_spline(t, D, knots, k=k)
                except Exception:  # Schoenberg-Whitney failure: interpolate instead
                    spl = make_interp_spline(t[0::2], X, k=k)
            err = float(np.max(np.linalg.norm(spl(t) - D, axis=1)))
            if best is None or err < best[1]:
                best = (spl, err)
            if err <= tol or len(spl.c) >= len(X):
                break
            nseg *= 2
        spl, err = best
        dense = np.linspace(0, 1, 8 * len(D))
        pe = float(np.max(np.abs(spl(dense) @ section.plane[:3] + section.plane[3])))
        out.append(FittedCurve(int(spl.k), np.asarray(spl.t, float),
                               np.asarray(spl.c, float).reshape(-1, 3),
                               bool(section.closed[ci]), err, pe))
    return out


def _units(section, units):
    """The section's length unit: ``units`` if given, else the section's ``units``
    attribute (None: unknown)."""
    return units if units is not None else getattr(section, "units", None)


def to_csv(section, path, overwrite=False, units=None):
    """Rows ``curve,index,x,y,z,u,v,surface,units``; isolated points have curve -1.
    ``units`` names the length unit of x, y, z ("model units" when unknown)."""
    from geomkit.units import unit_label

    p = check_target(path, overwrite)
    u = unit_label(_units(section, units))
    u = f'"{u}"' if ("," in u or '"' in u) else u
    lines = ["curve,index,x,y,z,u,v,surface,units"]
    for ci, (X, uv, sid) in enumerate(zip(section.curves, section.uv, section.surface_index)):
        for i in range(len(X)):
            lines.append(f"{ci},{i},{float(X[i, 0])!r},{float(X[i, 1])!r},{float(X[i, 2])!r},"
                         f"{float(uv[i, 0])!r},{float(uv[i, 1])!r},{int(sid[i])},{u}")
    for i in range(len(section.points)):
        X, uv = section.points[i], section.points_uv[i]
        lines.append(f"-1,{i},{float(X[0])!r},{float(X[1])!r},{float(X[2])!r},"
                     f"{float(uv[0])!r},{float(uv[1])!r},"
                     f"{int(section.points_surface[i])},{u}")
    text = "\n".join(lines) + "\n"
    return atomic_write(p, lambda fh: fh.write(text.encode("utf-8")))


def read_csv(path):
    """Curves and points back from :func:`to_csv`: ``(list of (k, 3), (m, 3))``."""
    a = np.loadtxt(path, delimiter=",", skiprows=1, ndmin=2, usecols=range(8))
    curves = [a[a[:, 0] == c][:, 2:5] for c in np.unique(a[:, 0]) if c >= 0]
    return curves, a[a[:, 0] == -1][:, 2:5]


def to_dxf(section, path, fit_tol=None, overwrite=False, units=None):
    """3-D POLYLINEs (closed flag kept), POINTs, and SPLINEs of the fit if asked.

    The header declares the model's length unit (``$INSUNITS``: mm 4, in 1, m 6, ...;
    0, unitless, when unknown) so unit-aware CAD does not rescale the coordinates."""
    from geomkit.units import dxf_insunits

    try:
        import ezdxf
    except ImportError as exc:  # pragma: no cover - declared dependency
        raise MissingDependencyError("to_dxf needs ezdxf (pip install ezdxf)") from exc
    p = check_target(path, overwrite)
    code = dxf_insunits(_units(section, units))
    doc = ezdxf.new("R2010", units=code)
    doc.header["$INSUNITS"] = code
    doc.header["$MEASUREMENT"] = 0 if code in (1, 2, 3, 8, 9, 10) else 1
    msp = doc.modelspace()
    for X, closed in zip(section.curves, section.closed):
        msp.add_polyline3d([tuple(map(float, x)) for x in X], close=bool(closed),
                           dxfattribs={"layer": "SECTION"})
    for x in section.points:
        msp.add_point(tuple(map(float, x)), dxfattribs={"layer": "SECTION_POINTS"})
    if fit_tol is not None:
        for fc in section.fit(fit_tol):
            msp.add_open_spline([tuple(c) for c in fc.control_points], degree=fc.degree,
                                knots=[float(k) for k in fc.knots],
                                dxfattribs={"layer": "SECTION_FIT"})
    buf = io.StringIO()
    doc.write(buf)
    text = buf.getvalue()
    return atomic_write(p, lambda fh: fh.write(text.encode("utf-8")))


def to_json(section, path, fit_tol=None, overwrite=False):
    """geomdl curve JSON (``exchange.import_json`` reads it back)."""
    p = check_target(path, overwrite)
    data = []
    if fit_tol is None:
        for X, closed in zip(section.curves, section.closed):
            P = np.concatenate([X, X[:1]]) if closed else X
            t = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(P, axis=0), axis=1))])
            t = t / t[-1] if t[-1] > 0 else np.linspace(0, 1, len(P))
            knots = np.concatenate([[0.0], t, [1.0]])
            data.append(_geomdl_curve(1, knots, P))
    else:
        for fc in section.fit(fit_tol):
            data.append(_geomdl_curve(fc.degree, fc.knots, fc.control_points))
    doc = {"shape": {"type": "curve", "count": len(data), "data": data}}
    text = json.dumps(doc, indent=1)
    return atomic_write(p, lambda fh: fh.write(text.encode("utf-8")))


def _geomdl_curve(degree, knots, P):
    return {"type": "spline", "rational": False, "dimension": 3, "degree": int(degree),
            "knotvector": [float(k) for k in knots],
            "control_points": {"points": np.asarray(P, float).tolist()}, "delta": 0.01}


def plot(section, ax=None, **kwargs):
    """Curves as lines (closed ones closed) and points as markers on a 3-D axis."""
    import matplotlib.pyplot as plt

    if ax is None:
        ax = plt.figure().add_subplot(projection="3d")
    for X, closed in zip(section.curves, section.closed):
        P = np.concatenate([X, X[:1]]) if closed else X
        ax.plot(P[:, 0], P[:, 1], P[:, 2], **kwargs)
    if len(section.points):
        ax.scatter(*section.points.T, marker="o", color="k")
    return ax
