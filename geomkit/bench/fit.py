"""Benchmark of :func:`geomkit.fitting.fit` (least squares) against scikit-spatial's
``best_fit`` and :func:`scipy.optimize.least_squares` on the same points.

Points are sampled on a known feature, 1e3 from the origin along a random axis, and
displaced +-h in symmetric pairs along the normal, so the least-squares solution is
the nominal feature: the "error" of every engine is measured against that truth
(worst of positions / radii over the feature size and directions in radians).
scikit-spatial is optional: without it its columns are empty and the note says so.
"""

from __future__ import annotations

import time

import numpy as np

KINDS = ("plane", "line", "circle", "sphere", "cylinder", "cone")
#: scikit-spatial's cylinder fit is a slow generic optimisation: capped at this size.
SKSPATIAL_CYLINDER_MAX = 10_000


def _rotation(seed):
    from scipy.spatial.transform import Rotation
    return Rotation.random(random_state=seed).as_matrix()


def make_case(kind, n, seed=0, h=0.01):
    """(points, truth dict, size) for ``kind`` with ``n`` points (n even)."""
    rng = np.random.default_rng(seed)
    R = _rotation(seed + 1)
    t = rng.normal(size=3)
    t = 1e3 * t / np.linalg.norm(t)
    m = n // 2
    th = rng.uniform(0, 2 * np.pi, m)
    c, s, z0 = np.cos(th), np.sin(th), np.zeros(m)
    if kind == "plane":
        P, N, size = np.column_stack([rng.uniform(-10, 10, (m, 2)), z0]), \
            np.tile([0.0, 0, 1], (m, 1)), 10.0
    elif kind == "line":
        P, N, size = np.column_stack([z0, z0, rng.uniform(-30, 30, m)]), \
            np.column_stack([c, s, z0]), 30.0
    elif kind == "circle":
        P, N, size = 5 * np.column_stack([c, s, z0]), np.column_stack([c, s, z0]), 5.0
    elif kind == "sphere":
        N = rng.normal(size=(m, 3))
        N /= np.linalg.norm(N, axis=1)[:, None]
        P, size = 7 * N, 7.0
    elif kind == "cylinder":
        N = np.column_stack([c, s, z0])
        P, size = 20 * N + np.column_stack([z0, z0, rng.uniform(-50, 50, m)]), 50.0
    else:
        phi, hh = 0.3, rng.uniform(10, 40, m)
        P = np.column_stack([hh * np.tan(phi) * c, hh * np.tan(phi) * s, hh])
        N = np.column_stack([np.cos(phi) * c, np.cos(phi) * s, -np.sin(phi) + z0])
        size = 40.0
    d = h * rng.uniform(0.2, 1.0, m)[:, None]
    Q = np.vstack([P + d * N, P - d * N]) @ R.T + t
    zax = R[:, 2]
    truth = {"plane": {"point": t, "normal": zax}, "line": {"point": t, "axis": zax},
             "circle": {"center": t, "normal": zax, "radius": 5.0},
             "sphere": {"center": t, "radius": 7.0},
             "cylinder": {"point": t, "axis": zax, "radius": 20.0},
             "cone": {"apex": t, "axis": zax, "half_angle": 0.3}}[kind]
    return Q, truth, size


def error(kind, got, truth, size):
    """Worst error of a {name: value} geometry against ``truth``."""
    worst = 0.0
    ax = truth.get("axis", truth.get("normal"))
    for k, v in truth.items():
        g = np.asarray(got[k], dtype=float)
        if k in ("normal", "axis"):
            cr = np.linalg.norm(np.cross(g / np.linalg.norm(g), v))
            e = float(cr) if kind != "cone" or g @ v > 0 else np.pi
        elif k == "point":
            q = g - v
            e = abs(q @ ax) / size if kind == "plane" else \
                float(np.linalg.norm(q - (q @ ax) * ax)) / size
        elif k == "half_angle":
            e = abs(float(g) - v)
        else:
            e = float(np.linalg.norm(g - v)) / size
        worst = max(worst, e)
    return worst


def _geomkit(kind, P):
    from geomkit.fitting import fit
    r = fit(P, kind)
    g = dict(r.geometry)
    if kind == "line":
        g["axis"] = g["direction"]
    return g


def _skspatial(kind, P):
    import skspatial.objects as so
    if kind == "plane":
        p = so.Plane.best_fit(P, full_matrices=False)
        return {"point": np.asarray(p.point), "normal": np.asarray(p.normal)}
    if kind == "line":
        ln = so.Line.best_fit(P, full_matrices=False)
        return {"point": np.asarray(ln.point), "axis": np.asarray(ln.direction)}
    if kind == "sphere":
        s = so.Sphere.best_fit(P)
        return {"center": np.asarray(s.point), "radius": float(s.radius)}
    if kind == "cylinder":
        c = so.Cylinder.best_fit(P)
        a = np.asarray(c.vector, float)
        return {"point": np.asarray(c.point), "axis": a / np.linalg.norm(a),
                "radius": float(c.radius)}
    return None


