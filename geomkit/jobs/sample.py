"""Virtual measurement: points sampled on the exact trimmed faces of a part, with
planted form errors, probe noise and a rigid misplacement (issue 34).

The result is what a CMM would report of a part whose deviations are known, so the
deviation and GD&T evaluations can be checked against the truth.

Method
------
1. **Where**: on each selected face, a scrambled Sobol sequence in
   ``(u, v, w)`` over the UV box of the face (the domain, cut down to the box of its
   trim loops).  A candidate is kept when :meth:`Surface.classify_uv` calls it
   ``INSIDE`` (with ``margin``: also the UV points ``margin`` away in model units,
   a 9-point stencil) and ``w < J / J_max`` with ``J = |S_u x S_v|`` — rejection by
   the area element, so the points are spread evenly over the face's *area*, not its
   UV rectangle (a sphere's poles are not crowded).  The first ``per_face`` kept
   points of the sequence are taken: a prefix of a low-discrepancy sequence is
   spread out, not clustered.  A face whose trimmed region is a small part of its
   box draws more candidates (doubling, up to :data:`MAX_CANDIDATES`); if it still
   has fewer than ``per_face`` the points found are kept, the face is listed in
   ``short`` and a warning says how many were found.
2. **Normals**: the exact unit normal ``S_u x S_v / |S_u x S_v|``, turned to point
   out of the material (``orient="outward"``): for each face, rays from a few of its
   points along ``+n`` and ``-n`` are cast against a tessellation of the whole part
   (chord tolerance ``1e-3`` of its size); an even count of crossings along ``+n``
   with an odd count along ``-n`` says ``n`` points out.  A face with no verdict
   (an open sheet, a model that is not closed) keeps ``S_u x S_v``; ``orientation``
   says which faces were decided.  ``orient="surface"`` keeps ``S_u x S_v``
   everywhere (the sign convention of :func:`geomkit.deviation`).
3. **Planted form errors** (per face, in the order given; directions are the
   outward normal ``n`` at each nominal point):

   * ``{"kind": "bump", "center": (x, y, z), "radius": r, "height": h}``: moved by
     ``h * (1 + cos(pi d / r)) / 2`` along ``n`` where ``d = |p - center| < r`` (a
     smooth C1 bump, ``h`` at the centre, 0 from ``r`` on);
   * ``{"kind": "tilt", "axis": (x, y, z), "angle": a[, "center": (x, y, z)]}``:
     rotated by ``a`` radians about the axis through ``center`` (default: the
     centroid of the face's points);
   * ``{"kind": "offset", "distance": d}``: moved by ``d`` along ``n``; or
     ``{"kind": "offset", "translate": (x, y, z)}``: moved by that vector (a shifted
     hole);
   * ``{"kind": "scale", "factor": f[, "axis": (x, y, z)][, "center": (x, y, z)]}``:
     the distance from the axis through ``center`` (default the centroid) multiplied
     by ``f`` (a hole or shaft grown radially); without ``axis`` the distance from
     ``center`` (a sphere grown).

   ``planted`` is the normal component ``(p_measured - p_nominal) . n`` of the
   displacement before the misplacement: exact for bumps, offsets along ``n`` and
   noise, to first order for the others.
4. **Noise**: a Gaussian displacement of standard deviation ``noise`` along ``n``
   (``numpy.random.default_rng(seed)``: reproducible).
5. **Misplacement**: ``transform`` (4 x 4, rigid) is applied to every point last
   (the part misplaced on the machine).  ``normals`` and ``nominal`` stay in the
   part's frame (the nominal approach directions of the program).
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from geomkit.errors import InvalidInputError
from geomkit.nurbs.surface import as_surfaces
from geomkit.nurbs.trimming import INSIDE

__all__ = ["sample_faces", "SampledPoints", "FORM_ERROR_KINDS", "MAX_CANDIDATES"]

FORM_ERROR_KINDS = ("bump", "tilt", "offset", "scale")
"""The planted form errors :func:`sample_faces` knows."""

MAX_CANDIDATES = 1 << 20
"""UV candidates drawn at most per face before a face is reported short."""

_ORIENT_TOL = 1e-3
"""Chord tolerance of the orientation mesh, relative to the part's size."""

