"""CMM deviation job: a synthetic ball-centre scan of freeform_1 against its nominal.

Run: python examples/deviation_job.py [OUTPUT_FOLDER]  (default: a new temporary folder)
"""
import sys
import tempfile

from geomkit import samples
from geomkit.jobs.demo import synthetic_scan
from geomkit.jobs.deviation import deviation
from geomkit.report.files import (plot_deviation_map, plot_histogram, prepare_outputs,
                            write_deviation_csv, write_json)

OUT = sys.argv[1] if len(sys.argv) > 1 else tempfile.mkdtemp(prefix="geomkit-deviation-")

surface = samples.load("freeform_1")[0]
centres, normals, truth = synthetic_scan(surface, grid=30)          # probe radius 1
rep = deviation(surface, centres, normals, probe_radius=1.0, tolerance=(-0.02, 0.02))
out = prepare_outputs(OUT, ["deviation.csv", "map.png", "hist.png", "summary.json"],
                      overwrite=True)
write_deviation_csv(rep, out["deviation.csv"], overwrite=True)
plot_deviation_map(rep, surface, out["map.png"], overwrite=True)
plot_histogram(rep, out["hist.png"], overwrite=True)
write_json(rep.summary(), out["summary.json"], overwrite=True)
s = rep.stats
print(f"max {s['max']:.4f}  rms {s['rms']:.4f}  over tolerance {s['pct_over']:.1f}%")
print(f"reports in {OUT}/")
