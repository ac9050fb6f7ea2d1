"""Write docs/api.md: every public name of ``geomkit`` (its ``__all__``) with its
signature and the first paragraph of its docstring.  Run after changing the API:

    python docs/gen_api.py

tests/package/test_docs.py checks that docs/api.md is what this script writes."""

from __future__ import annotations

import inspect
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

import geomkit  # noqa: E402

GROUPS = [
    ("Surfaces and files", ["Surface", "TrimCurve", "TrimLoop", "BezierPatches", "Case",
                            "load", "load_case", "save", "samples", "read_iges",
                            "IgesResult", "read_step", "read_points", "PointSet"]),
    ("Evaluation and trims", ["evaluate", "derivatives", "normals", "classify_uv",
                              "bezier_patches", "INSIDE", "OUTSIDE", "ON_BOUNDARY"]),
    ("Tessellation", ["tessellate", "Mesh"]),
    ("Distances", ["project_points", "Projector", "PartProjector", "Projection", "VoxelGrid",
                   "nearest_triangles", "MeshNearest", "surface_distance",
                   "SurfaceDistance"]),
    ("Sections", ["plane_section", "Section"]),
    ("CMM deviation", ["deviation", "DeviationReport", "align_rigid", "report"]),
    ("Probe safety", ["probe_clearance", "Stylus", "Clearance"]),
    ("Feature fits and GD&T", ["fit", "FitResult", "gdt", "datum_frame", "DatumFrame",
                               "Characteristic", "read_pmi", "Pmi", "sample_faces",
                               "SampledPoints", "inspect_part", "Inspection"]),
    ("Collision", ["Body", "Contact", "Contacts", "Distance", "collide", "collide_many",
                   "min_distance"]),
    ("Motion and scenes", ["first_contact", "probe_path", "FirstContact", "ProbePath",
                           "Scene", "SceneCollisions", "SceneDistances", "SweepAndPrune",
                           "CoherentPair", "fit_exclusions"]),
    ("Errors and tolerances", ["errors", "tolerances", "GeomkitError", "InvalidInputError",
                               "InvalidSurfaceError", "InvalidTrimError",
                               "DegenerateGeometryError", "FileFormatError",
                               "MissingDependencyError"]),
]


def _first_paragraph(obj) -> str:
    doc = inspect.getdoc(obj) or ""
    para = doc.split("\n\n")[0].strip()
    return " ".join(para.split())


def _entry(name) -> str:
    obj = getattr(geomkit, name)
    if inspect.ismodule(obj):
        return f"### `geomkit.{name}` (module)\n\n{_first_paragraph(obj)}\n"
    if inspect.isclass(obj) or callable(obj):
        try:
            sig = str(inspect.signature(obj))
        except (TypeError, ValueError):
            sig = "(...)"
        kind = "class" if inspect.isclass(obj) else "function"
        return f"### `geomkit.{name}{sig}` ({kind})\n\n{_first_paragraph(obj)}\n"
    return f"### `geomkit.{name}` = `{obj!r}`\n"


def render() -> str:
    listed = [n for _, names in GROUPS for n in names]
    missing = sorted(set(geomkit.__all__) - set(listed))
    groups = GROUPS + ([("Other", missing)] if missing else [])
    out = ["# API reference", "",
           "Generated from the docstrings by `python docs/gen_api.py`: every public name of "
           "`geomkit`, its signature and the first paragraph of its docstring (`help(...)` "
           "gives the whole text: parameters, returns, errors, method).  Guides: "
           "[deviation](guide_deviation.md), [section](guide_section.md), "
           "[clearance](guide_clearance.md); command line: [cli.md](cli.md).", ""]
    for title, names in groups:
        out += [f"## {title}", ""]
        for n in names:
            if n in geomkit.__all__:
                out.append(_entry(n))
    return "\n".join(out)


if __name__ == "__main__":
    (ROOT / "docs" / "api.md").write_text(render(), encoding="utf-8")
    print("wrote docs/api.md")