_ORIENT_POINTS = 5
"""Points per face whose rays vote on its outward side."""

CSV_HEADER = "x,y,z,i,j,k,face,u,v"


@dataclass(eq=False)
class SampledPoints:
    """Result of :func:`sample_faces`.

    Attributes
    ----------
    points : (n, 3) float, the "measured" points (form errors, noise, misplacement).
    normals : (n, 3) float, the nominal outward unit normals (the part's frame).
    face : (n,) int64, index of the face each point was sampled on.
    uv : (n, 2) float, its parameters on that face.
    nominal : (n, 3) float, the exact nominal points ``S(u, v)`` (the part's frame).
    planted : (n,) float, the planted deviation along ``normals`` (form errors plus
        noise, before the misplacement).
    noise : (n,) float, the noise part of ``planted``.
    per_face : int, the points asked for per face.
    counts : dict face -> points found.
    short : dict face -> points found, for the faces with fewer than ``per_face``.
    orientation : dict face -> ``"outward"`` (normal turned out of the material),
        ``"flipped"`` (``S_u x S_v`` pointed in and was turned) or ``"surface"``
        (no verdict or ``orient="surface"``: ``S_u x S_v`` kept).
    transform : (4, 4) float, the misplacement applied (identity when none).
    settings : dict, the arguments (noise, seed, margin, form errors, orient).
    """

    points: np.ndarray
    normals: np.ndarray
    face: np.ndarray
    uv: np.ndarray
    nominal: np.ndarray
    planted: np.ndarray
    noise: np.ndarray
    per_face: int
    counts: dict
    short: dict
    orientation: dict
    transform: np.ndarray
    settings: dict = field(default_factory=dict)

    def __len__(self) -> int:
        return int(self.points.shape[0])

    def __repr__(self) -> str:
        return (f"<SampledPoints {len(self)} points on {len(self.counts)} face(s), "
                f"noise {self.settings.get('noise', 0.0):g}>")

    def summary(self) -> dict:
        """JSON-ready counts, planted-deviation statistics and settings."""
        p, z = self.planted, self.noise
        stat = (lambda a, f: float(f(a)) if a.size else None)
        return {"points": len(self), "faces": len(self.counts), "per_face": self.per_face,
                "counts": {int(k): int(v) for k, v in self.counts.items()},
                "short_faces": {int(k): int(v) for k, v in self.short.items()},
                "flipped_faces": sorted(int(k) for k, v in self.orientation.items()
                                        if v == "flipped"),
                "undecided_faces": sorted(int(k) for k, v in self.orientation.items()
                                          if v == "surface"),
                "planted": {"min": stat(p, np.min), "max": stat(p, np.max),
                            "mean": stat(p, np.mean), "rms": stat(p, _rms)},
                "noise_std": stat(z, np.std),
                "transform": self.transform.tolist(),
                **self.settings}

    def to_csv(self, path, overwrite: bool = False) -> Path:
        """Write ``x,y,z,i,j,k,face,u,v`` (one point a row; ``i,j,k`` the nominal
        outward normal) through a temporary file; an existing file is kept unless
        ``overwrite``.  Returns the path."""
        from geomkit.outputs import atomic_write, check_target

        target = check_target(path, overwrite)
        data = self.csv_text().encode("utf-8")
        return atomic_write(target, lambda fh: fh.write(data))

    def csv_text(self) -> str:
        """The CSV of :meth:`to_csv` as a string."""
        rows = [CSV_HEADER]
        for p, n, f, t in zip(self.points.tolist(), self.normals.tolist(),
                              self.face.tolist(), self.uv.tolist()):
            rows.append(",".join([*map(repr, p), *map(repr, n), str(f), *map(repr, t)]))
        return "\n".join(rows) + "\n"


