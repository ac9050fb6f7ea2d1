"""Report writers for the jobs: deviation CSV, summary JSON, colour-map and histogram PNGs,
section exports, probe-clearance CSV and chart (:mod:`geomkit.report.files`); the HTML
and PDF reports are in :mod:`geomkit.report.html` and :mod:`geomkit.report.pdf`."""

from .files import *  # noqa: F401,F403
from .files import __all__  # noqa: F401
