"""Bézier extraction of NURBS surfaces (knot insertion, The NURBS Book A5.6).

The patches carry exact homogeneous control nets; with positive weights each patch
lies in the convex hull of its control points, which gives the conservative bounds
that later subdivision and distance certification use.
"""

from __future__ import annotations

from geomkit.nurbs.surface import BezierPatches, Surface, check_surface

__all__ = ["bezier_patches", "BezierPatches"]


def bezier_patches(surface: Surface) -> BezierPatches:
    """Split ``surface`` into rational Bézier patches, one per non-empty knot cell
    (kept on the surface); see :meth:`geomkit.Surface.bezier_patches`."""
    return check_surface(surface).bezier_patches()