def _rms(a):
    return np.sqrt(np.mean(np.square(a)))


# ------------------------------------------------------------------ validation
def _number(value, field, minimum=None, positive=False) -> float:
    try:
        x = float(value)
    except (TypeError, ValueError):
        raise InvalidInputError(f"expected a number, got {value!r}", field) from None
    if not math.isfinite(x):
        raise InvalidInputError(f"must be finite, got {x!r}", field)
    if positive and not x > 0:
        raise InvalidInputError(f"must be > 0, got {x!r}", field)
    if minimum is not None and x < minimum:
        raise InvalidInputError(f"must be >= {minimum:g}, got {x!r}", field)
    return x


def _vector(value, field, unit=False) -> np.ndarray:
    try:
        v = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        raise InvalidInputError(f"expected 3 numbers (x, y, z), got {value!r}",
                                field) from None
    if v.shape != (3,) or not np.all(np.isfinite(v)):
        raise InvalidInputError(f"expected 3 finite numbers (x, y, z), got {value!r}", field)
    if unit:
        n = np.linalg.norm(v)
        if n == 0:
            raise InvalidInputError("must not be the zero vector", field)
        v = v / n
    return v


def _faces(faces, n) -> list:
    if faces is None:
        return list(range(n))
    if isinstance(faces, (int, np.integer)):
        faces = [faces]
    try:
        raw = list(faces)
    except TypeError:
        raise InvalidInputError(f"expected face indices, got {faces!r}", "faces") from None
    out = []
    for f in raw:
        if isinstance(f, (bool, np.bool_)) or not isinstance(f, (int, np.integer)):
            raise InvalidInputError(f"expected integer face indices, got {f!r}", "faces")
        if not 0 <= int(f) < n:
            raise InvalidInputError(f"face {int(f)} is out of range: the part has {n} "
                                    f"face(s), 0..{n - 1}", "faces")
        if int(f) not in out:
            out.append(int(f))
    if not out:
        raise InvalidInputError("no face selected", "faces")
    return out


def _check_form_errors(form_errors, n) -> dict:
    """``{face: [spec, ...]}`` checked, vectors as arrays."""
    if form_errors is None:
        return {}
    if not isinstance(form_errors, dict):
        raise InvalidInputError("expected a dict face -> list of form-error specs, got "
                                f"{type(form_errors).__name__}", "form_errors")
    out = {}
    for f, specs in form_errors.items():
        if isinstance(f, (bool, np.bool_)) or not isinstance(f, (int, np.integer)) \
                or not 0 <= int(f) < n:
            raise InvalidInputError(f"face {f!r} is not a face index 0..{n - 1}",
                                    "form_errors")
        if isinstance(specs, dict):
            specs = [specs]
        if not isinstance(specs, (list, tuple)):
            raise InvalidInputError(f"expected a list of specs, got {specs!r}",
                                    f"form_errors[{f}]")
        checked = []
        for k, spec in enumerate(specs):
            checked.append(_check_spec(spec, f"form_errors[{int(f)}][{k}]"))
        out[int(f)] = checked
    return out


_KEYS = {"bump": ({"center", "radius", "height"}, set()),
         "tilt": ({"axis", "angle"}, {"center"}),
         "offset": (set(), {"distance", "translate"}),
         "scale": ({"factor"}, {"axis", "center"})}


