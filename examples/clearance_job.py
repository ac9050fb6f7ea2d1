"""Probe-safety job: a stylus path over the bundled torus, checked against a margin.

The path travels 10 above the torus' top, then plunges onto the tube.  Every move gets
a certified clearance (an interval on the exact NURBS), the closest stylus piece, where
it happens, and the first contact parameter of a colliding move.

Run: python examples/clearance_job.py [OUTPUT_FOLDER]  (default: a new temporary folder)
"""
import sys
import tempfile

import numpy as np

from geomkit import Stylus, probe_clearance, samples
from geomkit.report.files import plot_clearance, prepare_outputs, write_clearance_csv

OUT = sys.argv[1] if len(sys.argv) > 1 else tempfile.mkdtemp(prefix="geomkit-clearance-")

torus = samples.load("torus")                       # tube radius 5 around a circle of 20
stylus = Stylus(tip_radius=1.0, shaft_radius=0.5, shaft_length=20.0,
                extension_radius=2.0, extension_length=30.0)
path = np.array([[-30.0, 0, 15], [0, 30, 15], [20, 0, 15], [20, 0, 0]])  # last: plunge
res = probe_clearance(torus, stylus, path, axis=(0, 0, 1), margin=2.0)

for i in range(len(res)):
    lo, hi = res.lower_bound[i], res.clearance[i]
    what = ("PASS" if res.passed[i] else
            f"FAIL, first contact at s = {res.first_contact[i]:.9f}"
            if np.isfinite(res.first_contact[i]) else "FAIL (margin)")
    print(f"move {i} ({res.motion[i]}): clearance in [{lo:.9f}, {hi:.9f}] "
          f"({res.component_names[res.component[i]]} at s = {res.parameter[i]:.4f}) {what}")
# the plunge: the tip centre descends from z = 15 to 0 over the tube top at z = 5, so it
# touches when the centre is at z = 6: s = (15 - 6) / 15 = 0.6
out = prepare_outputs(OUT, ["clearance.csv", "clearance.png"], overwrite=True)
write_clearance_csv(res, path, out["clearance.csv"], overwrite=True)
plot_clearance(res, out["clearance.png"], overwrite=True)
print(f"reports in {OUT}/")
