"""Inspection job: every tolerance of a NIST AP242 part (CTC-01, public domain) checked
on a virtual measurement with one planted error, the characteristic table printed and
written with an HTML report.

Run: python examples/inspect_job.py [OUTPUT_FOLDER]  (default: a new temporary folder)
"""
import sys
import tempfile
from pathlib import Path

import geomkit
from geomkit.jobs.sample import sample_faces
from geomkit.report.files import prepare_outputs, write_json
from geomkit.report.inspect import inspect_html

OUT = sys.argv[1] if len(sys.argv) > 1 else tempfile.mkdtemp(prefix="geomkit-inspect-")
PART = Path(__file__).resolve().parent.parent / "tests" / "data" / "parts" / \
    "nist_ctc_01_ap242.stp"

part = geomkit.read_step(PART)
pmi = geomkit.read_pmi(PART)
print(f"{PART.name}: {len(part.surfaces)} faces, {len(pmi.tolerances)} tolerances, "
      f"datums {', '.join(d.label for d in pmi.datums)}")

# the virtual CMM: 25 points on each face the tolerances and datums name, 2 um noise,
# the slot of tolerance #21 (faces 37 and 41) made 0.5 mm off its true position
faces = sorted({f for t in pmi.tolerances for f in t.faces}
               | {f for d in pmi.datums for f in d.faces})
shift = {"kind": "offset", "translate": (0.5, 0.0, 0.0)}
pts = sample_faces(part, 25, faces=faces, noise=0.002, seed=7,
                   form_errors={37: [shift], 41: [shift]})

res = geomkit.inspect_part(part, pmi, pts.points, pts.face)
for c in res.characteristics:
    print(f"{c.id:>5} {c.type:18s} {'|'.join(c.datums):6s} measured "
          f"{c.measured:.4f} / limit {c.limit:.4f} {part.units}: {c.status}")
print(f"verdict: {res.verdict}")

out = prepare_outputs(OUT, ["summary.json", "inspection_report.html"], overwrite=True)
write_json(res.to_dict(), out["summary.json"], overwrite=True, units=part.units)
inspect_html(res, part.surfaces, out["inspection_report.html"], overwrite=True,
             part=str(PART))
print(f"reports in {OUT}/")