def _check_spec(spec, fld) -> dict:
    if not isinstance(spec, dict):
        raise InvalidInputError(f"expected a dict with a 'kind', got {spec!r}", fld)
    kind = spec.get("kind")
    if kind not in _KEYS:
        raise InvalidInputError(f"unknown form-error kind {kind!r}; use "
                                f"{', '.join(FORM_ERROR_KINDS)}", f"{fld}.kind")
    need, optional = _KEYS[kind]
    missing = sorted(need - set(spec))
    if missing:
        raise InvalidInputError(f"{kind} needs {', '.join(missing)}", fld)
    extra = sorted(set(spec) - need - optional - {"kind"})
    if extra:
        raise InvalidInputError(f"unknown key(s) {', '.join(extra)} for {kind}; expected "
                                f"{', '.join(sorted(need | optional))}", fld)
    out = {"kind": kind}
    if kind == "bump":
        out["center"] = _vector(spec["center"], f"{fld}.center")
        out["radius"] = _number(spec["radius"], f"{fld}.radius", positive=True)
        out["height"] = _number(spec["height"], f"{fld}.height")
    elif kind == "tilt":
        out["axis"] = _vector(spec["axis"], f"{fld}.axis", unit=True)
        out["angle"] = _number(spec["angle"], f"{fld}.angle")
    elif kind == "offset":
        if ("distance" in spec) == ("translate" in spec):
            raise InvalidInputError("offset needs one of distance (along the normal) or "
                                    "translate (a vector)", fld)
        if "distance" in spec:
            out["distance"] = _number(spec["distance"], f"{fld}.distance")
        else:
            out["translate"] = _vector(spec["translate"], f"{fld}.translate")
    else:
        out["factor"] = _number(spec["factor"], f"{fld}.factor", positive=True)
        if "axis" in spec:
            out["axis"] = _vector(spec["axis"], f"{fld}.axis", unit=True)
    if "center" in spec and kind != "bump":
        out["center"] = _vector(spec["center"], f"{fld}.center")
    return out


def check_transform(transform) -> np.ndarray:
    """A 4 x 4 rigid transform (rotation with det +1 within 1e-9, last row 0 0 0 1),
    or the identity for None."""
    if transform is None:
        return np.eye(4)
    try:
        T = np.asarray(transform, dtype=float)
    except (TypeError, ValueError):
        raise InvalidInputError("expected a 4 x 4 matrix of numbers", "transform") from None
    if T.shape != (4, 4) or not np.all(np.isfinite(T)):
        raise InvalidInputError(f"expected a finite 4 x 4 matrix, got shape {T.shape}",
                                "transform")
    R = T[:3, :3]
    err = float(np.abs(R @ R.T - np.eye(3)).max())
    if err > 1e-9 or np.linalg.det(R) < 0 or np.any(T[3] != [0, 0, 0, 1]):
        raise InvalidInputError("not rigid: the 3 x 3 block must be a rotation (R R^T = I "
                                f"within 1e-9, got {err:.1e}; det +1) and the last row "
                                "0 0 0 1", "transform")
    return T.copy()


# ---------------------------------------------------------------------- sampling
def _uv_box(s):
    """The UV box to draw from: the domain cut down to the box of the trim loops."""
    (u0, u1), (v0, v1) = s.domain
    if not s.trim:
        return u0, u1, v0, v1
    pts = []
    for loop in s.trim:
        for c in loop.pieces:
            H = np.asarray(c.homogeneous, dtype=float)
            pts.append(H[:, :2] / H[:, 2:3])
    P = np.concatenate(pts)
    lo, hi = P.min(axis=0), P.max(axis=0)
    a, b = max(u0, lo[0]), min(u1, hi[0])
    c, d = max(v0, lo[1]), min(v1, hi[1])
    if not (a < b and c < d):  # degenerate box: fall back to the domain
        return u0, u1, v0, v1
    return a, b, c, d


def _inside(s, uv, margin):
    """Candidates INSIDE the trimmed face (and ``margin`` in from its edges)."""
    ok = s.classify_uv(uv) == INSIDE
    if margin <= 0 or not ok.any():
        return ok
    idx = np.flatnonzero(ok)
    D = s.derivatives(uv[idx], 1)
    su = np.linalg.norm(D[:, 1, 0], axis=1)
    sv = np.linalg.norm(D[:, 0, 1], axis=1)
    (u0, u1), (v0, v1) = s.domain
    du = np.minimum(margin / np.maximum(su, 1e-300), u1 - u0)
    dv = np.minimum(margin / np.maximum(sv, 1e-300), v1 - v0)
    keep = np.ones(idx.size, dtype=bool)
    for a, b in ((1, 0), (-1, 0), (0, 1), (0, -1), (1, 1), (1, -1), (-1, 1), (-1, -1)):
        f = 1 / math.sqrt(2) if a and b else 1.0
        q = uv[idx] + np.column_stack([a * f * du, b * f * dv])
        keep &= s.classify_uv(q) == INSIDE
    ok[idx] = keep
    return ok


