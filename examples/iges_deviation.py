"""Deviation against a real IGES model (pyiges's impeller): read, report skipped faces,
measure points placed 0.01 off three faces.

Run: python examples/iges_deviation.py
"""
import numpy as np
from pyiges import examples

import geomkit
from geomkit.jobs.deviation import deviation
from geomkit.cad.iges.reader import read_iges

res = read_iges(examples.impeller)
print(f"{len(res.surfaces)} faces read, {len(res.skipped)} skipped "
      f"({res.gaps_closed} trim gaps bridged, largest {res.max_gap:.2g} in UV)")
pts = []
for s in (res.surfaces[0], res.surfaces[100], res.surfaces[200]):
    (a, b), (c, d) = s.domain
    uv = np.array([[a + (b - a) * x, c + (d - c) * y] for x in np.linspace(0.3, 0.7, 4)
                   for y in np.linspace(0.3, 0.7, 4)])
    uv = uv[s.classify_uv(uv) == geomkit.INSIDE]
    pts.append(s.evaluate(uv) + 0.01 * s.normals(uv))
rep = deviation(res.surfaces, np.concatenate(pts), tolerance=(-0.005, 0.005))
print(rep)
