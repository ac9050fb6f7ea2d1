"""Open CASCADE ``GeomAPI_IntSS`` surface/plane intersection, for the section benchmark.

Kept apart from :mod:`geomkit.bench.oracles.occ` (which holds ``BRepAlgoAPI_Section`` as
``occ.section``).  Importing never fails; calls need ``cadquery-ocp``.
"""

from __future__ import annotations

import time

import numpy as np

from geomkit.cad.occ import HAVE_OCP, require_ocp, xyz

__all__ = ["HAVE_OCP", "intss"]


def intss(geom_surface, plane_abcd, tol: float = 1e-7, deflection: float = 1e-3):
    """Intersect a ``Geom_Surface`` with the plane ``A x + B y + C z + D = 0``.

    Returns
    -------
    polylines : list of (k, 3) ndarray, each intersection line discretised with
        ``GCPnts_QuasiUniformDeflection(deflection)``; empty if none.
    seconds : float, wall time of ``GeomAPI_IntSS.Perform`` only.
    """
    require_ocp("intss")
    from OCP.GCPnts import GCPnts_QuasiUniformDeflection
    from OCP.Geom import Geom_Plane
    from OCP.GeomAdaptor import GeomAdaptor_Curve
    from OCP.GeomAPI import GeomAPI_IntSS
    from OCP.gp import gp_Pln

    abcd = np.asarray(plane_abcd, dtype=np.float64).ravel()
    pl = Geom_Plane(gp_Pln(*map(float, abcd)))
    t0 = time.perf_counter()
    inter = GeomAPI_IntSS(geom_surface, pl, float(tol))
    seconds = time.perf_counter() - t0
    out = []
    if not inter.IsDone():
        return out, seconds
    for i in range(1, inter.NbLines() + 1):
        ad = GeomAdaptor_Curve(inter.Line(i))
        disc = GCPnts_QuasiUniformDeflection(ad, float(deflection))
        if disc.IsDone() and disc.NbPoints() >= 2:
            out.append(np.array([xyz(disc.Value(k)) for k in range(1, disc.NbPoints() + 1)]))
    return out, seconds