def _sample_face(s, n, margin, rng):
    """``(uv (m, 2), points, unit normals)`` with m <= n points spread over the
    trimmed face by area (module doc, step 1)."""
    from scipy.stats import qmc

    a, b, c, d = _uv_box(s)
    sob = qmc.Sobol(d=3, scramble=True, seed=rng)
    kept_uv = np.empty((0, 2))
    drawn, jmax = 0, None
    batch = 1 << max(10, math.ceil(math.log2(max(1, 4 * n))))
    while drawn < MAX_CANDIDATES:
        m = min(batch, MAX_CANDIDATES - drawn)
        m = 1 << int(math.log2(m))  # Sobol balance: powers of two
        X = sob.random(m)
        drawn += m
        uv = np.column_stack([a + (b - a) * X[:, 0], c + (d - c) * X[:, 1]])
        ok = _inside(s, uv, margin)
        if ok.any():
            D = s.derivatives(uv[ok], 1)
            J = np.linalg.norm(np.cross(D[:, 1, 0], D[:, 0, 1]), axis=1)
            if jmax is None:
                jmax = float(J.max()) * 1.05
            jmax = max(jmax, float(J.max()))
            acc = np.zeros(uv.shape[0], dtype=bool)
            acc[ok] = (X[ok, 2] * jmax < J) & (J > 0)
            kept_uv = np.concatenate([kept_uv, uv[acc]])
        if kept_uv.shape[0] >= n:
            break
        batch *= 2
    uv = kept_uv[:n]
    pts = s.evaluate(uv)
    nrm, status = s.normals(uv, return_status=True)
    good = (status == 0) & np.all(np.isfinite(nrm), axis=1)
    return uv[good], pts[good], nrm[good]


def _ray_hits(origins, dirs, tri, tmin):
    """Crossings of each ray ``origins + t dirs`` (t > tmin) with triangles (T, 3, 3):
    Möller–Trumbore, vectorised over the triangles."""
    v0, e1, e2 = tri[:, 0], tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0]
    out = np.zeros(origins.shape[0], dtype=np.int64)
    for r in range(origins.shape[0]):
        o, dvec = origins[r], dirs[r]
        p = np.cross(dvec, e2)
        det = np.einsum("ij,ij->i", e1, p)
        ok = np.abs(det) > 1e-300
        inv = np.where(ok, 1.0 / np.where(ok, det, 1.0), 0.0)
        tv = o - v0
        u = np.einsum("ij,ij->i", tv, p) * inv
        q = np.cross(tv, e1)
        v = (q @ dvec) * inv
        t = np.einsum("ij,ij->i", e2, q) * inv
        hit = ok & (u >= 0) & (v >= 0) & (u + v <= 1) & (t > tmin)
        out[r] = int(hit.sum())
    return out


