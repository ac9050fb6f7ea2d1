"""The Mesh type: triangles of one or more surfaces with their measured deviation."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from geomkit.errors import InvalidInputError
from geomkit.outputs import atomic_write, check_target

__all__ = ["Mesh", "export_mesh", "MESH_FORMATS"]

MESH_FORMATS = (".stl", ".ply", ".obj")


@dataclass(eq=False)
class Mesh:
    """A triangle mesh of one or more surfaces, with its measured deviation.

    Attributes
    ----------
    vertices : (n, 3) float
    faces : (m, 3) int64, counter-clockwise seen from the surface normal side.
    uv : (n, 2) float, parameters of each vertex on its surface (at a degenerate point
        such as a pole, where many parameters map to one vertex, one of them).
    vertex_surface : (n,) int32, surface index of each vertex.
    face_surface : (m,) int32, surface index of each face.
    face_deviation : (m,) float, measured parametric deviation of each face from its
        surface (see :func:`geomkit.tessellate`).
    max_deviation : float, the largest entry of ``face_deviation`` (0 for no faces).
    tol : float, the tolerance the mesh was built for.
    stats : dict, counts and timings of the build.
    face_uv : (m, 3, 2) float, the parameters of each face corner on its surface
        (exact for that face, also where a vertex is shared by several parameters).
    """

    vertices: np.ndarray
    faces: np.ndarray
    uv: np.ndarray
    vertex_surface: np.ndarray
    face_surface: np.ndarray
    face_deviation: np.ndarray
    tol: float = float("nan")
    stats: dict = None
    face_uv: np.ndarray = None

    @property
    def max_deviation(self) -> float:
        return float(self.face_deviation.max()) if self.face_deviation.size else 0.0

    @property
    def area(self) -> float:
        """Total area of the triangles."""
        V = self.vertices[self.faces]
        return float(0.5 * np.linalg.norm(np.cross(V[:, 1] - V[:, 0], V[:, 2] - V[:, 0]),
                                          axis=1).sum())

    def __repr__(self) -> str:
        return (f"<Mesh {self.vertices.shape[0]} vertices, {self.faces.shape[0]} faces, "
                f"max deviation {self.max_deviation:.3g} (tol {self.tol:.3g})>")

    def to_trimesh(self):
        """A ``trimesh.Trimesh`` (vertices shared along surface seams and poles)."""
        import trimesh

        return trimesh.Trimesh(self.vertices.copy(), self.faces.copy(), process=False)

    def export(self, path, overwrite: bool = False):
        """Write STL / PLY / OBJ (by extension) through trimesh; never overwrites
        an existing file unless ``overwrite=True``."""
        return export_mesh(self, path, overwrite)


def export_mesh(mesh: Mesh, path, overwrite: bool = False) -> Path:
    """Write a :class:`Mesh` as STL (binary), PLY (binary) or OBJ, by extension.

    Written atomically; an existing file is kept unless ``overwrite=True``.
    """
    p = Path(path)
    ext = p.suffix.lower()
    if ext not in MESH_FORMATS:
        raise InvalidInputError(f"unknown mesh format {p.suffix!r}; use one of "
                                f"{', '.join(MESH_FORMATS)}", "path")
    check_target(p, overwrite)
    data = mesh.to_trimesh().export(file_type=ext[1:])
    if isinstance(data, str):
        data = data.encode("utf-8")
    return atomic_write(p, lambda fh: fh.write(data))
