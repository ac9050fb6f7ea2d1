"""Benchmarks: speed against error, measured beside a reference in the same run.

Not part of the test suite.  Run e.g. ``python -m geomkit.bench.evaluation``.
"""