def _orientation(surfs, sel, pts_by_face, nrm_by_face, rng, dup=()):
    """``{face: +1 (normal points out), -1 (points in), 0 (no verdict)}`` by ray
    parity against a tessellation of the whole part (module doc, step 2), without
    the loose faces ``dup`` that duplicate a solid's face (they would be crossed
    twice)."""
    from geomkit.mesh.tessellate import tessellate

    lo = np.min([s.bounds[0] for s in surfs], axis=0)
    hi = np.max([s.bounds[1] for s in surfs], axis=0)
    size = float(np.linalg.norm(hi - lo)) or 1.0
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        mesh = tessellate([s for i, s in enumerate(surfs) if i not in dup] or surfs,
                          _ORIENT_TOL * size)
    tri = mesh.vertices[mesh.faces]
    tmin = 3.0 * max(float(mesh.max_deviation), _ORIENT_TOL * size) + 1e-9 * size
    verdict = {}
    for f in sel:
        P, N = pts_by_face[f], nrm_by_face[f]
        if P.shape[0] == 0:
            verdict[f] = 0
            continue
        k = rng.choice(P.shape[0], size=min(_ORIENT_POINTS, P.shape[0]), replace=False)
        jitter = 1e-3 * rng.standard_normal((k.size, 3))  # off edges and vertices
        d = N[k] + jitter
        d /= np.linalg.norm(d, axis=1)[:, None]
        plus = _ray_hits(P[k], d, tri, tmin) % 2
        minus = _ray_hits(P[k], -d, tri, tmin) % 2
        votes = np.where((plus == 0) & (minus == 1), 1, np.where((plus == 1) & (minus == 0),
                                                                 -1, 0))
        total = int(votes.sum())
        verdict[f] = 1 if total > 0 else (-1 if total < 0 else 0)
    return verdict


# ---------------------------------------------------------------- form errors
def _apply_form(spec, P, N, nominal):
    """Displaced points of one face after ``spec`` (directions: nominal normals N)."""
    kind = spec["kind"]
    centre = spec.get("center", nominal.mean(axis=0))
    if kind == "bump":
        dist = np.linalg.norm(nominal - spec["center"], axis=1)
        w = np.where(dist < spec["radius"], 0.5 * (1 + np.cos(np.pi * dist / spec["radius"])),
                     0.0)
        return P + (spec["height"] * w)[:, None] * N
    if kind == "offset":
        if "distance" in spec:
            return P + spec["distance"] * N
        return P + spec["translate"]
    if kind == "tilt":
        from scipy.spatial.transform import Rotation

        R = Rotation.from_rotvec(spec["axis"] * spec["angle"]).as_matrix()
        return (P - centre) @ R.T + centre
    # scale: radial about the axis through centre, or about centre
    rel = P - centre
    if "axis" in spec:
        ax = spec["axis"]
        along = (rel @ ax)[:, None] * ax
        return centre + along + spec["factor"] * (rel - along)
    return centre + spec["factor"] * rel


