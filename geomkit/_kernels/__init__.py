"""numba kernels: functions of arrays and scalars only.

Kernels never import geomkit types or public modules; the public modules validate
inputs, call these, and wrap the results.
"""
