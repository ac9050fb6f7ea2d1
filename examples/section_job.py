"""Section export job: five parallel sections of the torus as CSV / DXF / JSON / PNG.

Run: python examples/section_job.py [OUTPUT_FOLDER]  (default: a new temporary folder)
"""
import sys
import tempfile

import numpy as np

from geomkit import plane_section, samples
from geomkit.report.files import plot_section, prepare_outputs, write_section

OUT = sys.argv[1] if len(sys.argv) > 1 else tempfile.mkdtemp(prefix="geomkit-section-")

torus = samples.load("torus")[0]
names = [f"z{k}.{e}" for k in range(5) for e in ("csv", "dxf", "json")] + ["all.png"]
out = prepare_outputs(OUT, names, overwrite=True)
sections = []
for k in range(5):
    sec = plane_section(torus, np.array([0.0, 0.0, 1.0, -1.0 * k]), tol=1e-4)
    write_section(sec, {e: out[f"z{k}.{e}"] for e in ("csv", "dxf", "json")}, overwrite=True)
    sections.append(sec)
    print(f"z = {k}: {len(sec.curves)} curves, residual {sec.max_residual:.1e}")
plot_section(sections, out["all.png"], overwrite=True)
print(f"reports in {OUT}/")