# --------------------------------------------------------------------- public
def sample_faces(surfaces, per_face, *, noise: float = 0.0, seed: int = 0, faces=None,
                 form_errors=None, transform=None, margin: float = 0.0,
                 orient: str = "outward") -> SampledPoints:
    """A virtual measurement: ``per_face`` points spread over each selected trimmed
    face, with planted form errors, Gaussian noise and a rigid misplacement.

    Parameters
    ----------
    surfaces : Surface, list of Surface, or a case / CAD read (its ``surfaces``)
    per_face : int >= 1
        Points per face (fewer on a face whose trimmed region cannot be found with
        :data:`MAX_CANDIDATES` candidates: see ``short`` and the warning).
    noise : float >= 0
        Standard deviation of the Gaussian displacement along the normal.
    seed : int
        Seeds the sample positions, the noise and the orientation rays: the same
        arguments give the same points.
    faces : iterable of int, optional
        The faces to sample (default all).
    form_errors : dict face -> list of specs, optional
        Planted form errors (module doc, step 3): ``bump``, ``tilt``, ``offset``,
        ``scale``.  A face with form errors is sampled even when not in ``faces``.
    transform : (4, 4) float, optional
        A rigid misplacement applied to every point last.
    margin : float >= 0
        Keep the points about this far (model units) inside the face's edges.
    orient : {"outward", "surface"}
        Turn each face's normals out of the material (ray parity on the whole part),
        or keep ``S_u x S_v``.

    Returns
    -------
    SampledPoints

    Raises
    ------
    InvalidInputError
        Naming the field: ``per_face`` < 1, negative or non-finite ``noise`` or
        ``margin``, a face index out of range, an unknown form-error kind or a
        missing key, a transform that is not rigid, an unknown ``orient``.
    """
    dup = set(getattr(surfaces, "duplicates", None) or {})
    surfs = as_surfaces(surfaces)
    if isinstance(per_face, (bool, np.bool_)) or not isinstance(per_face, (int, np.integer)):
        raise InvalidInputError(f"expected an integer >= 1, got {per_face!r}", "per_face")
    per_face = int(per_face)
    if per_face < 1:
        raise InvalidInputError(f"must be >= 1, got {per_face}", "per_face")
    noise = _number(noise, "noise", minimum=0.0)
    margin = _number(margin, "margin", minimum=0.0)
    if isinstance(seed, (bool, np.bool_)) or not isinstance(seed, (int, np.integer)) \
            or seed < 0:
        raise InvalidInputError(f"expected an integer >= 0, got {seed!r}", "seed")
    if orient not in ("outward", "surface"):
        raise InvalidInputError(f"expected 'outward' or 'surface', got {orient!r}", "orient")
    sel = _faces(faces, len(surfs))
    forms = _check_form_errors(form_errors, len(surfs))
    sel += [f for f in sorted(forms) if f not in sel]
    T = check_transform(transform)

    rng = np.random.default_rng(int(seed))
    face_rngs = rng.spawn(len(sel))
    uv_by, pts_by, nrm_by, counts, short = {}, {}, {}, {}, {}
    for f, frng in zip(sel, face_rngs):
        uv, P, N = _sample_face(surfs[f], per_face, margin, frng)
        uv_by[f], pts_by[f], nrm_by[f] = uv, P, N
        counts[f] = int(P.shape[0])
        if counts[f] < per_face:
            short[f] = counts[f]
    if short:
        shown = ", ".join(f"face {f}: {m}" for f, m in list(short.items())[:5])
        warnings.warn(f"{len(short)} face(s) gave fewer than {per_face} points inside "
                      f"their trim ({shown}{', ...' if len(short) > 5 else ''})",
                      stacklevel=2)
    orientation = {f: "surface" for f in sel}
    if orient == "outward":
        verdict = _orientation(surfs, sel, pts_by, nrm_by, rng.spawn(1)[0], dup)
        for f, v in verdict.items():
            if v < 0:
                nrm_by[f] = -nrm_by[f]
            orientation[f] = {1: "outward", -1: "flipped", 0: "surface"}[v]

    noise_rng = rng.spawn(1)[0]
    out = {k: [] for k in ("P", "N", "F", "UV", "P0", "Z")}
    for f in sel:
        P0, N = pts_by[f], nrm_by[f]
        P = P0.copy()
        for spec in forms.get(f, []):
            P = _apply_form(spec, P, N, P0)
        z = noise * noise_rng.standard_normal(P0.shape[0]) if noise else np.zeros(len(P0))
        P = P + z[:, None] * N
        out["P"].append(P)
        out["N"].append(N)
        out["F"].append(np.full(P0.shape[0], f, dtype=np.int64))
        out["UV"].append(uv_by[f])
        out["P0"].append(P0)
        out["Z"].append(z)
    cat = {k: np.concatenate(v) if v else None for k, v in out.items()}
    P, N, P0 = cat["P"].reshape(-1, 3), cat["N"].reshape(-1, 3), cat["P0"].reshape(-1, 3)
    planted = np.einsum("ij,ij->i", P - P0, N)
    measured = P @ T[:3, :3].T + T[:3, 3]
    settings = {"noise": noise, "seed": int(seed), "margin": margin, "orient": orient,
                "selected_faces": list(sel),
                "form_errors": {int(f): [_spec_json(s) for s in v] for f, v in forms.items()}}
    return SampledPoints(points=measured, normals=N, face=cat["F"], uv=cat["UV"].reshape(-1, 2),
                         nominal=P0, planted=planted, noise=cat["Z"], per_face=per_face,
                         counts=counts, short=short, orientation=orientation, transform=T,
                         settings=settings)


def _spec_json(spec):
    return {k: (v.tolist() if isinstance(v, np.ndarray) else v) for k, v in spec.items()}
