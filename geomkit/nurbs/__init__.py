"""Exact NURBS surfaces: the Surface type, evaluation, trims, Bezier extraction."""
