"""Voxel grid of a triangle mesh and exact nearest-triangle searches (Paper 1).

Paper 1 bins the triangles of a tessellation into small cubes (steps 2–3) and finds,
for each triangle of one mesh, the nearest triangle of the other by growing a box one
voxel layer at a time until it holds a triangle (step 4).  That first hit is not
always the nearest: a box shell is not a sphere (a triangle in a shell corner can be
up to sqrt(3) times farther than one found in a later shell along an axis), and a
large triangle reaches nearer than its voxels' shell index suggests.
:class:`VoxelGrid` keeps the binning and fixes the stop rule:

* ``method="shells"`` is Paper 1's expanding box shells, run until the shells'
  guaranteed lower bound (the gap between the query's box and the outside of the
  scanned block) exceeds the best distance found; ``stop="first_hit"`` reproduces
  the paper's rule for comparison;
* ``method="best_first"`` (default) expands over a pyramid of occupancy (cells of
  2, 4, 8, ... voxels) in order of their distance lower bound: the same guarantee,
  and queries far from the mesh cost O(log) cells instead of O((d/h)^3) voxels.

Voxel size rule (``voxel_size=None``): the median triangle edge length, enlarged if
needed so that the grid has at most :data:`MAX_VOXELS` voxels.  Voxels of about one
edge length hold a few triangles each, so a query tests few triangles.
"""

from __future__ import annotations

import math

import numpy as np

from geomkit._kernels import voxel as _vk
from geomkit.validate import as_mesh_arrays, as_points
from geomkit.errors import InvalidInputError
from geomkit.query.results import MeshNearest

__all__ = ["VoxelGrid", "nearest_triangles", "CROSSED", "ENCLOSED", "MAX_VOXELS",
           "sliver_voxel_size"]

CROSSED = _vk.CROSSED
ENCLOSED = _vk.ENCLOSED
MAX_VOXELS = 1 << 22
SLIVER_RATIO = 0.3
""":func:`sliver_voxel_size` applies when the triangles' typical width is below this
fraction of the median edge."""


def sliver_voxel_size(mesh):
    """A voxel size for a mesh of long thin triangles, or None for a regular one.

    The default rule (the median edge) makes voxels as long as the long edges of a
    sliver mesh (a plate's fan triangles around a hole: 108 triangles, 50 long and 1
    wide, in 9 voxels of ~37 triangles each), so every query tests dozens of
    triangles.  ``sqrt(2 area)`` per triangle is about the edge for a well-shaped
    triangle and about the width times the length's square root for a sliver; when
    its median is below :data:`SLIVER_RATIO` times the median edge it is returned
    (at least the size that keeps the grid within :data:`MAX_VOXELS`): the exact
    triangle / voxel binning then puts each sliver only in the voxels it crosses.
    """
    V, F = _mesh_arrays(mesh)
    if F.shape[0] == 0:
        return None
    E = V[F]
    he = float(np.median(np.linalg.norm(E - np.roll(E, 1, axis=1), axis=2)))
    area = 0.5 * np.linalg.norm(np.cross(E[:, 1] - E[:, 0], E[:, 2] - E[:, 0]), axis=1)
    h = float(np.median(np.sqrt(2.0 * area)))
    if not (he > 0 and h > 0 and h < SLIVER_RATIO * he):
        return None
    ext = E.reshape(-1, 3).max(axis=0) - E.reshape(-1, 3).min(axis=0)
    vol = float(np.prod(np.maximum(ext, h)))
    if vol / h ** 3 > MAX_VOXELS:
        h = (vol / MAX_VOXELS) ** (1.0 / 3.0) * 1.0001
    return h if h < he else None


def _mesh_arrays(mesh, field="mesh"):
    V, F, _ = as_mesh_arrays(mesh, field)
    return V, F


