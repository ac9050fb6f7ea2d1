"""Module paths that moved into subpackages: still importable, with a warning.

``geomkit.deviation``, ``geomkit.scene``, ``geomkit.motion``, ``geomkit.iges``,
``geomkit.demo`` and the other flat modules of earlier releases are registered in
``sys.modules`` as lazy stand-ins: the first attribute read imports the module's new
home, warns once (:class:`DeprecationWarning`, naming the new path) and forwards.
Nothing is imported until a stand-in is used, and pickles that name an old path
(``geomkit._collision_types.Body``) still load.
"""

from __future__ import annotations

import importlib
import sys
import types
import warnings

MOVED = {
    "geomkit.types": ("geomkit.nurbs.surface", "geomkit.mesh.mesh"),
    "geomkit.evaluation": ("geomkit.nurbs.evaluation",),
    "geomkit.trimming": ("geomkit.nurbs.trimming",),
    "geomkit.bezier": ("geomkit.nurbs.bezier",),
    "geomkit.tessellate": ("geomkit.mesh.tessellate",),
    "geomkit.projection": ("geomkit.query.projection",),
    "geomkit.voxel": ("geomkit.query.voxel",),
    "geomkit.distance": ("geomkit.query.distance",),
    "geomkit.results": ("geomkit.query.results",),
    "geomkit.collision": (),   # the package of that name (collide, Body, ...) stays
    "geomkit._collision_types": ("geomkit.collision.body",),
    "geomkit.motion": ("geomkit.collision.motion",),
    "geomkit.scene": ("geomkit.collision.scene",),
    "geomkit.iges": ("geomkit.cad.iges.reader",),
    "geomkit.step": ("geomkit.cad.step",),
    "geomkit.io": ("geomkit.exchange.cases",),
    "geomkit.points_io": ("geomkit.exchange.points",),
    "geomkit.scan_io": ("geomkit.exchange.scans",),
    "geomkit.deviation": ("geomkit.jobs.deviation",),
    "geomkit.dev_stats": ("geomkit.jobs.stats",),
    "geomkit.stream": ("geomkit.jobs.stream",),
    "geomkit.distributed": ("geomkit.jobs.distributed",),
    "geomkit.batch": ("geomkit.jobs.batch",),
    "geomkit.clearance": ("geomkit.jobs.clearance",),
    "geomkit.report_html": ("geomkit.report.html",),
    "geomkit.report_pdf": ("geomkit.report.pdf",),
    "geomkit.demo": ("geomkit.jobs.demo",),
    "geomkit.oracles": ("geomkit.bench.oracles",),
    "geomkit.oracles.occ": ("geomkit.bench.oracles.occ",),
}
"""Old module path -> the new modules whose names it offers, in lookup order."""
MOVED = {k: v for k, v in MOVED.items() if v}


class _Moved(types.ModuleType):
    """A stand-in for a module path that moved (see the module docstring)."""

    def __init__(self, name, targets):
        super().__init__(name, f"Moved to {', '.join(targets)}.")
        self.__dict__["_targets"] = targets
        self.__dict__["_warned"] = False
        self.__path__ = []      # a package-like stand-in: 'geomkit.oracles.occ' resolves

    def __getattr__(self, attr):
        if attr.startswith("__") and attr.endswith("__"):
            raise AttributeError(attr)
        targets = self.__dict__["_targets"]
        for t in targets:
            mod = importlib.import_module(t)
            if hasattr(mod, attr):
                if not self.__dict__["_warned"]:
                    self.__dict__["_warned"] = True
                    warnings.warn(f"{self.__name__} moved to {t}; import it from there (the "
                                  "old path goes in a later release)", DeprecationWarning,
                                  stacklevel=2)
                return getattr(mod, attr)
        raise AttributeError(f"module {self.__name__!r} (moved to {targets[0]}) has no "
                             f"attribute {attr!r}")


def install():
    """Register the stand-ins (only for paths no real module holds)."""
    for old, targets in MOVED.items():
        if old not in sys.modules:
            sys.modules[old] = _Moved(old, targets)
