"""Result types of the distance queries: plain dataclasses of arrays, no algorithms."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

__all__ = ["MeshNearest", "Projection", "INTERIOR", "DOMAIN_EDGE", "TRIM_EDGE",
           "BEYOND", "FAILED", "STATUS_NAMES",
           "SurfaceDistance"]

INTERIOR = 0
"""The foot lies inside the face: an orthogonal foot (S - x parallel to the normal)."""
DOMAIN_EDGE = 1
"""The foot lies on the boundary of the parameter domain (edge or corner of the patch)."""
TRIM_EDGE = 2
"""The foot lies on a trim curve (the nearest point of the trimmed face is on its edge)."""
BEYOND = 3
"""Every surface point is farther than ``max_distance``: no foot computed (NaN)."""
FAILED = 4
"""The iteration did not converge: values are NaN (never observed in the test suite)."""

STATUS_NAMES = {INTERIOR: "interior", DOMAIN_EDGE: "domain_edge", TRIM_EDGE: "trim_edge",
                BEYOND: "beyond", FAILED: "failed"}


@dataclass
class MeshNearest:
    """Nearest triangle of mesh B for each triangle of mesh A (Paper 1, step 5).

    Attributes
    ----------
    distance : (m,) float, exact triangle–triangle distance to the nearest triangle.
    triangle : (m,) int64, index of that triangle in B.
    point_a, point_b : (m, 3) float, the closest points on the triangle of A and on B.
    cells_visited : (m,) int64, voxels (shells) or pyramid cells (best first) examined.
    """

    distance: np.ndarray
    triangle: np.ndarray
    point_a: np.ndarray
    point_b: np.ndarray
    cells_visited: np.ndarray

    @property
    def min_distance(self) -> float:
        """The smallest distance between the two meshes."""
        return float(self.distance.min())

    @property
    def argmin(self) -> int:
        """The triangle of A that realises :attr:`min_distance`."""
        return int(np.argmin(self.distance))


@dataclass
class Projection:
    """Feet of points on surfaces (:func:`geomkit.project_points`).

    Attributes
    ----------
    point : (n, 3) float, the nearest surface point (foot).
    uv : (n, 2) float, its parameters on surface ``surface``.
    surface : (n,) int32, index of the surface holding the foot (-1 if none).
    distance : (n,) float, |x - foot|.
    signed_distance : (n,) float, ``distance`` with the sign of (x - foot) . normal.
    normal : (n, 3) float, unit surface normal at the foot (``S_u x S_v`` orientation;
        the limit normal at a pole).
    status : (n,) int8, :data:`INTERIOR`, :data:`DOMAIN_EDGE`, :data:`TRIM_EDGE`,
        :data:`BEYOND` or :data:`FAILED`; rows with BEYOND / FAILED hold NaN.
    lower_bound : (n,) float, a lower bound of the exact distance from the mesh search
        (triangle distance minus the triangle's measured deviation): the exact
        distance lies in ``[lower_bound, distance]``.
    residual : (n,) float, first-order optimality residual of the foot: for INTERIOR
        feet the sine of the angle between x - foot and the normal times the distance
        (0 at an exact orthogonal foot); 0 on edges.
    feet_tried : (n,) int8, Newton runs started for the point (several for points with
        many feet, e.g. the sphere centre).
    stats : dict, sizes and timings.
    """

    point: np.ndarray
    uv: np.ndarray
    surface: np.ndarray
    distance: np.ndarray
    signed_distance: np.ndarray
    normal: np.ndarray
    status: np.ndarray
    lower_bound: np.ndarray
    residual: np.ndarray
    feet_tried: np.ndarray
    stats: dict = field(default_factory=dict)

    def __len__(self) -> int:
        return int(self.distance.shape[0])

    def counts(self) -> dict:
        """Number of points per status name."""
        return {name: int(np.count_nonzero(self.status == k))
                for k, name in STATUS_NAMES.items()}

    def __repr__(self) -> str:
        c = ", ".join(f"{k} {v}" for k, v in self.counts().items() if v)
        return f"<Projection of {len(self)} points: {c}>"


@dataclass
class SurfaceDistance:
    """Minimum distance between two surfaces or two scenes of surfaces
    (:func:`geomkit.surface_distance`), with a certified interval.

    Attributes
    ----------
    distance : float, the distance between ``point_a`` and ``point_b`` (= ``upper``).
    lower, upper : float, certified bounds: ``lower <= exact <= upper``.  ``upper`` is
        the distance of a real pair of face points; ``lower`` comes from the convex
        hulls of Bézier control nets (up to floating-point rounding, see the docs).
    point_a, point_b : (3,) float, a pair of face points realising ``upper``.
    uv_a, uv_b : (2,) float, their parameters.
    surface_a, surface_b : int, index of the surface of each scene holding the points.
    certified : bool, ``upper - lower <= tol`` was reached (False only when the work
        cap stopped the search, e.g. a curved continuum of minima).
    tol : float, the requested interval width.
    regions_refined : int, sub-patch pairs subdivided (the lazily refined regions).
    stats : dict, counts (pairs examined / pushed / pruned, nodes, Newton runs, peak
        heap), memory in bytes and the wall time.
    """

    distance: float
    lower: float
    upper: float
    point_a: np.ndarray
    point_b: np.ndarray
    uv_a: np.ndarray
    uv_b: np.ndarray
    surface_a: int
    surface_b: int
    certified: bool
    tol: float
    regions_refined: int
    stats: dict = field(default_factory=dict)

    @property
    def interval(self) -> tuple[float, float]:
        """``(lower, upper)``."""
        return (self.lower, self.upper)

    @property
    def width(self) -> float:
        """``upper - lower``."""
        return self.upper - self.lower

    def __repr__(self) -> str:
        c = "certified" if self.certified else "NOT certified"
        return (f"<SurfaceDistance {self.distance:.12g} in [{self.lower:.12g}, "
                f"{self.upper:.12g}] ({c}, tol {self.tol:.3g}), surfaces "
                f"{self.surface_a}/{self.surface_b}, {self.regions_refined} regions refined>")
