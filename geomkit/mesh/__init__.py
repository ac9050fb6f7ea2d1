"""Meshes of surfaces: the Mesh type, tessellation to a tolerance, trim polylines."""