def _scipy(kind, P, truth):
    """scipy least_squares (method 'lm') from the truth perturbed by 1e-3."""
    from scipy.optimize import least_squares
    if kind == "sphere":
        x0 = np.concatenate([truth["center"] + 1e-3, [truth["radius"] + 1e-3]])
        sol = least_squares(lambda x: np.linalg.norm(P - x[:3], axis=1) - x[3], x0,
                            method="lm", xtol=1e-15, ftol=1e-15)
        return {"center": sol.x[:3], "radius": sol.x[3]}
    if kind == "cylinder":
        a = truth["axis"]

        def axis(x):
            return np.array([np.sin(x[3]) * np.cos(x[4]), np.sin(x[3]) * np.sin(x[4]),
                             np.cos(x[3])])

        def f(x):
            q = P - x[:3]
            w = axis(x)
            return np.linalg.norm(q - np.outer(q @ w, w), axis=1) - x[5]
        x0 = np.concatenate([truth["point"] + 1e-3, [np.arccos(a[2]) + 1e-3,
                                                     np.arctan2(a[1], a[0]), 20.001]])
        sol = least_squares(f, x0, method="lm", xtol=1e-15, ftol=1e-15)
        return {"point": sol.x[:3], "axis": axis(sol.x), "radius": sol.x[5]}
    return None


def _timed(fn):
    t0 = time.perf_counter()
    out = fn()
    return time.perf_counter() - t0, out


def run(sizes=(1000, 100000, 1000000), kinds=KINDS):
    """One row per (kind, size): seconds and worst error of geomkit, scikit-spatial
    and scipy.optimize.least_squares (None when not run, with a note)."""
    try:
        import skspatial  # noqa: F401
        have_sk = True
    except ImportError:
        have_sk = False
    rows = []
    for kind in kinds:
        for n in sizes:
            P, truth, size = make_case(kind, int(n))
            row = {"kind": kind, "n": int(n), "note": ""}
            t, g = _timed(lambda: _geomkit(kind, P))
            row.update(geomkit_s=t, geomkit_err=error(kind, g, truth, size))
            row.update(skspatial_s=None, skspatial_err=None, scipy_s=None, scipy_err=None)
            if not have_sk:
                row["note"] = "scikit-spatial not installed"
            elif kind in ("plane", "line", "sphere") or \
                    (kind == "cylinder" and n <= SKSPATIAL_CYLINDER_MAX):
                t, g = _timed(lambda: _skspatial(kind, P))
                row.update(skspatial_s=t, skspatial_err=error(kind, g, truth, size))
            else:
                row["note"] = "no scikit-spatial fit" if kind in ("circle", "cone") \
                    else f"scikit-spatial skipped above {SKSPATIAL_CYLINDER_MAX} points"
            if kind in ("sphere", "cylinder"):
                t, g = _timed(lambda: _scipy(kind, P, truth))
                row.update(scipy_s=t, scipy_err=error(kind, g, truth, size))
            rows.append(row)
    return rows


def sweep(sizes=(1000, 100000), kinds=KINDS):
    """:func:`run` as rows of the common schema (:mod:`geomkit.bench._common`) for
    ``geomkit bench``: one row per (kind, size) and reference (scikit-spatial where it
    has the fit, else scipy's ``least_squares`` where it is run); the error is the
    worst parameter error against the known feature, relative to its size (radians
    for directions)."""
    from geomkit.bench._common import make_row

    rows = []
    for r in run(sizes, kinds):
        refs = [(name, r[f"{key}_s"], r[f"{key}_err"])
                for name, key in (("scikit-spatial", "skspatial"),
                                  ("scipy least_squares", "scipy"))
                if r[f"{key}_s"] is not None]
        for name, rs, re_ in refs or [(None, None, None)]:
            rows.append(make_row("fit", r["kind"], "points", r["n"], r["geomkit_s"],
                                 r["geomkit_err"], name, rs, re_, per="call",
                                 note="least squares; error relative to the size"
                                 + (f"; {r['note']}" if r["note"] else "")))
    return rows


def main(sizes=(1000, 100000, 1000000)):
    """Print the table of :func:`run`."""
    def f(x, fmt):
        return format("-", ">" + fmt.split(".")[0]) if x is None else format(x, fmt)

    print(f"{'kind':9}{'n':>9} {'geomkit s':>10} {'err':>9} {'skspatial s':>12} "
          f"{'err':>9} {'scipy s':>9} {'err':>9}  note")
    for r in run(sizes):
        print(f"{r['kind']:9}{r['n']:>9} {f(r['geomkit_s'], '10.4f')} "
              f"{f(r['geomkit_err'], '9.1e')} {f(r['skspatial_s'], '12.4f')} "
              f"{f(r['skspatial_err'], '9.1e')} {f(r['scipy_s'], '9.4f')} "
              f"{f(r['scipy_err'], '9.1e')}  {r['note']}")


if __name__ == "__main__":
    main()
