"""Shared helpers of the tessellation tests (tests/mesh/test_tessellate*.py): the bundled
cases' meshes built once per (case, tol) for the whole session, mesh topology
helpers (edges, manifold, Euler characteristic, boundary loops), and small surface
builders (planes with circle holes, regular random nets)."""

from __future__ import annotations

import numpy as np

from geomkit import Surface, samples
from geomkit.mesh.tessellate import tessellate

from helpers.trims import S2

NAMES = samples.names()
REL = 1 + 1e-9                       # rounding slack on "<= tol"
FAST_1E4 = ["crease", "cylinder_quarter", "offset_planes", "plate_with_hole", "saddle"]
"""Cases whose tol 1e-4 mesh builds in a few seconds (crease and saddle: ~2-4 s, 200k+
faces, sampled on 32k of them).  Measured while writing these tests, at 1e-4: sphere
~33 s, wave_seed003 ~44 s, torus ~60 s, freeform_1 ~150 s, heavy_weights > 8 min; those
are checked at 1e-2 and 1e-3 only, to keep this file within ~4 minutes."""

_CASES: dict = {}
_MESHES: dict = {}


def case_of(name):
    if name not in _CASES:
        _CASES[name] = samples.load_case(name)
    return _CASES[name]


def mesh_of(name, tol):
    """(case, mesh) for a bundled case, tessellated once per (name, tol)."""
    key = (name, tol)
    if key not in _MESHES:
        case = case_of(name)
        _MESHES[key] = tessellate(case.surfaces, tol)
    return case_of(name), _MESHES[key]


# ------------------------------------------------------------------ mesh helpers
def directed_edges(F):
    """(3m, 2) directed edges (a, b) of faces F (m, 3), face-major."""
    return np.stack([F, np.roll(F, -1, axis=1)], axis=-1).reshape(-1, 2)


def edge_report(F):
    """Undirected edges of faces F (m, 3) with their multiplicities, the undirected edge
    of each directed edge (face-major, ``3 * face + corner``), and the largest
    multiplicity of a directed edge."""
    d = directed_edges(F).astype(np.int64)
    n = int(F.max(initial=0)) + 1
    lo, hi = d.min(axis=1), d.max(axis=1)
    ukey, inv, cnt = np.unique(lo * n + hi, return_inverse=True, return_counts=True)
    _, dcnt = np.unique(d[:, 0] * n + d[:, 1], return_counts=True)
    return {"edges": np.stack([ukey // n, ukey % n], axis=1), "count": cnt,
            "edge_of": inv.ravel(), "max_count": int(cnt.max(initial=0)),
            "max_directed": int(dcnt.max(initial=0))}


def assert_manifold_oriented(F, what=""):
    """Every edge is used by one face (boundary) or two faces that traverse it in
    opposite directions (so the surface is a manifold, consistently oriented)."""
    assert len(F), f"{what}: no faces"
    assert np.all((F[:, 0] != F[:, 1]) & (F[:, 1] != F[:, 2]) & (F[:, 0] != F[:, 2])), \
        f"{what}: a face repeats a vertex"
    r = edge_report(F)
    bad = np.nonzero(r["count"] > 2)[0]
    assert not len(bad), (f"{what}: {len(bad)} edges shared by more than two faces, e.g. "
                          f"{r['edges'][bad[:3]].tolist()} x{r['count'][bad[:3]].tolist()}")
    assert r["max_directed"] == 1, (f"{what}: an edge is traversed twice in the same "
                                    "direction (inconsistent orientation)")
    return r


def euler_characteristic(F):
    r = edge_report(F)
    return len(np.unique(F)) - len(r["edges"]) + len(F)


def boundary_loops(F):
    """Number of closed boundary loops of faces F (boundary vertices must have degree 2)."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    r = edge_report(F)
    B = r["edges"][r["count"] == 1]
    if not len(B):
        return 0
    verts, local = np.unique(B, return_inverse=True)
    local = local.reshape(-1, 2)
    deg = np.bincount(local.ravel(), minlength=len(verts))
    assert np.all(deg == 2), f"boundary is not a set of simple loops (degrees {np.unique(deg)})"
    n = len(verts)
    g = coo_matrix((np.ones(len(local)), (local[:, 0], local[:, 1])), shape=(n, n))
    return int(connected_components(g, directed=False)[0])


def face_areas(V, F):
    T = V[F]
    return 0.5 * np.linalg.norm(np.cross(T[:, 1] - T[:, 0], T[:, 2] - T[:, 0]), axis=1)


def surface_faces(mesh, i):
    """Faces of surface i (global vertex indices)."""
    return mesh.faces[mesh.face_surface == i]


def id_of(name, tol):
    return f"{name}-{tol:g}"


def plane(a, b, trim, frame=None):
    """A bilinear plane a x b (3-D = diag(a, b) x UV), optionally rotated by ``frame``."""
    P = np.array([[[0, 0, 0], [0, b, 0]], [[a, 0, 0], [a, b, 0]]], float)
    if frame is not None:
        P = P @ frame.T
    return Surface(1, 1, [0, 0, 1, 1], [0, 0, 1, 1], P, trim=trim)


def circle_dict(c, r):
    """An exact rational quadratic circle in UV, counter-clockwise, 4 quarters."""
    unit = np.array([[1, 0], [1, 1], [0, 1], [-1, 1], [-1, 0], [-1, -1], [0, -1], [1, -1],
                     [1, 0]], float)
    return {"degree": 2, "knots": [0, 0, 0, .25, .25, .5, .5, .75, .75, 1, 1, 1],
            "control_points": (np.asarray(c) + r * unit).tolist(),
            "weights": [1, S2, 1, S2, 1, S2, 1, S2, 1]}


def rotation(a, b, c):
    ca, sa, cb, sb, cc, sc = np.cos(a), np.sin(a), np.cos(b), np.sin(b), np.cos(c), np.sin(c)
    Rz = np.array([[ca, -sa, 0], [sa, ca, 0], [0, 0, 1]])
    Ry = np.array([[cb, 0, sb], [0, 1, 0], [-sb, 0, cb]])
    Rx = np.array([[1, 0, 0], [0, cc, -sc], [0, sc, cc]])
    return Rz @ Ry @ Rx


def regular_surface(s, relief=0.5):
    """A regular surface built from a random one: its degrees, knots and weights, its
    control points' z (scaled by ``relief``) over a regular 100 x 100 grid, x and y
    jittered by 3% of the random control points (less than the grid spacing, so each
    row and column of the net stays ordered and the surface is, in practice, a graph
    over the plane: no folds, collapsed rows or self-touching boundary)."""
    nu, nv = s.shape
    gu, gv = np.meshgrid(np.linspace(0, 100, nu), np.linspace(0, 100, nv), indexing="ij")
    P = np.stack([gu, gv, np.zeros_like(gu)], axis=-1)
    R = s.control_points
    P[..., 0] += 0.03 * R[..., 0]
    P[..., 1] += 0.03 * R[..., 1]
    P[..., 2] = relief * R[..., 2]
    return P
