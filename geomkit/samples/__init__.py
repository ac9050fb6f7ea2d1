"""Built-in sample surfaces: the canonical ``geomkit-case/1`` cases, shipped with the
package so the demo, the docs and the tests work with no files of the user's.

>>> import geomkit
>>> "sphere" in geomkit.samples.names()
True
>>> [s.shape for s in geomkit.samples.load("sphere")]
[(9, 5)]
"""

from __future__ import annotations

import json
from importlib import resources

from geomkit.errors import InvalidInputError
from geomkit.exchange.cases import Case, case_from_doc

__all__ = ["names", "load", "load_case", "path", "analytic_residual"]


def _files():
    return resources.files(__name__).joinpath("data")


def names() -> list[str]:
    """Sorted names of the bundled cases."""
    return sorted(p.name[:-5] for p in _files().iterdir() if p.name.endswith(".json"))


def path(name: str):
    """Filesystem path (a ``Traversable``) of a bundled case."""
    if name not in names():
        raise InvalidInputError(f"unknown sample {name!r}; available: {', '.join(names())}",
                                "name")
    return _files().joinpath(name + ".json")


def load_case(name: str) -> Case:
    """A bundled case with its analytic truth."""
    doc = json.loads(path(name).read_text(encoding="utf-8"))
    case = case_from_doc(doc, f"sample {name}")
    case.name = case.name or name
    return case


def load(name: str) -> list:
    """The surfaces of a bundled case."""
    return load_case(name).surfaces


def analytic_residual(analytic: dict, points):
    """Signed distance of ``points`` (n, 3) from a case's analytic truth surface.

    ``analytic`` is a case's ``truth["analytic"]`` block: ``sphere`` (center, radius),
    ``torus`` (R, r, about the z axis through the origin), ``cylinder`` (radius, axis
    through the origin), ``plane`` (z).  Returns (n,) float; 0 means on the surface.
    """
    import numpy as np

    P = np.asarray(points, dtype=float).reshape(-1, 3)
    kind = analytic.get("type")
    if kind == "sphere":
        c = np.asarray(analytic.get("center", [0, 0, 0]), float)
        return np.linalg.norm(P - c, axis=1) - float(analytic["radius"])
    if kind == "torus":
        rho = np.hypot(P[:, 0], P[:, 1])
        return np.hypot(rho - float(analytic["R"]), P[:, 2]) - float(analytic["r"])
    if kind == "cylinder":
        a = np.asarray(analytic.get("axis", [0, 0, 1]), float)
        a = a / np.linalg.norm(a)
        radial = P - np.outer(P @ a, a)
        return np.linalg.norm(radial, axis=1) - float(analytic["radius"])
    if kind == "plane":
        return P[:, 2] - float(analytic.get("z", 0.0))
    raise InvalidInputError(f"unknown analytic type {kind!r}", "truth.analytic.type")
