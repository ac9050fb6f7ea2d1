"""HTML / PDF reports of a job in one call, for the command line and the demo.

>>> report_files("deviation", ["html", "pdf"])
['deviation_report.html', 'deviation_report.pdf']
"""

from __future__ import annotations

from geomkit.errors import InvalidInputError

__all__ = ["REPORT_KINDS", "report_files", "write_reports", "parse_kinds"]

REPORT_KINDS = ("html", "pdf")
_STEM = {"deviation": "deviation_report", "section": "section_report",
         "clearance": "clearance_report"}


def parse_kinds(values) -> list[str]:
    """``["html,pdf", "html"]`` -> ``["html", "pdf"]`` (order kept, duplicates
    dropped); None -> []."""
    out = []
    for v in values or ():
        for k in str(v).split(","):
            k = k.strip().lower()
            if not k:
                continue
            if k not in REPORT_KINDS:
                raise InvalidInputError(f"unknown report kind {k!r}; use html, pdf or "
                                        "html,pdf", "--report")
            if k not in out:
                out.append(k)
    return out


def report_files(job: str, kinds) -> list[str]:
    """File names of the reports of ``job`` ("deviation", "section", "clearance")."""
    if job not in _STEM:
        raise InvalidInputError(f"no reports for job {job!r}", "job")
    return [f"{_STEM[job]}.{k}" for k in parse_kinds(kinds)]


def write_reports(job: str, kinds, targets: dict, overwrite: bool = False, **data) -> list:
    """Write the ``kinds`` reports of ``job`` to ``targets[name]`` (names from
    :func:`report_files`); ``data`` are the keyword arguments of the writers:

    - deviation: ``rep, surfaces`` (+ ``units, model_note, part, extra``);
    - section: ``sections`` (+ ``scan, surfaces, probe_radius, tolerance``);
    - clearance: ``res, surfaces, path_points`` (+ ``stylus, axis, probing``).

    Returns the written paths."""
    from geomkit.report import html as H, pdf as P

    out = []
    for name in report_files(job, kinds):
        kind = name.rsplit(".", 1)[1]
        t = targets[name]
        d = dict(data)
        common = {k: d.pop(k) for k in ("units", "model_note", "part", "extra") if k in d}
        if job == "deviation":
            w = H.deviation_html if kind == "html" else P.deviation_pdf
            out.append(w(d["rep"], d["surfaces"], t, overwrite, **common))
        elif job == "section":
            if kind == "html":
                out.append(H.section_html(d["sections"], t, overwrite, scan=d.get("scan"),
                                          surfaces=d.get("surfaces"),
                                          probe_radius=d.get("probe_radius", 0.0),
                                          tolerance=d.get("tolerance"), **common))
            else:
                out.append(P.section_pdf(d["sections"], t, overwrite, **common))
        else:
            if kind == "html":
                out.append(H.clearance_html(d["res"], d["surfaces"], d["path_points"], t,
                                            overwrite, stylus=d.get("stylus"),
                                            axis=d.get("axis"), probing=d.get("probing", ()),
                                            **common))
            else:
                out.append(P.clearance_pdf(d["res"], t, overwrite, stylus=d.get("stylus"),
                                           probing=d.get("probing", ()), **common))
    return out