class VoxelGrid:
    """Triangles of a mesh binned into cubic voxels (Paper 1, steps 2–3).

    Parameters
    ----------
    mesh : Mesh, trimesh.Trimesh or (vertices (n, 3), faces (m, 3))
    voxel_size : float, optional
        Edge of a voxel (model units).  Default: the median triangle edge, enlarged so
        the grid has at most :data:`MAX_VOXELS` voxels.

    Attributes
    ----------
    vertices, faces : the mesh arrays (copies, C-contiguous).
    origin : (3,) float, corner of voxel (0, 0, 0).
    voxel_size : float
    shape : (3,) int, voxels per axis.
    start : (nvox + 1,) int64 and ``triangles`` (entries,) int32: the triangles of
        voxel ``i`` are ``triangles[start[i]:start[i+1]]``; ``flags`` (entries,) int8
        says whether the triangle crosses the voxel (:data:`CROSSED`) or lies inside it
        (:data:`ENCLOSED`).

    Binning is exact: a triangle is listed in every voxel it touches (the 13-axis
    separating-axis test on boxes inflated by 1e-12 relative), so a voxel's box lower-
    bounds the distance to every triangle that is not listed in it.
    """

    def __init__(self, mesh, voxel_size: float | None = None):
        V, F = _mesh_arrays(mesh)
        self.vertices = V
        self.faces = F
        lo = V[F].reshape(-1, 3).min(axis=0)
        hi = V[F].reshape(-1, 3).max(axis=0)
        ext = hi - lo
        if voxel_size is None:
            E = V[F]
            edges = np.linalg.norm(E - np.roll(E, 1, axis=1), axis=2).ravel()
            h = float(np.median(edges))
            if not h > 0:
                h = float(ext.max()) or 1.0
            # enough voxels, but not more than MAX_VOXELS over the box
            vol = np.prod(np.maximum(ext, h))
            if vol / h ** 3 > MAX_VOXELS:
                h = float((vol / MAX_VOXELS) ** (1.0 / 3.0)) * 1.0001
            h = max(h, float(ext.max()) / (_vk.MAX_AXIS / 2))
        else:
            h = float(voxel_size)
            if not (math.isfinite(h) and h > 0):
                raise InvalidInputError(f"must be a finite number > 0, got {voxel_size!r}",
                                        "voxel_size")
        dims = np.maximum(1, np.ceil(ext / h).astype(np.int64) + 1)
        if int(np.prod(dims)) > 4 * MAX_VOXELS or dims.max() >= _vk.MAX_AXIS:
            raise InvalidInputError(
                f"{int(np.prod(dims))} voxels; choose a voxel_size >= "
                f"{(np.prod(ext + h) / MAX_VOXELS) ** (1 / 3):.3g}", "voxel_size")
        # centre the mesh box in the grid
        origin = lo - 0.5 * (dims * h - ext)
        self.origin = np.ascontiguousarray(origin, dtype=np.float64)
        self.voxel_size = h
        self.shape = dims
        counts = np.empty(F.shape[0], dtype=np.int64)
        _vk.bin_counts(V, F, self.origin, h, dims, counts)
        offsets = np.zeros(F.shape[0] + 1, dtype=np.int64)
        np.cumsum(counts, out=offsets[1:])
        total = int(offsets[-1])
        cell = np.empty(total, dtype=np.int64)
        tri = np.empty(total, dtype=np.int32)
        flag = np.empty(total, dtype=np.int8)
        _vk.bin_fill(V, F, self.origin, h, dims, offsets[:-1].copy(), cell, tri, flag)
        order = np.argsort(cell, kind="stable")
        nvox = int(np.prod(dims))
        self.triangles = np.ascontiguousarray(tri[order])
        self.flags = np.ascontiguousarray(flag[order])
        self.start = np.zeros(nvox + 1, dtype=np.int64)
        np.cumsum(np.bincount(cell, minlength=nvox), out=self.start[1:])
        self._pyramid()

    def _pyramid(self):
        occ = (np.diff(self.start) > 0).reshape(tuple(self.shape))
        levels = [occ]
        while max(levels[-1].shape) > 2:
            a = levels[-1]
            pad = [(0, s % 2) for s in a.shape]
            a = np.pad(a, pad)
            a = a.reshape(a.shape[0] // 2, 2, a.shape[1] // 2, 2, a.shape[2] // 2, 2)
            levels.append(a.any(axis=(1, 3, 5)))
        self.lvl_dims = np.array([lv.shape for lv in levels], dtype=np.int64)
        sizes = [lv.size for lv in levels]
        self.lvl_off = np.zeros(len(levels), dtype=np.int64)
        self.lvl_off[1:] = np.cumsum(sizes)[:-1]
        self.occ = np.concatenate([lv.ravel() for lv in levels]).astype(np.uint8)

    # ------------------------------------------------------------------ info
    @property
    def n_voxels(self) -> int:
        return int(np.prod(self.shape))

    @property
    def n_occupied(self) -> int:
        return int(np.count_nonzero(np.diff(self.start)))

    def voxel_triangles(self, ijk) -> tuple[np.ndarray, np.ndarray]:
        """Triangles and flags of voxel ``(i, j, k)``."""
        i, j, k = (int(x) for x in ijk)
        nx, ny, nz = (int(x) for x in self.shape)
        if not (0 <= i < nx and 0 <= j < ny and 0 <= k < nz):
            raise InvalidInputError(f"voxel {ijk} outside the grid {tuple(self.shape)}",
                                    "ijk")
        lin = (i * ny + j) * nz + k
        a, b = self.start[lin], self.start[lin + 1]
        return self.triangles[a:b].copy(), self.flags[a:b].copy()

    def __repr__(self) -> str:
        return (f"<VoxelGrid {tuple(int(x) for x in self.shape)} voxels of "
                f"{self.voxel_size:.4g}, {self.n_occupied} occupied, "
                f"{self.triangles.size} entries for {self.faces.shape[0]} triangles>")

    def _args(self):
        return (self.origin, self.voxel_size, self.lvl_dims, self.lvl_off, self.occ,
                self.start, self.triangles)

    # ------------------------------------------------------------------ queries
    def nearest(self, points):
        """Exact nearest triangle of each point.

        Returns ``(distance (n,), triangle (n,), closest (n, 3))``.
        """
        P, lead = as_points(points, 3, "points")
        n = P.shape[0]
        d = np.empty(n)
        t = np.empty(n, dtype=np.int64)
        c = np.empty((n, 3))
        self.last_work = np.zeros((n, 2), dtype=np.int64)
        if n:
            _vk.nearest_points(P, self.vertices, self.faces, *self._args(), d, t, c,
                               self.last_work)
        return d.reshape(lead), t.reshape(lead), c.reshape(lead + (3,))

    def nearest_triangles(self, mesh, method: str = "best_first",
                          stop: str = "bound") -> MeshNearest:
        """For every triangle of ``mesh`` (A), the nearest triangle of this grid's mesh (B).

        Parameters
        ----------
        mesh : Mesh, trimesh.Trimesh or (vertices, faces) — mesh A.
        method : ``"best_first"`` (pyramid, default) or ``"shells"`` (Paper 1's box
            shells).
        stop : ``"bound"`` (exact: expand until the guaranteed lower bound exceeds the
            best distance) or ``"first_hit"`` (Paper 1's rule, shells only: stop at the
            first shell holding a triangle — not always the nearest).

        Returns
        -------
        MeshNearest
        """
        from geomkit._kernels import voxel_tri as _vt

        VA, FA = _mesh_arrays(mesh, "mesh")
        if method not in ("best_first", "shells"):
            raise InvalidInputError(f"expected 'best_first' or 'shells', got {method!r}",
                                    "method")
        if stop not in ("bound", "first_hit"):
            raise InvalidInputError(f"expected 'bound' or 'first_hit', got {stop!r}", "stop")
        if stop == "first_hit" and method != "shells":
            raise InvalidInputError("stop='first_hit' is Paper 1's shell rule; use "
                                    "method='shells'", "stop")
        m = FA.shape[0]
        d = np.empty(m)
        t = np.empty(m, dtype=np.int64)
        pa = np.empty((m, 3))
        pb = np.empty((m, 3))
        visits = np.zeros(m, dtype=np.int64)
        if method == "best_first":
            _vt.nearest_tris_best_first(VA, FA, self.vertices, self.faces, *self._args(),
                                        d, t, pa, pb, visits)
        else:
            _vt.nearest_tris_shells(VA, FA, self.vertices, self.faces, self.origin,
                                    self.voxel_size, self.shape, self.start,
                                    self.triangles, stop == "first_hit", d, t, pa, pb,
                                    visits)
        return MeshNearest(distance=d, triangle=t, point_a=pa, point_b=pb,
                           cells_visited=visits)


def nearest_triangles(mesh_a, mesh_b, voxel_size: float | None = None,
                      method: str = "best_first", stop: str = "bound") -> MeshNearest:
    """For each triangle of ``mesh_a``, the nearest triangle of ``mesh_b`` (Paper 1,
    steps 2–5, searching until no unopened cell can hold a nearer triangle).  See :meth:`VoxelGrid.nearest_triangles`."""
    return VoxelGrid(mesh_b, voxel_size).nearest_triangles(mesh_a, method, stop)
